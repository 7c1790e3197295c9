"""A demonstration retargeted to another robot: scaled keypoint IK, one solve per frame.

Each :class:`Keypoint` pairs a frame of the source model (the CMU humanoid's ``lfoot``) with a point
of the target robot (its ``left_ankle_roll_link``, with an offset in that frame). Per frame the
target's configuration minimises the weighted distances of its points to the source's, scaled by
``scale`` (world positions times ``scale``: a robot of 0.77 times the legs' length jumps 0.77 times
as far), and of the frames' orientations to the source's turned by their rest offset (the two
models' frames at their reference poses), with every bounded joint inside its limits. A keypoint
with a ``parent`` keypoint is placed from its parent's target along the source's segment between
the two, rescaled to the target's length of it at the reference poses (hips as wide as the robot's,
feet as long), so proportions that differ from the source's do not pull the robot off. A foot
keypoint (``height`` given) stands on the ground: its height is ``height`` plus the source's
scaled rise above its own reference height, and while the source foot rests (low and slow) the
target foot is planted: its position held at the stretch's mean on the ground and its orientation
flat. Each frame starts from the last one's solution and is polished without regularisation, so a
target that can match the source exactly does (the residual per keypoint is reported).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.intervals import runs
from latentoc.robots.point_kinematics import point_jacobian

__all__ = ["Keypoint", "Retargeted", "RetargetError", "retarget", "frame_id", "chain_scale", "resting"]

REGULARISATION = 1e-3  # weight (per rad or m) of a frame's change from the last frame, before polishing
PLANT_WEIGHT = 1000.0  # a planted foot's weight, times its own
GROUND_WEIGHT = 100.0  # per m a foot point is lower than its standing height


class RetargetError(LatentocError, ValueError):
    """A keypoint map that does not fit the two models, or a frame the target cannot follow."""


@dataclass(frozen=True)
class Keypoint:
    """A source frame mapped to a target frame's point (module doc); weights per m and per rad."""

    name: str
    source: str
    target: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # the point in the target frame, m
    weight: float = 1.0
    orientation: float = 0.0
    height: float | None = None  # a foot: the point's height above the ground when the foot stands flat, m
    parent: str | None = None  # a keypoint whose target this one's is relative to (its segment rescaled)


@dataclass
class Retargeted:
    """The target's motion and how closely it follows the source."""

    t: np.ndarray
    Q: np.ndarray  # N x nq of the target model
    scale: float
    residual_mm: dict[str, tuple[float, float]]  # keypoint -> (RMS, max) position residual, mm (weight > 0)
    residual_deg: dict[str, tuple[float, float]]  # keypoint -> (RMS, max) orientation residual, deg (orientation > 0)
    planted: dict[str, np.ndarray] = field(default_factory=dict)  # foot keypoint -> planted per frame
    at_limit: dict[str, float] = field(default_factory=dict)  # joint -> fraction of frames at a position limit
    too_fast: dict[str, float] = field(default_factory=dict)  # joint -> its largest speed over its URDF limit (> 1)

    def info(self) -> dict:
        return {"frames": int(len(self.t)), "scale": self.scale,
                "residual_mm": {k: {"rms": r, "max": m} for k, (r, m) in self.residual_mm.items()},
                "residual_deg": {k: {"rms": r, "max": m} for k, (r, m) in self.residual_deg.items()},
                "planted_frames": {k: int(v.sum()) for k, v in self.planted.items()}, "at_limit": self.at_limit,
                "too_fast": self.too_fast}


def frame_id(model: pin.Model, name: str, which: str) -> int:
    """The frame ``name`` of ``model`` (a body's frame first, then an operational one, then any)."""
    for kind in (pin.FrameType.BODY, pin.FrameType.OP_FRAME, pin.FrameType.FIXED_JOINT, pin.FrameType.JOINT):
        if model.existFrame(name, kind):
            return model.getFrameId(name, kind)
    raise RetargetError(f"{which}: the model {model.name!r} has no frame {name!r}")


def chain_scale(source: pin.Model, q_source: np.ndarray, target: pin.Model, q_target: np.ndarray,
                chain: list[Keypoint]) -> float:
    """Target over source length of the polyline through the keypoints of ``chain`` (hip, knee,
    ankle: the distances between joints on neighbouring bodies do not depend on the pose)."""
    ds, dt = source.createData(), target.createData()
    pin.framesForwardKinematics(source, ds, q_source)
    pin.framesForwardKinematics(target, dt, q_target)
    ps = [ds.oMf[frame_id(source, k.source, f"keypoints.{k.name}.source")].translation for k in chain]
    pt = [dt.oMf[frame_id(target, k.target, f"keypoints.{k.name}.target")].act(np.asarray(k.offset, float)) for k in chain]
    ls = sum(np.linalg.norm(b - a) for a, b in zip(ps, ps[1:]))
    lt = sum(np.linalg.norm(b - a) for a, b in zip(pt, pt[1:]))
    if ls <= 0:
        raise RetargetError("scale: the source keypoints of the scaling chain coincide")
    return float(lt / ls)


GAP = 0.05  # s: a shorter break between two resting stretches is capture noise, not a step


def resting(p: np.ndarray, t: np.ndarray, rise: float, speed: float) -> np.ndarray:
    """Frames at which a point (N x 3) is within ``rise`` of its lowest height and moves slower than
    ``speed`` horizontally (central differences); breaks shorter than ``GAP`` are closed."""
    v = np.gradient(p[:, :2], t, axis=0)
    on = (p[:, 2] - p[:, 2].min() <= rise) & (np.linalg.norm(v, axis=1) <= speed)
    stretches = runs(on)
    for (_, b), (a, _) in zip(stretches, stretches[1:]):
        if t[a] - t[b - 1] <= GAP + 1e-9:
            on[b:a] = True
    return on


def _yaw(R: np.ndarray) -> float:
    return float(np.arctan2(R[1, 0], R[0, 0]))


def _order(keypoints: list[Keypoint]) -> list[int]:
    """Keypoint indices with every parent before its children; a RetargetError for an unknown
    parent or a cycle."""
    index = {k.name: i for i, k in enumerate(keypoints)}
    for k in keypoints:
        if k.parent is not None and k.parent not in index:
            raise RetargetError(f"keypoints.{k.name}.parent: no keypoint named {k.parent!r}")
    order: list[int] = []
    while len(order) < len(keypoints):
        ready = [i for i, k in enumerate(keypoints) if i not in order and (k.parent is None or index[k.parent] in order)]
        if not ready:
            raise RetargetError("keypoints: the parents form a cycle")
        order += ready
    return order


def _targets(source: pin.Model, Q_src: np.ndarray, t: np.ndarray, keypoints: list[Keypoint], rest_src: np.ndarray,
             rest_tgt: list[pin.SE3], scale: float, rise: float, speed: float):
    """Per frame and keypoint the target position and rotation, and the planted frames of the feet."""
    d = source.createData()
    fids = [frame_id(source, k.source, f"keypoints.{k.name}.source") for k in keypoints]
    index = {k.name: i for i, k in enumerate(keypoints)}
    pin.framesForwardKinematics(source, d, rest_src)
    R_off = [d.oMf[f].rotation.T @ M.rotation for f, M in zip(fids, rest_tgt)]
    p_rest = np.array([d.oMf[f].translation for f in fids])
    t_rest = np.array([M.act(np.asarray(k.offset, float)) for k, M in zip(keypoints, rest_tgt)])
    n, K = len(Q_src), len(keypoints)
    S, R = np.zeros((n, K, 3)), np.zeros((n, K, 3, 3))
    for i, q in enumerate(Q_src):
        pin.framesForwardKinematics(source, d, q)
        for k, f in enumerate(fids):
            S[i, k] = d.oMf[f].translation
            R[i, k] = d.oMf[f].rotation @ R_off[k]
    P = np.zeros_like(S)
    planted = {}
    for k in _order(keypoints):
        kp = keypoints[k]
        if kp.parent is None:
            P[:, k] = scale * S[:, k]
        else:  # the parent's target plus the source's segment, at the target's length for it
            j = index[kp.parent]
            ls, lt = np.linalg.norm(p_rest[k] - p_rest[j]), np.linalg.norm(t_rest[k] - t_rest[j])
            P[:, k] = P[:, j] + (lt / ls if ls > 0 else scale) * (S[:, k] - S[:, j])
        if kp.height is None:
            continue
        P[:, k, 2] = kp.height + np.maximum(scale * (S[:, k, 2] - p_rest[k, 2]), 0.0)  # never into the ground
        on = resting(P[:, k], t, rise * scale, speed * scale)
        for a, b in runs(on):
            P[a:b, k, :2] = P[a:b, k, :2].mean(axis=0)
            P[a:b, k, 2] = kp.height
            yaw = float(np.mean([_yaw(Ri @ rest_tgt[k].rotation.T) for Ri in R[a:b, k]]))
            R[a:b, k] = pin.rpy.rpyToMatrix(0.0, 0.0, yaw) @ rest_tgt[k].rotation
        planted[kp.name] = on
    return P, R, planted


class _Frame:
    """One frame's weighted residuals and their Jacobian in the tangent step ``dv`` from ``q0``."""

    def __init__(self, model: pin.Model, keypoints: list[Keypoint], fids: list[int]):
        self.model, self.data, self.kps, self.fids = model, model.createData(), keypoints, fids
        self.offsets = [np.asarray(k.offset, float) for k in keypoints]

    def set(self, q0: np.ndarray, P: np.ndarray, R: np.ndarray, w: np.ndarray, wo: np.ndarray, reg: float) -> None:
        self.q0, self.P, self.R, self.w, self.wo, self.reg = q0, P, R, np.sqrt(w), np.sqrt(wo), np.sqrt(reg)

    def residuals(self, dv: np.ndarray) -> np.ndarray:
        q = pin.integrate(self.model, self.q0, dv)
        pin.framesForwardKinematics(self.model, self.data, q)
        out = []
        for k, f in enumerate(self.fids):
            M = self.data.oMf[f]
            out.append(self.w[k] * (M.act(self.offsets[k]) - self.P[k]))
            out.append(self.wo[k] * pin.log3(self.R[k].T @ M.rotation))
            if self.kps[k].height is not None:  # a foot point never below its standing height
                out.append([GROUND_WEIGHT * min(M.act(self.offsets[k])[2] - self.kps[k].height, 0.0)])
        out.append(self.reg * dv)
        return np.concatenate(out)

    def jacobian(self, dv: np.ndarray) -> np.ndarray:
        m = self.model
        q = pin.integrate(m, self.q0, dv)
        pin.computeJointJacobians(m, self.data, q)
        pin.updateFramePlacements(m, self.data)
        Jint = pin.dIntegrate(m, self.q0, dv, pin.ArgumentPosition.ARG1)
        rows = []
        for k, f in enumerate(self.fids):
            M = self.data.oMf[f]
            Jp = point_jacobian(m, self.data, f, M.act(self.offsets[k])) @ Jint
            rows.append(self.w[k] * Jp)
            Jl = pin.getFrameJacobian(m, self.data, f, pin.LOCAL)[3:]
            rows.append(self.wo[k] * pin.Jlog3(self.R[k].T @ M.rotation) @ Jl @ Jint)
            if self.kps[k].height is not None:
                below = M.act(self.offsets[k])[2] < self.kps[k].height
                rows.append(GROUND_WEIGHT * Jp[2:3] * below)
        rows.append(self.reg * np.eye(m.nv))
        return np.vstack(rows)


def _bounds(model: pin.Model, q0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the step ``dv`` that keep every bounded one-coordinate joint in its limits."""
    lo, hi = np.full(model.nv, -np.inf), np.full(model.nv, np.inf)
    for j in model.joints[1:]:
        if j.nq == 1 and j.nv == 1:
            a, b = model.lowerPositionLimit[j.idx_q], model.upperPositionLimit[j.idx_q]
            if np.isfinite(a) and np.isfinite(b) and a < b:
                lo[j.idx_v], hi[j.idx_v] = min(a - q0[j.idx_q], 0.0), max(b - q0[j.idx_q], 0.0)
    return lo, hi


def _solve(frame: _Frame, nv: int, lo: np.ndarray, hi: np.ndarray, iterations: int) -> np.ndarray:
    """Levenberg-Marquardt steps projected on the bounds ``lo <= dv <= hi``, from ``dv = 0``."""
    dv = np.zeros(nv)
    r = frame.residuals(dv)
    cost, lam = float(r @ r), 1e-6
    for _ in range(iterations):
        J = frame.jacobian(dv)
        g = J.T @ r
        while True:
            trial = np.clip(dv - np.linalg.solve(J.T @ J + lam * np.eye(nv), g), lo, hi)
            rt = frame.residuals(trial)
            ct = float(rt @ rt)
            if ct <= cost or lam > 1e8:
                break
            lam *= 10.0
        step = np.max(np.abs(trial - dv))
        if ct <= cost:
            dv, r, cost, lam = trial, rt, ct, max(lam / 10.0, 1e-12)
        if step < 1e-12 or cost < 1e-24:
            break
    return dv


def retarget(source: pin.Model, Q_src: np.ndarray, t: np.ndarray, target: pin.Model, keypoints: list[Keypoint], *,
             scale: float = 1.0, rest_source: np.ndarray | None = None, rest_target: np.ndarray | None = None,
             rise: float = 0.02, speed: float = 0.5) -> Retargeted:
    """The target's configurations that follow ``Q_src`` (module doc). ``rest_source`` and
    ``rest_target`` (default: the source's first frame, the target's neutral) are the poses whose
    frame orientations correspond; ``rise`` (m) and ``speed`` (m/s), in the source's units, say when
    a source foot rests."""
    if not keypoints:
        raise RetargetError("keypoints: none given")
    Q_src = np.asarray(Q_src, float)
    rest_src = Q_src[0] if rest_source is None else np.asarray(rest_source, float)
    q_rest = pin.neutral(target) if rest_target is None else np.asarray(rest_target, float)
    fids = [frame_id(target, k.target, f"keypoints.{k.name}.target") for k in keypoints]
    dt = target.createData()
    pin.framesForwardKinematics(target, dt, q_rest)
    rest_tgt = [dt.oMf[f].copy() for f in fids]
    P, R, planted = _targets(source, Q_src, t, keypoints, rest_src, rest_tgt, scale, rise, speed)
    w0 = np.array([k.weight for k in keypoints], float)
    wo = np.array([k.orientation for k in keypoints], float)
    frame = _Frame(target, keypoints, fids)
    Q = np.zeros((len(Q_src), target.nq))
    q = q_rest.copy()
    if target.joints[1].shortname() == "JointModelFreeFlyer":  # the base starts over the first targets
        q[:3] += (P[0] - np.array([M.translation for M in rest_tgt])).mean(axis=0)
    for i in range(len(Q_src)):
        w = w0 * np.array([PLANT_WEIGHT if planted.get(k.name, np.zeros(len(t), bool))[i] else 1.0 for k in keypoints])
        for reg in (REGULARISATION, 0.0):
            frame.set(q, P[i], R[i], w, wo, reg)
            q = pin.integrate(target, q, _solve(frame, target.nv, *_bounds(target, q), 100 if i == 0 else 20))
        Q[i] = q
    res, ang = np.zeros((len(Q), len(keypoints))), np.zeros((len(Q), len(keypoints)))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(target, dt, q)
        for k, f in enumerate(fids):
            res[i, k] = np.linalg.norm(dt.oMf[f].act(np.asarray(keypoints[k].offset, float)) - P[i, k])
            ang[i, k] = np.linalg.norm(pin.log3(R[i, k].T @ dt.oMf[f].rotation))

    at_limit = {}
    for j, name in zip(target.joints[1:], list(target.names)[1:]):
        if j.nq == 1:
            a, b = target.lowerPositionLimit[j.idx_q], target.upperPositionLimit[j.idx_q]
            hit = float(np.mean((Q[:, j.idx_q] <= a + 1e-6) | (Q[:, j.idx_q] >= b - 1e-6)))
            if hit > 0:
                at_limit[name] = hit

    too_fast = {}  # central differences of the joint angles against the URDF's velocity limits
    for j, name in zip(target.joints[1:], list(target.names)[1:]):
        vmax = float(target.velocityLimit[j.idx_v]) if j.nv == 1 else 0.0
        if j.nq == 1 and len(Q) > 1 and 0 < vmax < np.inf:
            speed = float(np.abs(np.gradient(Q[:, j.idx_q], t)).max())
            if speed > vmax:
                too_fast[name] = speed / vmax

    def rms_max(x: np.ndarray, unit: float) -> tuple[float, float]:
        return float(unit * np.sqrt(np.mean(x ** 2))), float(unit * x.max())

    return Retargeted(np.asarray(t, float), Q, scale,
                      {k.name: rms_max(res[:, j], 1e3) for j, k in enumerate(keypoints) if k.weight > 0},
                      {k.name: rms_max(ang[:, j], np.degrees(1.0)) for j, k in enumerate(keypoints) if k.orientation > 0},
                      planted, at_limit, too_fast)
