"""The flight's rows (:mod:`latentoc.jump.flight`): inverse dynamics, foot clearance, pitch rate.

In flight the body falls freely, so the joint torques do not depend on where the body is nor on
its pitch: they are those of RNEA with the base at the origin, unpitched, turning at the pitch
rate pd, and accelerating at (ax, az, pdd) such that the base rows of RNEA vanish (no external
wrench; Crocoddyl's inverse-dynamics form). (pd, ax, az, pdd) are variables of each flight
sample, tied to the conserved momentum by the pitch-rate block, so the torque block's
derivatives hold no ballistic base; it can sit at any time of the flight (the exchange of
:mod:`latentoc.jump.exchange` places it on the 1 kHz grid). The clearance block takes the
pitch and the takeoff COM state to place the feet.
"""
from __future__ import annotations

import casadi as ca

from ...nlp.blocks import RobotBlock
from ..flight import GRAVITY, flight_functions
from ..robot import SAGITTAL_ROWS, JumpRobot
from . import inputs

DYNAMICS_INPUTS = {"pd": 1, "acc": 3}  # pitch rate; base accelerations (x, z, pitch)
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


def dynamics_block(robot: JumpRobot, d: int) -> RobotBlock:
    """Free fall by inverse dynamics: the base rows of RNEA (body weights; zero in flight) and the
    joint torques, at zero pitch and position (module doc)."""
    (y, yd, ydd, r), u = inputs(robot, DYNAMICS_INPUTS)
    q, v, a = robot.configuration(ca.DM.zeros(3), ca.vertcat(0, 0, u["pd"]), u["acc"], y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    return RobotBlock.from_parts("jump_flight_dynamics", (y, yd, ydd, r),
                                 {"flight_base": tau[SAGITTAL_ROWS] / robot.weight,
                                  "torque": robot.torque_rows(tau[6:])}, d)


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
