"""The robot's joint position and velocity limits along the whole jump, from its description (a
URDF's ``<limit lower upper velocity>``): rows on the learned coordinates y and their rates yd
(a right joint's limits mirrored onto its left partner, :attr:`JumpRobot.joint_bounds`), every
:data:`~latentoc.jump.rows.tube_rows.TUBE_SPACING` seconds. A robot without limits (the CMU humanoid) has no such block.
"""
from __future__ import annotations

import numpy as np

from latentoc.nlp.blocks import RobotBlock
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.transcription.wiring import Rows, Wiring
from latentoc.jump.rows import inputs
from latentoc.jump.rows.tube_rows import TUBE_SPACING

LIMIT_BACKOFF = 5e-3  # rad and rad/s inside the limits: the rows hold between their samples too (5 ms apart)


def block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), _ = inputs(robot, {})
    return RobotBlock.from_parts("jump_joint_limits", (y, yd, ydd, r), {"joint_position": y, "joint_velocity": yd}, d)


def limited(robot: JumpRobot) -> tuple[np.ndarray, np.ndarray]:
    """The learned coordinates with a position limit, and those with a velocity limit."""
    lo, hi, vmax = robot.joint_bounds
    return np.flatnonzero(np.isfinite(lo) | np.isfinite(hi)), np.flatnonzero(np.isfinite(vmax))


def bounds(robot: JumpRobot, names: np.ndarray, comps: np.ndarray, lbg: np.ndarray, ubg: np.ndarray) -> None:
    """The rows' bounds (in place): the limits less :data:`LIMIT_BACKOFF`."""
    lo, hi, vmax = robot.joint_bounds
    pos, vel = names == "joint_position", names == "joint_velocity"
    lbg[pos], ubg[pos] = lo[comps[pos]] + LIMIT_BACKOFF, hi[comps[pos]] - LIMIT_BACKOFF
    lbg[vel], ubg[vel] = -vmax[comps[vel]] + LIMIT_BACKOFF, vmax[comps[vel]] - LIMIT_BACKOFF


def wire(w: Wiring) -> None:
    if "joint_limits" not in w.blocks:
        return
    pos, vel = limited(w.robot)
    t = np.arange(0.0, w.phases.duration + 1e-9, TUBE_SPACING)
    ni = w.inputs(len(t))
    w.latent(ni, t)
    rows = Rows(w.blocks["joint_limits"])
    for k in range(len(t)):
        rows.add(k, "joint_position", subset=pos)
        rows.add(k, "joint_velocity", subset=vel)
    w.add("joint_limits", ni, rows, t)
