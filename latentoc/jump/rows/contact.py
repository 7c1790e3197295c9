"""A contact node or sample of the stance or the landing (Eq. 3, 34-36).

Inputs r: the base (b, bd, bdd) of the contact phase's own (x, z, pitch) spline, the toe tip's
ground point x_pin, and the friction-pyramid edge weights lam (heel, ball, toe, pad; body weights).
Rows: the sagittal base rows of RNEA minus sum J^T f (body weights), the joint torques, the
toe tip's offset from its ground point, the heel and ball heights, the centre of pressure on
the ground within the loaded support, the ZMP in the support polygon (both homogeneous in the
normal force, smooth as fz -> 0) and the projected COM in it.
"""
from __future__ import annotations

import casadi as ca

from ...nlp.blocks import RobotBlock
from ..contact import EDGES, TOE_PAD, point_forces, point_generalized_force, toe_wrench
from ..robot import SAGITTAL_ROWS, JumpRobot, galilean
from ...support_polygon import symbolic_rows
from . import inputs

INPUTS = {"b": 3, "bd": 3, "bdd": 3, "x_pin": 1, "lam": EDGES}


def homogeneous_polygon_rows(heel, toe, p_scaled, s):
    """s * rows(p_scaled / s) of the feet's support polygon, without the division."""
    V = [(heel[0], -heel[1]), (toe[0], -toe[1]), (toe[0], toe[1]), (heel[0], heel[1])]
    out = []
    for i in range(4):
        (x0, y0), (x1, y1) = V[i], V[(i + 1) % 4]
        ex, ey = x1 - x0, y1 - y0
        out.append(-(ex * (p_scaled[1] - y0 * s) - ey * (p_scaled[0] - x0 * s)) / ca.sqrt(ex * ex + ey * ey))
    return ca.vertcat(*out)


def block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, INPUTS)
    W = robot.weight
    q, v, a = robot.configuration(*galilean(u["b"], u["bd"]), u["bdd"], y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    lam = u["lam"]
    gen = point_generalized_force(robot.sym, robot.geom, q, point_forces(lam * W, robot.mu))
    P = robot.points(q, u["b"][:2])
    w = toe_wrench(lam, P, robot.mu)  # body weights, moment about the toe tip
    fx, fz = w[0], w[2]
    my = w[4] + P[2, 2] * fx  # about the ground point below the toe tip: CoP x = toe_x - my / fz
    heel, toe = P[:2, 0], P[:2, 2]
    parts = {
        "dynamics": (tau - gen)[SAGITTAL_ROWS] / W,
        "torque": robot.torque_rows((tau - gen)[6:]),
        "ball_height": P[2, 1],
        "toe_position": ca.vertcat(P[0, 2] - u["x_pin"], P[2, 2]),
        "heel_height": P[2, 0],
        # the centre of pressure on the ground between the rearmost loaded point and the toe tip
        # (homogeneous in fz, >= 0): cop_front, and cop_heel / cop_ball / cop_pad by the schedule
        "cop_front": my,
        "cop_heel": (toe[0] - heel[0]) * fz - my,
        "cop_ball": (toe[0] - P[0, 1]) * fz - my,
        "cop_pad": TOE_PAD * fz - my,
        # ZMP x = toe_x - my / fz (y = 0), as fz * rows(ZMP)
        "zmp_polygon": homogeneous_polygon_rows(heel, toe, ca.vertcat(toe[0] * fz - my, 0), fz),
        "com_polygon": symbolic_rows(heel, toe)(robot.sym.com(q)[:2] + ca.vertcat(u["b"][0], 0)),
    }
    return RobotBlock.from_parts("jump_contact", (y, yd, ydd, r), parts, d)
