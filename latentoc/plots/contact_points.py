"""The contact points of a contact motion's feet, from the result schema alone.

``trajectory.npz`` names the left foot's points (``contact_points``; results from before it was
exported: heel, ball, toe) and the frames they are fixed in (``contact_frames``, the left foot's
then the right foot's). With one frame per point (2 k frames for k points) point j lies in frame j
of its foot; otherwise the frames are each foot's foot, ball and toes bodies (the CMU humanoid's
``lfoot``, ``lfoot_end``, ``ltoes_end``) and a point lies in one of them by its name
(:data:`BODY_OF`). A left point ``name`` sits at ``{name}_offset`` in its frame (zeros where the
trajectory has none, e.g. ``toe_offset`` of older results). The right foot is the left one's mirror
image (y negated), as in :mod:`latentoc.jump.robot.feet`: its forces are the left ones mirrored, and
each of its points is the point of its right frame that is the mirror image of the left point at
the model's neutral configuration (a left-right symmetric pose; :func:`mirrored_offset`). The
offset itself is not simply mirrored: the CMU humanoid's right frames are the left ones mirrored
with their local x reversed, so (x, -y, z) in ``rtoes_end`` would put the pad 2 cm off.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

__all__ = ["BODY_OF", "LEGACY_POINTS", "MIRROR", "ContactPoints", "contact_points_of", "mirrored_offset",
           "point_positions", "world_forces"]

BODY_OF = {"heel": 0, "ball": 1, "toe": 2, "pad": 2}  # the point's frame among each foot's (foot, ball, toes)
LEGACY_POINTS = ("heel", "ball", "toe")  # a result without ``contact_points``
MIRROR = np.array([1.0, -1.0, 1.0])  # the left foot to the right one (y negated)


@dataclass(frozen=True)
class ContactPoints:
    """The k points of the left foot by ``names``, then the right foot's: ``frames`` (2 k) and the
    points' ``offsets`` (2 k, 3) in them."""

    names: tuple[str, ...]
    frames: tuple[str, ...]
    offsets: np.ndarray

    @property
    def k(self) -> int:
        """Points per foot."""
        return len(self.names)

    def index(self, name: str) -> int | None:
        """The position of point ``name`` among one foot's, None if the foot has none of that name."""
        return self.names.index(name) if name in self.names else None

    def labels(self) -> list[str]:
        """'left heel', ..., 'right heel', ...: the 2 k points in order."""
        return [f"{side} {n}" for side in ("left", "right") for n in self.names]

    def positions(self, model: pin.Model, Q: np.ndarray) -> np.ndarray:
        """World positions (n, 2 k, 3) of the points at the configurations Q (n, nq)."""
        return point_positions(model, self.frames, self.offsets, Q)


def _frame_ids(model: pin.Model, frames: Sequence[str]) -> list[int]:
    """The ids of the named frames; a ValueError naming one the model lacks."""
    missing = [f for f in frames if not model.existFrame(f)]
    if missing:
        raise ValueError(f"the model has no contact frame {missing[0]!r} (of {list(frames)})")
    return [model.getFrameId(f) for f in frames]


def mirrored_offset(model: pin.Model, left: str, right: str, offset: np.ndarray) -> np.ndarray:
    """The offset in frame ``right`` of the mirror image (y negated) of the point at ``offset`` in
    frame ``left``, at the neutral configuration of ``model`` (module doc)."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    L, R = (data.oMf[f] for f in _frame_ids(model, [left, right]))
    return R.actInv(MIRROR * L.act(np.asarray(offset, dtype=float)))


def contact_points_of(model: pin.Model, traj: Mapping[str, Any]) -> ContactPoints:
    """The feet's contact points a trajectory of ``model`` names (module doc)."""
    names = tuple(str(p) for p in np.asarray(traj["contact_points"]).ravel()) if "contact_points" in traj \
        else LEGACY_POINTS
    frames = [str(f) for f in np.asarray(traj["contact_frames"]).ravel()]
    k = len(names)
    if len(frames) == 2 * k:  # one frame per point
        point_frames = frames
    elif len(frames) % 2 == 0 and all(n in BODY_OF and BODY_OF[n] < len(frames) // 2 for n in names):
        half = len(frames) // 2
        point_frames = [frames[side * half + BODY_OF[n]] for side in range(2) for n in names]
    else:
        raise ValueError(f"contact points {list(names)} cannot be placed in the contact frames {frames}: "
                         f"give one frame per point (left foot's, then right foot's) or points among {sorted(BODY_OF)}")
    _frame_ids(model, point_frames)
    left = [np.asarray(traj.get(f"{n}_offset", np.zeros(3)), dtype=float).reshape(3) for n in names]
    right = [mirrored_offset(model, point_frames[j], point_frames[k + j], o) for j, o in enumerate(left)]
    return ContactPoints(names, tuple(point_frames), np.array(left + right).reshape(2 * k, 3))


def point_positions(model: pin.Model, frames: Sequence[str], offsets: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """World positions (n, m, 3) of m points, point j fixed at ``offsets[j]`` in frame ``frames[j]``,
    at each configuration of Q (n, nq) (numeric forward kinematics)."""
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    offsets = np.asarray(offsets, dtype=float).reshape(len(frames), 3)
    ids = _frame_ids(model, frames)
    data = model.createData()
    out = np.zeros((len(Q), len(frames), 3))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, data, q)
        for j, (f, o) in enumerate(zip(ids, offsets)):
            M = data.oMf[f]
            out[i, j] = M.translation + M.rotation @ o
    return out


def world_forces(point_forces: np.ndarray) -> np.ndarray:
    """World forces (n, 2 k, 3) of both feet's points from the left foot's ``point_forces``: (n, k, 2)
    sagittal (f_x, f_z) or (n, k, 3); the right foot's are their mirror image."""
    F = np.asarray(point_forces, dtype=float)
    if F.ndim != 3 or F.shape[2] not in (2, 3):
        raise ValueError(f"point_forces must be (n, points, 2) or (n, points, 3), got shape {F.shape}")
    left = np.zeros(F.shape[:2] + (3,))
    if F.shape[2] == 2:
        left[..., 0], left[..., 2] = F[..., 0], F[..., 1]
    else:
        left[:] = F
    return np.concatenate([left, left * MIRROR], axis=1)
