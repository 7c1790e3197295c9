"""The stick figure of a Pinocchio model: bones, their sides and world segments (numeric FK).

Shared by the stick-frame figures, the GIF animation and the 3-D view's capsules; a result's
model comes from its ``trajectory.npz`` (:func:`model_of`).
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

__all__ = ["PLANES", "SIDE_COLOURS", "model_of", "floating_base", "joint_positions", "bones", "side",
           "skeleton_segments", "frame_indices"]

PLANES = {"xz": (0, 2), "yz": (1, 2), "xy": (0, 1)}
SIDE_COLOURS = {"left": "C0", "right": "C3", "centre": "0.2"}


def model_of(trajectory: Mapping[str, Any]) -> pin.Model:
    """The robot a ``trajectory.npz`` carries (its ``model`` string)."""
    model = pin.Model()
    model.loadFromString(str(trajectory["model"]))
    return model


def floating_base(model: pin.Model) -> bool:
    """Whether the first joint is a free flyer (a jumping body, not a fixed arm)."""
    return model.njoints > 1 and model.joints[1].nq == 7


def joint_positions(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """World positions (njoints, 3) of every joint placement oMi (numeric FK)."""
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    return np.array([data.oMi[i].translation for i in range(model.njoints)])


def bones(model: pin.Model) -> list[tuple[str, int, str, int, str]]:
    """(parent kind, index, child kind, index, child name) of every stick-figure bone: each joint
    to its parent joint (not a free flyer to the world), each operational frame (the bone ends,
    e.g. ``lhand_end``) to its parent joint."""
    out = [("joint", int(model.parents[i]), "joint", i, model.names[i])
           for i in range(1, model.njoints)
           if not (model.parents[i] == 0 and model.joints[i].nq == 7)]
    out += [("joint", int(f.parentJoint), "frame", k, f.name)
            for k, f in enumerate(model.frames) if f.type == pin.FrameType.OP_FRAME]
    return out


def side(model: pin.Model, name: str) -> str:
    """'left', 'right' or 'centre' from CMU-style l/r name prefixes."""
    names = set(model.names) | {f.name for f in model.frames}
    if name[:1] in "lr" and ("rl"["lr".index(name[0])] + name[1:]) in names:
        return "left" if name[0] == "l" else "right"
    return "centre"


def skeleton_segments(model: pin.Model, q: np.ndarray,
                      return_names: bool = False) -> np.ndarray | tuple[np.ndarray, list[str]]:
    """Bones (:func:`bones`) as (k, 2, 3) world segments at ``q``; zero-length ones dropped. With
    ``return_names`` also each segment's child joint or frame name."""
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    pin.updateFramePlacements(model, data)
    segs, names = [], []
    for _, a, kind, b, name in bones(model):
        end = data.oMi[b] if kind == "joint" else data.oMf[b]
        seg = (data.oMi[a].translation, end.translation)
        if np.linalg.norm(seg[1] - seg[0]) > 1e-9:
            segs.append(seg)
            names.append(name)
    S = np.array(segs, dtype=float).reshape(-1, 2, 3)
    return (S, names) if return_names else S


def frame_indices(n: int, frames: int) -> np.ndarray:
    """``frames`` evenly spaced sample indices of a length-n motion, first and last included."""
    return np.unique(np.round(np.linspace(0, n - 1, min(int(frames), n))).astype(int))
