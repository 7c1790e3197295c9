"""A flight node and the flight's pitch rate (:mod:`latentoc.jump.flight`).

Flight node inputs r: the pitch p, the angular momentum L, the takeoff COM state (c_to, cd_to)
and the time since takeoff. The motion is computed about the COM (at the origin, at rest,
accelerating at g; Galilean invariance), and the COM's parabola moves the foot points. Rows:
the joint torques of the ballistic motion and the heel, ball and toe heights.
"""
from __future__ import annotations

import casadi as ca

from ...nlp.blocks import RobotBlock
from ..flight import GRAVITY, flight_functions
from ..robot import JumpRobot
from . import inputs

INPUTS = {"p": 1, "L": 1, "c_to": 2, "cd_to": 2, "t": 1}
PITCH_RATE_INPUTS = {"L": 1}


def ballistic_com(c_to, cd_to, t):
    """COM position and velocity (x, z) at flight time t from the takeoff state."""
    g = ca.DM(GRAVITY)
    return c_to + cd_to * t + 0.5 * g * t ** 2, cd_to + g * t


def flight_base(robot: JumpRobot, y, yd, ydd, p, L, c, cd):
    """Base (b, bd, bdd) of the flight for pitch p, momentum L and the COM at c moving at cd."""
    fns = flight_functions(robot.sym, robot.smap)
    pd, pdd = fns["pitch_rate"](y, yd, ydd, L)
    return fns["base"](y, yd, ydd, p, pd, pdd, c, cd, ca.DM(GRAVITY))


def block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, INPUTS)
    b, bd, bdd = flight_base(robot, y, yd, ydd, u["p"], u["L"], ca.DM.zeros(2), ca.DM.zeros(2))
    q, v, a = robot.configuration(b, bd, bdd, y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    P = robot.points(q, ballistic_com(u["c_to"], u["cd_to"], u["t"])[0])
    return RobotBlock.from_parts("jump_flight", (y, yd, ydd, r),
                                 {"torque": robot.torque_rows(tau[6:]), "flight_clearance": P[2, :].T}, d)


def pitch_rate_block(robot: JumpRobot, d: int) -> RobotBlock:
    """The pitch rate pd = (L - h) / I of the flight (integrated by the pitch rows)."""
    (y, yd, ydd, r), u = inputs(robot, PITCH_RATE_INPUTS)
    pd, _ = flight_functions(robot.sym, robot.smap)["pitch_rate"](y, yd, ydd, u["L"])
    return RobotBlock.from_parts("jump_pitch_rate", (y, yd, ydd, r), {"pitch_rate": pd}, d)
