"""Symmetric jump model and training motion (Kang & Park 2015, Sect. 4.2, Table 5).

* The model is the symmetrised CMU humanoid (:mod:`latentoc.robots.cmu_humanoid`), so that
  mirrored joint motions are exactly symmetric.
* The learned coordinates are the 37 left + centre DOFs of
  :class:`~latentoc.mocap.symmetry.SymmetryMap`; the right side is the mirror image.
  The centre DOFs that flip sign under the mirror (ry, rz of the spine, neck and head)
  are set to zero in the training data: a symmetric motion cannot have them, and keeping
  them would put the model's lateral base rows out of balance.
* The base of the training motion is projected to the sagittal plane
  (:mod:`..robot.sagittal_base`), and the motion is shifted so that the ground is ``z = 0`` and the
  toe tip at the start is at ``x = 0``.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from latentoc.robots.cmu_humanoid import symmetric_model
from latentoc.robots.human_models import broad_jump_sequences
from latentoc.mocap.symmetry import SymmetryMap
from latentoc.motions.readers import MotionFileError, read_raw_motion
from latentoc.jump.robot.sagittal_base import base_to_freeflyer, freeflyer_to_base
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID, RobotDeclaration


def antisymmetric_centre(smap: SymmetryMap) -> np.ndarray:
    """Indices (into the learned vector) of centre DOFs that flip sign under the mirror."""
    return np.array([k for k, n in enumerate(smap.learned_names)
                     if smap.centre_factor.get(n, 1.0) < 0], dtype=int)


@dataclass
class JumpTraining:
    """One symmetric training jump: times, learned coordinates, sagittal base, full q."""

    t: np.ndarray  # (n,)
    Y: np.ndarray  # (n, 37) learned DOFs
    base: np.ndarray  # (n, 3) x, z, pitch
    Q: np.ndarray  # (n, 63) full symmetric configurations

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])


def symmetric_motion(Q: np.ndarray, t: np.ndarray, model: pin.Model, smap: SymmetryMap,
                     robot: RobotDeclaration = CMU_HUMANOID) -> JumpTraining:
    """Symmetrise captured configurations; ground (the lowest of the foot's fixed points) at z = 0,
    starting toe tip at x = 0."""
    Y = smap.to_learned(Q).copy()
    Y[:, antisymmetric_centre(smap)] = 0.0
    base = freeflyer_to_base(Q[:, :7])
    Qs = smap.to_full(Y, base_to_freeflyer(base)[0])
    fp = robot.geometry(model, Qs[0], on_ground=False).footprint  # where the ground is (checked by the set-up)
    assert fp is not None
    base[:, 0] -= fp[0, 2]
    base[:, 1] -= min(fp[2, k] for k, p in enumerate(robot.foot) if not p.ground)
    Qs = smap.to_full(Y, base_to_freeflyer(base)[0])
    return JumpTraining(np.asarray(t, float) - t[0], Y, base, Qs)


def motion_training(path: Path, model: pin.Model, smap: SymmetryMap, robot: RobotDeclaration) -> JumpTraining:
    """A robot's own demonstration of the jump (an NPZ or CSV of t and the full q, as `retarget`
    writes it) as a symmetric training jump."""
    raw = read_raw_motion(path, model)
    if raw.names is not None or raw.values.shape[1] != model.nq:
        raise MotionFileError(f"{path}: a contact problem's motion is the robot's full configuration q "
                              f"({model.nq} columns, base first, no joint_names); got {raw.values.shape[1]} columns")
    dt = np.diff(raw.t)
    if np.ptp(dt) > 1e-6 * dt.mean():
        raise MotionFileError(f"{path}: the samples are not evenly spaced in time ({dt.min():.6f} to {dt.max():.6f} s)")
    return symmetric_motion(raw.values, raw.t, model, smap, robot)


def training_jumps(which: str | int = 0, robot: RobotDeclaration = CMU_HUMANOID) -> list[JumpTraining]:
    """Symmetric training jumps of take 01_01: ``0`` (the paper's single jump) or ``"all"``, with the
    CMU humanoid's feet as ``robot`` declares them."""
    model, smap = symmetric_model()
    seqs = broad_jump_sequences()
    chosen = seqs if which == "all" else [seqs[int(which)]]
    return [symmetric_motion(Q, t, model, smap, robot) for t, Q in chosen]
