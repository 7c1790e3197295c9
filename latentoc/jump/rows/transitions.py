"""The phase transitions: takeoff, touchdown (Eq. 4-5) and the heel's lift-off and strike.

Takeoff inputs r: whether the hinge is held and the flight variables (c_to, cd_to, L, p); rows: the
flight variables equal the stance's COM, COM velocity, angular momentum and pitch, and the closed
legs (:mod:`..closure.planted_legs`) meet the GP mean's: the out-of-plane joints (and a held hinge) with their
velocities, so the flight starts where the stance ends.

Touchdown inputs r: whether the hinge is held, the planted body's shift, the flight's pitch p and
momentum L, its takeoff COM state and the flight time. The landing's planted body arrives at rest:
the flight's base pose and velocity meet the landing's planted base and the closed legs the GP
mean's, so no impulse acts (the joints, the base and the feet keep their velocities).

The hinge switch, at the heel's lift-off in the stance and its strike in the landing: the GP mean's
hinge at its standing angle, at rest, where the closure starts or stops holding it.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from latentoc.nlp.blocks import RobotBlock
from latentoc.jump.closure.ballistic import flight_functions
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.transcription.wiring import Rows, Wiring
from latentoc.jump.rows import inputs
from latentoc.jump.rows.flight import ballistic_com, flight_base

TAKEOFF_INPUTS = {"held": 1, "c_to": 2, "cd_to": 2, "L": 1, "p": 1}
TOUCHDOWN_INPUTS = {"held": 1, "shift": 1, "p": 1, "L": 1, "c_to": 2, "cd_to": 2, "t": 1}


def _gap(robot: JumpRobot, y, yd, yc, ydc):
    """The closed legs less the GP mean's: the out-of-plane joints and the hinge, then their velocities."""
    assert robot.closure is not None
    idx = robot.closure.dependent.tolist() + ([robot.closure.hinge] if robot.closure.hinge is not None else [])
    return ca.vertcat((yc - y)[idx], (ydc - yd)[idx])


def gap_rows(robot: JumpRobot, held: bool) -> np.ndarray:
    """Components of the closure gap that can be nonzero: the hinge's only where it is held."""
    assert robot.closure is not None
    n_dep, hinge = len(robot.closure.dependent), robot.closure.hinge is not None
    per = np.arange(n_dep + int(hinge and held))
    return np.concatenate([per, per + n_dep + int(hinge)])


def takeoff_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, TAKEOFF_INPUTS)
    (yc, ydc, _), (b, bd, _) = robot.planted(y, yd, ydd, u["held"], 0.0)
    c, cd, L = flight_functions(robot.sym, robot.smap)["momentum"](yc, ydc, b, bd)
    rows = ca.vertcat(c - u["c_to"], cd - u["cd_to"], L - u["L"], b[2] - u["p"])
    return RobotBlock.from_parts("jump_takeoff", (y, yd, ydd, r), {"takeoff": rows, "closure_gap": _gap(robot, y, yd, yc, ydc)},
                                 d, hot=False)


def touchdown_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, TOUCHDOWN_INPUTS)
    bm, bdm, _ = flight_base(robot, y, yd, ydd, u["p"], u["L"], *ballistic_com(u["c_to"], u["cd_to"], u["t"]))
    (yc, ydc, _), (b, bd, _) = robot.planted(y, yd, ydd, u["held"], u["shift"])
    return RobotBlock.from_parts("jump_touchdown", (y, yd, ydd, r),
                                 {"touchdown_position": bm - b, "touchdown_velocity": bdm - bd,
                                  "closure_gap": _gap(robot, y, yd, yc, ydc)}, d, hot=False)


def hinge_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), _ = inputs(robot, {})
    assert robot.closure is not None and robot.closure.hinge is not None
    h = robot.closure.hinge
    return RobotBlock.from_parts("jump_hinge", (y, yd, ydd, r),
                                 {"hinge_switch": ca.vertcat(y[h] - robot.closure.hinge_standing, yd[h])}, d, hot=False)


def wire_takeoff(w: Wiring) -> None:
    """The takeoff: the flight's state variables are the stance's at takeoff, the legs the GP mean's."""
    var, t = w.variables, np.array([w.phases.takeoff])
    ni = w.inputs(1)
    w.latent(ni, t)
    held = bool(w.phases.held(t)[0])
    ni.constant(np.array([[float(held)]]))
    ni.variables(np.concatenate([var.index("c_to"), var.index("cd_to"), var.index("L_to"),
                                 var.index("pitch_flight")[:1]])[None, :])
    rows = Rows(w.blocks["takeoff"])
    rows.add(0, "takeoff")
    rows.add(0, "closure_gap", subset=gap_rows(w.robot, held))
    w.add("takeoff", ni, rows, t)


def wire_touchdown(w: Wiring) -> None:
    """The touchdown: the flight's base and legs meet the landing's planted ones, at rest."""
    var, ph = w.variables, w.phases
    t = np.array([ph.touchdown])
    ni = w.inputs(1)
    w.latent(ni, t)
    held = bool(ph.held(t)[0])
    ni.constant(np.array([[float(held)]]))
    ni.variables(var.index("x_L")[None, :], np.array([[-w.robot.geom.toe_x]]))
    ni.variables(np.concatenate([var.index("pitch_flight")[-1:], var.index("L_to"), var.index("c_to"),
                                 var.index("cd_to")])[None, :])
    ni.constant(np.array([[ph.touchdown - ph.takeoff]]))
    rows = Rows(w.blocks["touchdown"])
    rows.add(0, "touchdown_position")
    rows.add(0, "touchdown_velocity")
    rows.add(0, "closure_gap", subset=gap_rows(w.robot, held))
    w.add("touchdown", ni, rows, t)


def hinge_times(phases) -> np.ndarray:
    """Where the closure starts or stops holding the hinge inside a contact phase: the heel's lift-off
    in the stance, its strike in the landing (none at the takeoff or the touchdown: their gaps hold it)."""
    ph = phases
    ev = [e for e in ph.events if abs(e - ph.takeoff) > 1e-9 and abs(e - ph.touchdown) > 1e-9]
    return np.array(ev, float)


def wire_hinge(w: Wiring) -> None:
    """The hinge switches (module doc), for a robot with a hinge."""
    if "hinge" not in w.blocks:
        return
    t = hinge_times(w.phases)
    if not len(t):
        return
    ni = w.inputs(len(t))
    w.latent(ni, t)
    rows = Rows(w.blocks["hinge"])
    for k in range(len(t)):
        rows.add(k, "hinge_switch")
    w.add("hinge", ni, rows, t)
