"""A retargeted demonstration as a 3-D scene: the robot's motion (``latentoc retarget``'s NPZ) with
the source's motion it followed beside it, both on their own models and at the same times.

The NPZ carries ``t``, ``q`` (the robot), ``q_source`` (the source model's configurations) and the
report ``retarget`` naming both models; the source is drawn ``GAP`` metres to the robot's side of
their widest extents, so the two never overlap.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.runtime.files import NPZ_ERRORS
from latentoc.robots.catalog import load_robot
from latentoc.viewer.geometry import part_poses, robot_parts
from latentoc.viewer.scene import _part_json, b64, sample_indices

__all__ = ["retargeted_scene", "read_retargeted", "GAP"]

GAP = 0.3  # m between the robot's and the source's sideways extents


def read_retargeted(path: str | Path) -> dict[str, Any]:
    """``t``, ``q``, ``q_source`` and the report of ``latentoc retarget``'s NPZ at ``path``; a
    :class:`LatentocError` naming the file and what is missing otherwise."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as f:
            arrays = {k: f[k] for k in f.files}
    except NPZ_ERRORS as exc:
        raise LatentocError(f"{path}: not a readable .npz ({exc})") from None
    missing = [k for k in ("t", "q", "q_source", "retarget") if k not in arrays]
    if missing:
        raise LatentocError(f"{path}: not a retargeted motion of `latentoc retarget` (no {', '.join(missing)}; "
                            "a motion retargeted before the source was kept needs retargeting again)")
    info = json.loads(str(arrays["retarget"]))
    t, q, qs = (np.asarray(arrays[k], float) for k in ("t", "q", "q_source"))
    if not (t.ndim == 1 and q.ndim == 2 and qs.ndim == 2 and len(t) == len(q) == len(qs) >= 2):
        raise LatentocError(f"{path}: t, q and q_source must hold the same frames (got {t.shape}, {q.shape}, {qs.shape})")
    return {"t": t, "q": q, "q_source": qs, "info": info}


def _lowest(model: pin.Model, q: np.ndarray) -> float:
    """The height of the model's lowest frame at configuration q (a capture's ground may not be z = 0)."""
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    return float(min(f.translation[2] for f in d.oMf))


def retargeted_scene(path: str | Path, rate_hz: float = 50.0) -> dict[str, Any]:
    """The scene of the retargeted motion at ``path`` (module doc), for :func:`.html.page_html`."""
    r = read_retargeted(path)
    info = r["info"]
    target, source = load_robot(info["target"]), load_robot(info["source"])
    idx = sample_indices(r["t"], rate_hz)
    meshes: dict[str, int] = {}
    mesh_data: list[dict[str, Any]] = []
    parts, what = robot_parts(target, info["target"])
    src_parts, _ = robot_parts(source, info["source"])
    poses = part_poses(target, parts, r["q"][idx])
    beside = part_poses(source, src_parts, r["q_source"][idx])
    beside[..., 1] += poses[..., 1].min() - beside[..., 1].max() - GAP  # to the robot's right
    beside[..., 2] -= _lowest(source, r["q_source"][0])  # the source standing on the ground at its start
    times = r["t"][idx] - r["t"][0]
    pts = np.vstack([poses[..., :3].reshape(-1, 3), beside[..., :3].reshape(-1, 3)])
    worst = max((float(v["max"]) for v in info.get("residual_mm", {}).values()), default=0.0)
    return {"title": f"{info['source']} -> {info['target']} (retargeted)", "parts_are": what,
            "parts": [_part_json(p, meshes, mesh_data) for p in parts], "meshes": mesh_data,
            "frames": len(idx), "times": b64(times), "duration": float(times[-1]), "motions": {"optimised": b64(poses)},
            "beside": {"parts": [_part_json(p, meshes, mesh_data) for p in src_parts], "poses": b64(beside),
                       "label": f"the source ({info['source']})"},
            "bounds": [(pts.min(axis=0) - 0.3).tolist(), (pts.max(axis=0) + 0.3).tolist()], "ground": True,
            "summary": f"{len(r['t'])} frames, scale {float(info.get('scale', 1.0)):.3f}, "
                       f"largest keypoint residual {worst:.0f} mm"}
