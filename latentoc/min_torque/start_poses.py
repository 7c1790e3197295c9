"""New start poses (Kang & Park 2015, Sect. 4.1.4, Fig. 4-5).

The starting latent point x_0 of the training path is moved in a radial direction of the
tube (orthogonal to the path tangent) until sigma^2(x) = delta; the pose mu_Q(x_delta)
is reconstructed and its end-effector placement (p_delta, R_delta) compared with the
start's (p_0, R_0)::

    translational distance = |p_0 - p_delta|                              (Eq. 31)
    pose distance          = |log(R_0^T R_delta)| + |p_0 - p_delta|       (Eq. 32)

Radial direction: the normal of the path at x_0 lying in the plane of the latent path's
two principal directions (the learned paths are nearly planar), pointing away from the
path's centroid; ``direction`` overrides it.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import pinocchio as pin

from latentoc.errors import SolveError

from latentoc.gpdm import GPDM

__all__ = ["radial_direction", "tube_boundary_point", "start_pose_distances"]


def radial_direction(gpdm: GPDM) -> np.ndarray:
    """Unit vector at the path start, orthogonal to the tangent (see module doc)."""
    X = gpdm.latent_trajectories()[0]
    x0 = X[0]
    k = min(len(X) - 1, max(1, len(X) // 20))
    tangent = X[k] - x0
    tangent /= np.linalg.norm(tangent)
    _, _, Vt = np.linalg.svd(X - X.mean(axis=0), full_matrices=False)
    plane = Vt[:2] if X.shape[1] > 1 else Vt[:1]
    best = None
    for v in plane:
        n = v - tangent * (v @ tangent)
        if best is None or np.linalg.norm(n) > np.linalg.norm(best):
            best = n
    if best is None or np.linalg.norm(best) < 1e-9:
        best = np.eye(X.shape[1])[np.argmin(np.abs(tangent))] - tangent * tangent[np.argmin(np.abs(tangent))]
    n = best / np.linalg.norm(best)
    if n @ (x0 - X.mean(axis=0)) < 0:
        n = -n
    return n


def tube_boundary_point(gpdm: GPDM, x0: np.ndarray, direction: np.ndarray, delta: float,
                        step: float = 1e-3, max_distance: float = 10.0) -> tuple[np.ndarray, float]:
    """First point x0 + r u (r >= 0) with sigma^2 = delta (march, then bisect); returns (x, r)."""
    u = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    if gpdm.variance(x0) >= delta:
        return np.asarray(x0, dtype=float), 0.0
    r_lo, r = 0.0, step
    while r <= max_distance:
        if gpdm.variance(x0 + r * u) >= delta:
            break
        r_lo, r = r, r + step
    else:
        raise SolveError(f"tube {delta:g}: sigma^2 stays below it within distance {max_distance} of the start "
                         f"(sigma^2 <= {gpdm.variance(x0 + max_distance * u):.4g} there, its limit b1 + 1/b3)")
    lo, hi = r_lo, r
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gpdm.variance(x0 + mid * u) < delta else (lo, mid)
    return x0 + hi * u, hi


def start_pose_distances(gpdm: GPDM, model: pin.Model, frame: str, deltas: Sequence[float],
                         direction: np.ndarray | None = None) -> list[dict[str, Any]]:
    """For each delta: latent distance, translational (Eq. 31) and pose (Eq. 32) distances."""
    if not model.existFrame(frame):
        raise ValueError(f"model {model.name!r} has no frame {frame!r}")
    fid = model.getFrameId(frame)
    data = model.createData()

    def placement(q: np.ndarray) -> pin.SE3:
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[fid].copy()

    x0 = gpdm.latent_trajectories()[0][0]
    u = radial_direction(gpdm) if direction is None else np.asarray(direction, dtype=float)
    M0 = placement(gpdm.mean(x0))
    rows = []
    for delta in deltas:
        x, r = tube_boundary_point(gpdm, x0, u, float(delta))
        q = gpdm.mean(x)
        M = placement(q)
        trans = float(np.linalg.norm(M0.translation - M.translation))
        rot = float(np.linalg.norm(pin.log3(M0.rotation.T @ M.rotation)))
        rows.append({"tube": float(delta), "latent_distance": float(r), "translational_distance": trans,
                     "rotation_distance": rot, "pose_distance": rot + trans, "q": q.tolist(), "x": x.tolist()})
    return rows
