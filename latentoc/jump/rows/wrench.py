"""A sample between contact nodes: the contact wrench the motion needs, in the loaded points' cone.

No force variables: the sagittal base rows of RNEA, solved for the (fx, fz, my) of each
(symmetric) foot at its toe tip, must lie in the wrench cone of the foot's loaded points. In
the sagittal plane that holds exactly when fz >= 0, |fx| <= mu fz and the centre of pressure
``toe_x - my / fz`` lies between the rearmost loaded point and the toe tip; the rows are
homogeneous in fz (body weights, all >= 0): ``wrench_normal``, ``wrench_friction``,
``cop_front``, ``cop_heel`` / ``cop_ball`` / ``cop_pad`` (the rearmost loaded point: heel, ball
or the toe pad), and ``torque_free``: the torques of the joints no foot force enters.
"""
from __future__ import annotations

import casadi as ca

from ...nlp.blocks import RobotBlock
from ..contact import TOE_PAD
from ..robot import SAGITTAL_ROWS, JumpRobot, galilean
from ..training import RIGHT_TOE, TOE
from . import inputs

INPUTS = {"b": 3, "bd": 3, "bdd": 3}


def block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, INPUTS)
    q, v, a = robot.configuration(*galilean(u["b"], u["bd"]), u["bdd"], y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    J = robot.sym.frame_jacobian(TOE)(q) + robot.sym.frame_jacobian(RIGHT_TOE)(q)
    fx, fz, my = ca.vertsplit(ca.solve(J.T[SAGITTAL_ROWS, SAGITTAL_ROWS], tau[SAGITTAL_ROWS]) / robot.weight)
    P = robot.points(q, u["b"][:2])
    toe_x = P[0, 2]
    mu = robot.mu
    parts = {
        "wrench_normal": fz,
        "wrench_friction": ca.vertcat(mu * fz - fx, mu * fz + fx),
        "cop_front": my,
        "cop_heel": (toe_x - P[0, 0]) * fz - my,
        "cop_ball": (toe_x - P[0, 1]) * fz - my,
        "cop_pad": TOE_PAD * fz - my,
        "torque_free": robot.torque_rows(tau[6:])[robot.force_free.tolist()],
    }
    return RobotBlock.from_parts("jump_wrench", (y, yd, ydd, r), parts, d)
