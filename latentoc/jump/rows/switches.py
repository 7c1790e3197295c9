"""The contact mode switches: where the base's anchor changes, the two bases meet.

* Anchor switch (the heel leaves or strikes the ground: flat foot <-> flat toes), inputs r: the toe
  joint's standing angle; rows: the toe joint at that angle and at rest, so the base anchored on the
  flat foot and the one anchored on the flat toes meet in position and velocity.
* Roll switch (the toes start or stop rolling on the toe point), inputs r: the landing's sideways
  shift of the feet, the rolling toes' base pitch, rate and acceleration; rows: that pitch and rate
  those of the base on the flat toes (the legs closed sideways, :attr:`.robot.JumpRobot.closure`).
"""
from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from ...nlp.blocks import RobotBlock
from ...nlp.inputs import NodeInputs
from ..robot import JumpRobot
from ..wiring import Rows, Wiring
from . import inputs

ANCHOR_INPUTS = {"standing": 1}
ROLL_INPUTS = {"y_shift": 1, "roll": 3}


def anchor_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, ANCHOR_INPUTS)
    k = robot.hinge
    return RobotBlock.from_parts("jump_anchor_switch", (y, yd, ydd, r),
                                 {"anchor_switch": ca.vertcat(y[k] - u["standing"], yd[k])}, d, hot=False)


def roll_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, ROLL_INPUTS)
    b, bd, _ = robot.anchored("toes")(*robot.closure(y, yd, ydd, 0, u["y_shift"]), 0)
    return RobotBlock.from_parts("jump_roll_switch", (y, yd, ydd, r),
                                 {"roll_switch": ca.vertcat(u["roll"][0] - b[2], u["roll"][1] - bd[2])}, d, hot=False)


def _wire(w: Wiring, name: str, t: np.ndarray, extra: Callable[[NodeInputs, np.ndarray], None]) -> None:
    """Family ``name``: its block's rows at times t, the inputs after the path's from ``extra``."""
    if not len(t):
        return
    ni = w.inputs(len(t))
    w.latent(ni, t)
    extra(ni, t)
    rows = Rows(w.blocks[name])
    for k in range(len(t)):
        rows.add(k, name)
    w.add(name, ni, rows, t)


def wire_anchor(w: Wiring) -> None:
    """The toe joint at its standing angle and at rest where the heel leaves or strikes the ground."""
    _wire(w, "anchor_switch", w.phases.switches(), lambda ni, t: ni.constant(np.full((len(t), 1), w.hinge_standing)))


def wire_roll(w: Wiring) -> None:
    """The rolling toes' pitch and rate those of the flat toes where they start or stop rolling."""
    def extra(ni: NodeInputs, t: np.ndarray) -> None:
        land = t >= w.phases.touchdown - 1e-12
        ni.variables(np.where(land, w.variables.index("y_L")[0], -1)[:, None])
        w.roll(ni, t)

    _wire(w, "roll_switch", w.phases.roll_switches(), extra)
