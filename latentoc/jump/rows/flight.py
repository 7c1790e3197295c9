"""The flight's rows (:mod:`latentoc.jump.flight`): joint torques, foot clearance, pitch rate.

In flight the body falls freely about its COM, so the joint torques are those of the motion in
the COM's free-falling frame: they depend on the joint motion and the pitch rate and its time
derivative (from the conserved momentum L), not on the pitch itself nor on where the COM is.
The torque block therefore takes (y, yd, ydd, L) and holds at any time of the flight (the
exchange of :mod:`latentoc.jump.exchange` places it on the 1 kHz grid). The clearance block
takes the pitch and the takeoff COM state to place the feet.
"""
from __future__ import annotations

import casadi as ca

from ...nlp.blocks import RobotBlock
from ..flight import GRAVITY, flight_functions
from ..robot import JumpRobot
from . import inputs

TORQUE_INPUTS = {"L": 1}
CLEARANCE_INPUTS = {"p": 1, "L": 1, "c_to": 2, "cd_to": 2, "t": 1}
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


def torque_block(robot: JumpRobot, d: int) -> RobotBlock:
    """Joint torques of the ballistic motion, computed at zero pitch (they do not depend on it)."""
    (y, yd, ydd, r), u = inputs(robot, TORQUE_INPUTS)
    b, bd, bdd = flight_base(robot, y, yd, ydd, ca.DM(0.0), u["L"], ca.DM.zeros(2), ca.DM.zeros(2))
    q, v, a = robot.configuration(b, bd, bdd, y, yd, ydd)
    return RobotBlock.from_parts("jump_flight_torque", (y, yd, ydd, r),
                                 {"torque": robot.torque_rows(robot.sym.rnea(q, v, a)[6:])}, d)


def clearance_block(robot: JumpRobot, d: int) -> RobotBlock:
    """Heel, ball and toe heights at pitch p, the COM on its parabola from the takeoff state."""
    (y, yd, ydd, r), u = inputs(robot, CLEARANCE_INPUTS)
    b, _, _ = flight_base(robot, y, yd, ydd, u["p"], u["L"], ca.DM.zeros(2), ca.DM.zeros(2))
    q, _, _ = robot.configuration(b, ca.DM.zeros(3), ca.DM.zeros(3), y, 0 * yd, 0 * ydd)
    P = robot.points(q, ballistic_com(u["c_to"], u["cd_to"], u["t"])[0])
    return RobotBlock.from_parts("jump_flight_clearance", (y, yd, ydd, r), {"flight_clearance": P[2, :].T}, d)


def pitch_rate_block(robot: JumpRobot, d: int) -> RobotBlock:
    """The pitch rate pd = (L - h) / I of the flight (integrated by the pitch rows)."""
    (y, yd, ydd, r), u = inputs(robot, PITCH_RATE_INPUTS)
    pd, _ = flight_functions(robot.sym, robot.smap)["pitch_rate"](y, yd, ydd, u["L"])
    return RobotBlock.from_parts("jump_pitch_rate", (y, yd, ydd, r), {"pitch_rate": pd}, d)
