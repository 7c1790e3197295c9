"""Planted feet in a recorded motion: per-frame least-squares IK with the least joint change.

A captured foot that should stand still moves by about a centimetre (marker noise, skin motion),
and a model that learns the capture learns that motion. :func:`plant` changes only the chosen
joints, frame by frame, by the least amount (in the 2-norm) that puts each planted body exactly at
its target placement and holds the chosen joints at their values: an equality-constrained least
squares, solved by Gauss-Newton steps on the frame errors (``log6``), warm-started from the last
frame. Frames with nothing planted keep the capture's joints; the correction is tapered into them
(:func:`taper`) so the motion stays smooth where a plant ends.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.robots.point_kinematics import point_jacobian

__all__ = ["Plant", "PlantingError", "plant", "taper"]

TOLERANCE = 1e-10  # m and rad: the frame error at which a frame's IK stops
MAX_STEPS = 400


class PlantingError(LatentocError, ValueError):
    """A planted placement the free joints cannot reach."""


@dataclass(frozen=True)
class Plant:
    """Body frame ``frame`` at ``placement`` on the frames ``active`` (bool per frame); with ``point``
    (in the frame) only that point is held at ``placement``'s translation, the body may turn about it."""

    frame: str
    placement: pin.SE3
    active: np.ndarray
    point: np.ndarray | None = None


def plant(model: pin.Model, Q: np.ndarray, free_v: np.ndarray, plants: list[Plant],
          holds: dict[int, tuple[np.ndarray, np.ndarray]] | None = None,
          weights: np.ndarray | None = None) -> np.ndarray:
    """Configurations Q (n x nq) with each active plant's frame at its placement and each held
    1-DOF joint at its value (``holds``: v index -> (value per frame, active per frame)), changing
    only the velocity coordinates ``free_v`` (a free-flyer's among them), least in ``weights``
    (one per free coordinate, default 1: the norm of ``weights * change``)."""
    free_v = np.asarray(free_v, int)
    wts = np.ones(len(free_v)) if weights is None else np.asarray(weights, float)
    holds = holds or {}
    d = model.createData()
    out = np.array(Q, float)
    dv_prev = None
    for i in range(len(Q)):
        active = [p for p in plants if p.active[i]]
        held = {k: float(v[i]) for k, (v, on) in holds.items() if on[i]}
        if not active and not held:
            dv_prev = None
            continue
        q0 = out[i].copy()
        q = q0.copy() if dv_prev is None else pin.integrate(model, q0, dv_prev)  # warm: the last correction
        for k, v in held.items():
            q[k + model.nq - model.nv] = v
        cols = np.array([c for c in free_v if c not in held], int)
        w = wts[np.isin(free_v, cols)]
        e = np.zeros(0)
        for _ in range(MAX_STEPS):
            pin.computeJointJacobians(model, d, q)
            pin.updateFramePlacements(model, d)
            errs, jacs = [], []
            for p in active:
                fid = model.getFrameId(p.frame)
                if p.point is not None:  # the point's world position, its Jacobian in world axes
                    Mf = d.oMf[fid]
                    x = Mf.translation + Mf.rotation @ p.point
                    errs.append(x - p.placement.translation)
                    jacs.append(point_jacobian(model, d, fid, x)[:, cols])
                    continue
                M = p.placement.actInv(d.oMf[fid])
                errs.append(pin.log6(M).vector)
                jacs.append((pin.Jlog6(M) @ pin.getFrameJacobian(model, d, fid, pin.LOCAL))[:, cols])
            e = np.concatenate(errs) if errs else np.zeros(0)
            if not len(e) or np.max(np.abs(e)) < TOLERANCE:
                break
            J = np.vstack(jacs) / w
            back = w * pin.difference(model, q, q0)[cols]  # the way back to the capture, weighted
            # least change: back - J^+ (e + J back), the minimum-norm step onto the constraint's linearisation
            u = back - np.linalg.lstsq(J, e + J @ back, rcond=None)[0]
            dv = np.zeros(model.nv)
            dv[cols] = u / w
            q = pin.integrate(model, q, dv)
        else:
            raise PlantingError(f"frame {i}: the planted frames ({', '.join(p.frame for p in active)}) cannot be "
                                f"reached by the free joints (error {np.max(np.abs(e)):.2e} after {MAX_STEPS} steps)")
        out[i] = q
        dv_prev = np.zeros(model.nv)
        dv_prev[free_v] = pin.difference(model, q0, q)[free_v]
    return out


def taper(delta: np.ndarray, on: np.ndarray, t: np.ndarray, span: float) -> np.ndarray:
    """The corrections ``delta`` (n x k, zero where ``on`` is False) carried into the frames off
    each planted stretch with a smooth (C1) fade to zero over ``span`` seconds, so the corrected
    motion has no jump where a plant ends or begins."""
    out = np.array(delta, float)
    idx = np.flatnonzero(on)
    if not len(idx) or span <= 0:
        return out
    for i in np.flatnonzero(~on):
        before, after = idx[idx < i], idx[idx > i]
        total = np.zeros(out.shape[1])
        for j in ([before[-1]] if len(before) else []) + ([after[0]] if len(after) else []):
            s = abs(t[i] - t[j]) / span
            if s < 1:
                total += delta[j] * 0.5 * (1 + np.cos(np.pi * s))
        out[i] = total
    return out
