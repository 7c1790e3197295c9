"""A result as a 3-D scene: the robot's parts posed along the optimised and the initial motion, and
for a contact motion the contact points, forces, friction cones, support polygon, COM and ZMP.

:func:`build_scene` reads the result schema only (``trajectory.npz``, the problem's ``robot``
setting for the meshes) and samples the 1 kHz motion at ``rate_hz``; the arrays go into the page
as base64 little-endian float32 (:func:`b64`), decoded by ``js/page.js``.
"""
from __future__ import annotations

import base64
import hashlib
from typing import Any

import numpy as np
import pinocchio as pin

from ..plots.contact import contact_series
from ..plots.kinematics import floating_base, model_of
from ..results import Result
from .geometry import Part, part_poses, robot_parts

__all__ = ["build_scene", "b64", "sample_indices", "contact_points", "FORCE_SCALE", "CONE_HEIGHT"]

FORCE_SCALE = 0.5  # arrow length in m of a force of one body weight
CONE_HEIGHT = 0.15  # m, the drawn friction cones' height


def b64(a: np.ndarray, dtype: str = "<f4") -> str:
    """An array's values as base64 of little-endian ``dtype`` (the page's typed arrays)."""
    return base64.b64encode(np.ascontiguousarray(np.asarray(a).astype(dtype)).tobytes()).decode("ascii")


def sample_indices(t: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of the samples nearest to t0, t0 + 1/rate, ..., the last sample included."""
    t = np.asarray(t, dtype=float)
    n = int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1
    idx = np.abs(t[None, :] - (t[0] + np.arange(n) / rate_hz)[:, None]).argmin(axis=1)
    return np.unique(np.append(idx, len(t) - 1))


def _part_json(p: Part, meshes: dict[str, int], mesh_data: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {"name": p.name, "kind": p.kind, "colour": list(p.colour), "size": list(p.size)}
    if p.kind == "mesh":
        assert p.vertices is not None and p.triangles is not None
        key = hashlib.sha256(p.vertices.astype("<f4").tobytes() + p.triangles.astype("<u4").tobytes()).hexdigest()
        if key not in meshes:  # a mesh used twice (the Panda's fingers) is sent once
            meshes[key] = len(mesh_data)
            wide = len(p.vertices) > 65535
            mesh_data.append({"positions": b64(p.vertices), "indices": b64(p.triangles, "<u4" if wide else "<u2"),
                              "wide": wide})
        out["mesh"] = meshes[key]
    return out


def contact_points(model: pin.Model, traj: dict[str, Any], Q: np.ndarray) -> np.ndarray:
    """World positions (n, 6, 3) of the left then right heel, ball and toe tip (``contact_frames``:
    foot, ball and toe frames of each foot; the heel at ``heel_offset`` in the foot frame)."""
    frames = [str(f) for f in np.asarray(traj["contact_frames"])]
    heel = np.asarray(traj["heel_offset"], dtype=float)
    data = model.createData()
    out = np.zeros((len(Q), 6, 3))
    ids = [model.getFrameId(f) for f in frames]
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, data, q)
        for foot in range(2):
            foot_frame, ball, toe = (data.oMf[ids[3 * foot + k]] for k in range(3))
            out[i, 3 * foot:3 * foot + 3] = [foot_frame.act(heel), ball.translation, toe.translation]
    return out


def _contacts(model: pin.Model, traj: dict[str, Any], idx: np.ndarray) -> dict[str, Any]:
    """The contact layer at the sampled indices (module doc)."""
    sub = {k: (np.asarray(v)[idx] if np.ndim(v) and len(np.asarray(v)) == len(traj["t"]) else v)
           for k, v in traj.items() if k != "model"}
    n = len(idx)
    s = contact_series(model, sub)
    points = contact_points(model, traj, np.asarray(sub["q"]))
    contact = np.asarray(sub["contact"]).astype(bool)
    forces = np.zeros((n, 6, 3))
    if "point_forces" in sub:  # (fx, fz) of the left heel, ball, toe; the right foot mirrors the left
        F = np.asarray(sub["point_forces"], dtype=float)
        for foot in range(2):
            forces[:, 3 * foot:3 * foot + 3, 0] = F[:, :, 0]
            forces[:, 3 * foot:3 * foot + 3, 2] = F[:, :, 1]
        loaded = np.asarray(sub["loaded"]).astype(bool) if "loaded" in sub else np.ones((n, 3), bool)
        active = contact[:, None] & np.tile(loaded, (1, 2))
    else:  # one wrench per foot at its toe tip
        W = np.asarray(sub["wrench"], dtype=float)
        forces[:, 2], forces[:, 5] = W[:, :3], W[:, :3] * [1.0, -1.0, 1.0]
        active = np.zeros((n, 6), bool)
        active[:, [2, 5]] = contact[:, None]
    weight = sum(i.mass for i in model.inertias) * float(-model.gravity.linear[2])
    zmp = np.where(np.isfinite(s["zmp"]), s["zmp"], 0.0)
    return {"points": b64(points), "forces": b64(forces * FORCE_SCALE / weight), "active": b64(active, "u1"),
            "polygon": b64(s["polygon"]), "contact": b64(contact, "u1"), "com": b64(s["com"]), "zmp": b64(zmp),
            "mu": float(np.asarray(traj["friction"])) if "friction" in traj else 0.0, "cone_height": CONE_HEIGHT,
            "force_scale": FORCE_SCALE}


def build_scene(result: Result, rate_hz: float = 50.0) -> dict[str, Any]:
    """The scene of ``result`` as JSON-ready data (module doc)."""
    traj = result.trajectory
    model = model_of(traj)
    t = np.asarray(traj["t"], dtype=float)
    idx = sample_indices(t, rate_hz)
    parts, what = robot_parts(model, result.settings.get("robot"), result.details.get("source"))
    meshes: dict[str, int] = {}
    mesh_data: list[dict[str, Any]] = []
    part_json = [_part_json(p, meshes, mesh_data) for p in parts]
    times = t[idx] - t[0]
    poses = part_poses(model, parts, np.asarray(traj["q"])[idx])
    motions = {"optimised": b64(poses)}
    reach = [poses[..., :3].reshape(-1, 3)]
    if "q_initial" in traj:
        Q0 = np.asarray(traj["q_initial"], dtype=float)
        t0 = t if len(Q0) == len(t) else np.linspace(t[0], t[-1], len(Q0))  # its own rate: the same duration
        near = np.abs(t0[None, :] - t[idx][:, None]).argmin(axis=1)
        ghost = part_poses(model, parts, Q0[near])
        motions["initial"] = b64(ghost)
        reach.append(ghost[..., :3].reshape(-1, 3))
    pts = np.vstack(reach)
    radius = max([float(np.max(np.linalg.norm(p.vertices, axis=1))) for p in parts if p.vertices is not None]
                 + [0.5 * max(p.size) for p in parts if p.size] + [0.05])
    scene: dict[str, Any] = {
        "title": f"{result.problem} ({result.method})", "parts_are": what, "parts": part_json, "meshes": mesh_data,
        "frames": len(idx), "times": b64(times), "duration": float(times[-1]), "motions": motions,
        "bounds": [(pts.min(axis=0) - radius).tolist(), (pts.max(axis=0) + radius).tolist()],
        "ground": floating_base(model), "summary": f"cost {result.cost_initial:.4g} -> {result.cost:.4g} "
                                                   f"({result.gain_pct:+.2f} %): {result.cost_meaning}"}
    if "wrench" in traj and "contact_frames" in traj:
        scene["contacts"] = _contacts(model, traj, idx)
    return scene
