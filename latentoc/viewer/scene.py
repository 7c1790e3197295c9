"""A result as a 3-D scene: the robot's parts posed along the optimised and the initial motion, and
for a contact motion the contact points, forces, friction cones, support polygon, COM and ZMP.

The contact points are both feet's, as many per foot as the trajectory names (``contact_points``,
placed by :mod:`latentoc.plots.contact_points`); each has its force arrow and friction cone, shown while its
foot is on the ground and the point is loaded (``loaded``). A result with no ``point_forces`` has
each foot's wrench at its toe point.

:func:`build_scene` reads the result schema only (``trajectory.npz``, the problem's ``robot``
setting for the meshes) and samples the 1 kHz motion at ``rate_hz``; the arrays go into the page
as base64 little-endian float32 (:func:`b64`), decoded by ``js/page.js``.
"""
from __future__ import annotations

import base64
import hashlib
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.plots.forces import contact_series
from latentoc.plots.contact_points import MIRROR, contact_points_of, world_forces
from latentoc.plots.kinematics import floating_base, model_of
from latentoc.errors import ArgumentError
from latentoc.results import Result
from latentoc.viewer.geometry import Part, part_poses, robot_parts

__all__ = ["build_scene", "b64", "sample_indices", "contact_points", "FORCE_SCALE", "CONE_HEIGHT"]

FORCE_SCALE = 0.5  # arrow length in m of a force of one body weight
CONE_HEIGHT = 0.15  # m, the drawn friction cones' height


def b64(a: np.ndarray, dtype: str = "<f4") -> str:
    """An array's values as base64 of little-endian ``dtype`` (the page's typed arrays)."""
    return base64.b64encode(np.ascontiguousarray(np.asarray(a).astype(dtype)).tobytes()).decode("ascii")


def sample_indices(t: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of the samples nearest to t0, t0 + 1/rate, ..., the last sample included; the rate
    must be positive and finite, and is at most the motion's own (a faster one would repeat samples)."""
    t = np.asarray(t, dtype=float)
    own = (len(t) - 1) / (t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 1.0
    try:
        ok = not isinstance(rate_hz, bool) and math.isfinite(float(rate_hz)) and float(rate_hz) > 0
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ArgumentError(f"rate {rate_hz!r} Hz: must be a positive, finite number of frames per second of "
                            "motion time")
    rate_hz = min(float(rate_hz), own)
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz + 1e-9)) + 1) / rate_hz
    right = np.clip(np.searchsorted(t, grid), 1, len(t) - 1) if len(t) > 1 else np.zeros(len(grid), int)
    idx = right - (np.abs(grid - t[right - 1]) <= np.abs(t[right] - grid)) if len(t) > 1 else right
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


def contact_points(model: pin.Model, traj: Mapping[str, Any], Q: np.ndarray) -> np.ndarray:
    """World positions (n, 2 k, 3) of the left then the right foot's k contact points the trajectory
    names (:func:`latentoc.plots.contact_points.contact_points_of`) at the configurations Q."""
    return contact_points_of(model, traj).positions(model, Q)


def _at(traj: Mapping[str, Any], idx: np.ndarray) -> dict[str, Any]:
    """The trajectory's per-sample arrays at the indices ``idx``, the other entries as they are."""
    n = len(traj["t"])
    static = {"contact_points", "contact_frames", "tau_min", "tau_max"}  # never per sample, whatever n is
    return {k: (np.asarray(v)[idx] if np.ndim(v) and len(np.asarray(v)) == n and k not in static
                and not k.endswith("_offset") else v) for k, v in traj.items() if k != "model"}


def _contacts(model: pin.Model, traj: Mapping[str, Any], idx: np.ndarray) -> dict[str, Any]:
    """The contact layer at the sampled indices (module doc)."""
    sub = _at(traj, idx)
    n = len(idx)
    s = contact_series(model, sub)
    feet = contact_points_of(model, traj)
    k = feet.k
    contact = np.asarray(sub["contact"]).astype(bool)
    if "point_forces" in sub:  # each point's force; the right foot mirrors the left
        forces = world_forces(sub["point_forces"])
        loaded = np.asarray(sub["loaded"]).astype(bool) if "loaded" in sub else np.ones((n, k), bool)
        active = contact[:, None] & np.tile(loaded.reshape(n, k), (1, 2))
    else:  # one wrench per foot at its toe point
        W = np.asarray(sub["wrench"], dtype=float)
        j = feet.index("toe")
        j = k - 1 if j is None else j
        forces, active = np.zeros((n, 2 * k, 3)), np.zeros((n, 2 * k), bool)
        forces[:, j], forces[:, k + j] = W[:, :3], W[:, :3] * MIRROR
        active[:, [j, k + j]] = contact[:, None]
    weight = sum(i.mass for i in model.inertias) * float(-model.gravity.linear[2])
    zmp = np.where(np.isfinite(s["zmp"]), s["zmp"], 0.0)
    return {"names": feet.labels(), "points": b64(s["points"]), "forces": b64(forces * FORCE_SCALE / weight),
            "active": b64(active, "u1"), "polygon": b64(s["polygon"]), "corners": int(s["polygon"].shape[1]),
            "contact": b64(contact, "u1"), "com": b64(s["com"]), "zmp": b64(zmp),
            "mu": float(np.asarray(traj["friction"])) if "friction" in traj else 0.0, "cone_height": CONE_HEIGHT,
            "force_scale": FORCE_SCALE}


def _resampled_poses(model: pin.Model, parts: list, t_own: np.ndarray, Q: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Part poses of the motion ``Q`` (times ``t_own``) at the scene's times ``t``: each time's
    nearest sample (the last one beyond its end)."""
    near = np.abs(np.asarray(t_own, float)[None, :] - t[:, None]).argmin(axis=1)
    return part_poses(model, parts, np.asarray(Q, float)[near])


def build_scene(result: Result, rate_hz: float = 50.0, simulated: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The scene of ``result`` as JSON-ready data (module doc); ``simulated``: a replay of it
    (``simulation.npz``'s ``t`` from 0 and ``q``), shown beside the planned motion."""
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
        ghost = _resampled_poses(model, parts, t0, Q0, t[idx])
        motions["initial"] = b64(ghost)
        reach.append(ghost[..., :3].reshape(-1, 3))
    if simulated is not None:  # the replay's own times start at the motion's start
        sim = _resampled_poses(model, parts, np.asarray(simulated["t"], float) + t[0], simulated["q"], t[idx])
        motions["simulated"] = b64(sim)
        reach.append(sim[..., :3].reshape(-1, 3))
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
