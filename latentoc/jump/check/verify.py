"""Post-check of a jump on a 1 kHz grid with numeric Pinocchio.

From exported arrays only (``t``, ``q``, ``v``, ``a``, ``wrench`` = the per-foot contact
wrench at the toe tip, world-aligned, on the 1 kHz grid, optionally ``point_forces`` (n, 4, 2):
the left heel, ball, toe and pad (fx, fz), each acting on its own body, mirrored on the right
foot, used instead of ``wrench`` for the generalized force; ``contact`` flag,
``tau_min``/``tau_max``, ``sigma2``, the heel offset and the landing/settle times):

* base-wrench residual: ``max |rnea(q, v, a)[:6] - sum_feet J^T w|`` over all 6 rows, as a
  fraction of body weight (``pinocchio.rnea``, frame Jacobians); in flight (w = 0) it is the
  ballistic error of the base, in contact it is nonzero only if the exported wrench is not
  the one the motion needs (the exporter solves it from the sagittal rows);
* ``max_node_wrench_mismatch``: the NLP's node wrenches (``node_t``, ``node_wrench``, from
  its force generators) against the needed wrench at the nearest sample, body weights;
* the wrench the motion *needs*: the 3 sagittal base rows solved for (fx, fz, my) of
  each (symmetric) foot; from it the minimum normal force, the maximum friction ratio
  |fx|/fz and the centre-of-pressure margin inside the foot (heel..toe); with ``loaded``
  (n, 4: whether the heel, ball, toe and pad may carry force, the contact schedule) also
  ``cop_margin_loaded``, against the rearmost loaded point (the heel, else the ball, else a
  ``toe_pad`` behind the toe tip);
* ZMP from ``pinocchio.computeCentroidalMomentumTimeVariation`` (:mod:`..robot.zmp`) and the
  projected COM against the support polygon (:mod:`latentoc.jump.robot.support_polygon`) during landing
  (COM once settled);
* joint torques ``rnea[6:] - (J^T w)[6:]`` against tau_min, tau_max (joints with a
  non-zero range; the others must vanish by symmetry);
* the tube: max sigma^2;
* ``eq33_feet_distance``: the paper's objective (Eq. 33), the integral over the motion of the
  ground-projected speed of both toe tips, ``|J_xy v|`` from the frame Jacobians (twice the jump
  distance only if the feet never move backwards or sideways);
* with point forces: ``max_point_cone_violation``, max over points of |fx| - mu fz (body weights);
* contact kinematics of the exported point forces' points (heel, ball, toe, pad; a point is
  *loaded* where its normal force exceeds :data:`LOADED` of body weight): ``max_loaded_travel``,
  the farthest any loaded point moves along the ground (x, y) from where its loaded stretch began,
  ``max_loaded_travel_x`` the same in x alone, ``max_loaded_height`` its largest |z|,
  ``min_unloaded_height`` the lowest any point goes in contact while it carries no load (the ground is
  z = 0), ``ground_work_positive`` and ``ground_work`` the positive and the net work of the contact
  forces on the body (both feet: the integral of sum f . v over the points, J): a fixed ground
  does none, friction on a sliding point can only take energy out;
* ``toe_displacement``: the toe tip's forward travel from the first to the last sample, the jump
  distance measured on the motion itself (the NLP's objective is its landing ground point x_L).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from latentoc.jump.robot.feet import MIRROR, POINTS, FootGeometry, foot_points, point_jacobians
from latentoc.intervals import runs
from latentoc.min_torque.limits import Limits
from latentoc.robots.point_kinematics import point_jacobian
from latentoc.jump.robot.support_polygon import feet_polygon
from latentoc.jump.robot.zmp import G, zmp

PAD_SETBACK = 0.01  # m: the pad's setback in results that do not record it (the CMU humanoid's)
LOADED = 0.01  # of body weight: a point pushing harder than this is loaded


TOE = POINTS.index("toe")


def _wrench_jacobian(model: pin.Model, d: pin.Data, frame_id: int, p: np.ndarray) -> np.ndarray:
    """(6, nv) Jacobian of the point ``p`` fixed to frame ``frame_id``'s body, world axes: a wrench
    about ``p`` (force, moment) acts on the joints through its transpose (placements and joint
    Jacobians computed)."""
    return np.vstack([point_jacobian(model, d, frame_id, p),
                      pin.getFrameJacobian(model, d, frame_id, pin.LOCAL_WORLD_ALIGNED)[3:]])


def sagittal_contact_wrench(J_feet: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Per-foot wrench (6, world-aligned at the toe tip) the motion needs: the sagittal base
    rows of ``tau = rnea(q, v, a)`` solved for (fx, fz, my), with ``J_feet`` the sum of both
    toe tips' LOCAL_WORLD_ALIGNED frame Jacobians (the feet carry equal wrenches by symmetry)."""
    rows = [0, 2, 4]
    w = np.zeros(6)
    w[rows] = np.linalg.solve(J_feet.T[np.ix_(rows, rows)], tau[rows])
    return w


def series(model: pin.Model, arrays: dict, mu: float = 0.4) -> dict[str, np.ndarray]:
    """The hard constraints' slack at every sample (negative: violated), and what :func:`verify`
    sums up (module doc): ``torque`` (n, joints with a range; N m to the nearer limit), ``normal``
    (needed fz, N), ``friction`` (mu fz - |fx|, N), ``cop`` (m inside the loaded support),
    ``point_cone`` (N, over the exported point forces), ``zmp`` and ``com`` (n, 4: m inside each
    edge of the support polygon, :func:`latentoc.jump.robot.support_polygon.feet_polygon`), each NaN where it does
    not apply (flight; ZMP before touchdown, COM before settling)."""
    t, Q, V, A = (np.asarray(arrays[k]) for k in ("t", "q", "v", "a"))
    Wr, contact = np.asarray(arrays["wrench"]), np.asarray(arrays["contact"]).astype(bool)
    t_td, t_settle = float(arrays["touchdown"]), float(arrays["settle"])
    tmin, tmax = np.asarray(arrays["tau_min"]), np.asarray(arrays["tau_max"])
    d = model.createData()
    mass = sum(i.mass for i in model.inertias)
    geom = FootGeometry.from_result(arrays)
    toe_frame = geom.points[TOE].frame
    ids = {side: model.getFrameId(geom.side_frame(side, toe_frame)) for side in "lr"}
    toe_pad = float(arrays.get("pad_setback", PAD_SETBACK))
    act = tmax - tmin > 1e-6
    points = np.asarray(arrays["point_forces"]) if "point_forces" in arrays else None
    loaded = np.asarray(arrays["loaded"]).astype(bool) if "loaded" in arrays else None
    n = len(t)
    nan = np.full(n, np.nan)
    out = {"torque": np.zeros((n, int(act.sum()))), "residual": np.zeros(n), "lateral": np.zeros(n),
           "symmetric_torque": np.zeros(n), "feet_speed": np.zeros(n), "toe_xz": np.zeros((n, 2)),
           "points": np.full((n, len(POINTS), 3), np.nan), "point_velocity": np.full((n, len(POINTS), 3), np.nan),
           **{k: nan.copy() for k in ("normal", "friction", "cop", "cop_loaded", "point_cone")},
           "zmp": np.full((n, 4), np.nan), "com": np.full((n, 4), np.nan)}
    for i in range(n):
        q, v, a = Q[i], V[i], A[i]
        tau = pin.rnea(model, d, q, v, a)
        with_points = contact[i] and points is not None
        if with_points:  # places the frames and joint Jacobians too
            Jp = point_jacobians(model, d, q, geom)
        else:
            pin.computeJointJacobians(model, d, q)
            pin.framesForwardKinematics(model, d, q)
        toe = foot_points(model, d, geom)[:, TOE]
        JL, JR = (_wrench_jacobian(model, d, ids[side], p) for side, p in (("l", toe), ("r", MIRROR @ toe)))
        out["feet_speed"][i] = np.linalg.norm(JL[:2] @ v) + np.linalg.norm(JR[:2] @ v)  # ground-projected (Eq. 33)
        out["toe_xz"][i] = toe[[0, 2]]
        if contact[i]:
            out["points"][i], out["point_velocity"][i] = _left_points(model, d, geom, v)
        gen: np.ndarray
        if not contact[i]:
            gen = np.zeros(model.nv)
        elif with_points and points is not None:  # each point force on its own body (heel, ball: foot; toe: toes)
            gen = np.sum([Jp[k].T @ np.array([points[i, k, 0], 0.0, points[i, k, 1]]) for k in range(len(Jp))], axis=0)
            cone = mu * points[i, :, 1] - np.abs(points[i, :, 0])  # of the loaded points (the others carry 0)
            out["point_cone"][i] = float(np.min(cone[loaded[i]] if loaded is not None and loaded[i].any() else cone))
        else:
            gen = (JL + JR).T @ Wr[i]
        r = tau[:6] - gen[:6]
        out["residual"][i] = float(np.max(np.abs(r)))
        out["lateral"][i] = float(np.max(np.abs(r[[1, 3, 5]])))
        tj = tau[6:] - gen[6:]
        out["torque"][i] = np.minimum(tj[act] - tmin[act], tmax[act] - tj[act])
        out["symmetric_torque"][i] = float(np.max(np.abs(tj[~act]))) if (~act).any() else 0.0
        if not contact[i]:
            continue
        # the wrench the motion needs: solve the sagittal base rows for (fx, fz, my)
        fx, _, fz, _, my, _ = sagittal_contact_wrench(JL + JR, tau)
        out["normal"][i], out["friction"][i] = fz, mu * fz - abs(fx)
        heel, ball, toe, _ = foot_points(model, d, geom).T
        cop = toe[0] - (my + toe[2] * fx) / max(fz, 1e-9)  # on the ground, below the toe tip
        out["cop"][i] = min(cop - heel[0], toe[0] - cop)
        if loaded is not None:  # the rearmost loaded point: heel, ball or the toe pad
            back = heel[0] if loaded[i, 0] else (ball[0] if loaded[i, 1] else toe[0] - toe_pad)
            out["cop_loaded"][i] = min(cop - back, toe[0] - cop)
        if t[i] >= t_td - 1e-9:
            As, bs = feet_polygon(heel, toe)
            c = pin.centerOfMass(model, d, q)
            dh = pin.computeCentroidalMomentumTimeVariation(model, d, q, v, a).vector
            out["zmp"][i] = -(As @ np.array(zmp(c, dh, mass)) + bs)
            if t[i] >= t_settle - 1e-9:
                out["com"][i] = -(As @ c[:2] + bs)
    return out


def _left_points(model: pin.Model, d: pin.Data, geom: FootGeometry, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World positions (4 x 3) and velocities of the left foot's points (frames and joint Jacobians placed)."""
    P = foot_points(model, d, geom).T
    V = np.zeros_like(P)
    for k, c in enumerate(geom.points):
        V[k] = point_jacobian(model, d, model.getFrameId(c.frame), P[k]) @ v
    return P, V


def contact_kinematics(t: np.ndarray, points: np.ndarray, velocity: np.ndarray, forces: np.ndarray, contact: np.ndarray,
                       weight: float) -> dict[str, float]:
    """Where the loaded points are and how they move, and the work the ground does (module doc).
    ``points``, ``velocity``: (n, 4, 3) of the left foot (used in contact only); ``forces``: (n, 4, 2) its (fx, fz)."""
    loaded = (forces[:, :, 1] > LOADED * weight) & contact[:, None]
    points, velocity = np.where(contact[:, None, None], points, 0.0), np.where(contact[:, None, None], velocity, 0.0)
    travel = travel_x = height = 0.0
    for k in range(points.shape[1]):
        on = loaded[:, k]
        for a, b in runs(on):  # each loaded stretch
            d = points[a:b, k, :2] - points[a, k, :2]
            travel = max(travel, float(np.max(np.linalg.norm(d, axis=1))))
            travel_x = max(travel_x, float(np.max(np.abs(d[:, 0]))))
        if on.any():
            height = max(height, float(np.max(np.abs(points[on, k, 2]))))
    free = ~loaded & contact[:, None]
    power = 2.0 * np.sum(forces[:, :, 0] * velocity[:, :, 0] + forces[:, :, 1] * velocity[:, :, 2], axis=1)  # both feet
    dt = np.diff(t)

    def integral(p: np.ndarray) -> float:  # trapezoid rule
        return float(np.sum(0.5 * (p[1:] + p[:-1]) * dt))

    return {"max_loaded_travel": travel, "max_loaded_travel_x": travel_x, "max_loaded_height": height,
            "min_unloaded_height": float(np.min(points[:, :, 2][free])) if free.any() else np.inf,
            "ground_work_positive": integral(np.maximum(power, 0.0)), "ground_work": integral(power)}


def joint_limit_excess(arrays: dict) -> tuple[float, float]:
    """How far the motion goes beyond the joint position limits (rad) and velocity limits (rad/s) the
    result records as held (``q_min``, ``q_max``, ``v_max``; none recorded: 0) at its worst sample."""
    if "q_min" not in arrays:
        return 0.0, 0.0
    held = Limits(*(np.asarray(arrays[k], float) for k in ("q_min", "q_max", "v_max")))
    out = held.violations({k: np.asarray(arrays[k]) for k in ("q", "v")})
    return out["joint_limits_rad"], out["velocity_limits_rad_s"]


def _min(x: np.ndarray) -> float:
    return float(np.nanmin(x)) if np.isfinite(x).any() else np.inf


def verify(model: pin.Model, arrays: dict, mu: float = 0.4,
           checked: dict[str, np.ndarray] | None = None) -> dict:
    """Verification numbers (module doc); ``checked``: :func:`series` of the same arrays, if made."""
    sr = series(model, arrays, mu) if checked is None else checked
    t = np.asarray(arrays["t"])
    contact = np.asarray(arrays["contact"]).astype(bool)
    W = sum(i.mass for i in model.inertias) * G
    fz_min = _min(sr["normal"])
    out = {"max_dynamics_residual": float(sr["residual"].max(initial=0.0)) / W,
           "max_flight_residual": float(sr["residual"][~contact].max(initial=0.0)) / W,
           "max_lateral_residual": float(sr["lateral"].max(initial=0.0)) / W,
           "min_normal_force": fz_min,
           "max_friction_ratio": float(np.nanmax(np.where(contact, mu - sr["friction"] / np.maximum(sr["normal"], 1e-9),
                                                          -np.inf), initial=0.0)),
           "cop_margin": _min(sr["cop"]), "zmp_margin": _min(sr["zmp"]), "com_margin": _min(sr["com"]),
           "max_torque_violation": float(max(0.0, -sr["torque"].min(initial=0.0))),
           "max_point_cone_violation": float(max(0.0, -_min(sr["point_cone"]))) / W if np.isfinite(sr["point_cone"]).any() else 0.0,
           "max_symmetric_torque": float(sr["symmetric_torque"].max(initial=0.0))}
    out["max_joint_limit_violation"], out["max_velocity_violation"] = joint_limit_excess(arrays)
    Wr = np.asarray(arrays["wrench"])
    node_mis = 0.0
    if "node_wrench" in arrays and "node_t" in arrays:
        for tn, wn in zip(np.asarray(arrays["node_t"]), np.asarray(arrays["node_wrench"])):
            i = int(np.argmin(np.abs(t - tn)))
            if contact[i]:
                node_mis = max(node_mis, float(np.max(np.abs(wn - Wr[i]))) / W)
    out["max_node_wrench_mismatch"] = node_mis
    # Eq. 33: the integral of the feet's ground-projected speed, both toe tips (trapezoid rule)
    fs, toe_xz = sr["feet_speed"], sr["toe_xz"]
    out["eq33_feet_distance"] = float(np.sum(0.5 * (fs[1:] + fs[:-1]) * np.diff(t)))
    out["toe_displacement"] = float(toe_xz[-1, 0] - toe_xz[0, 0])
    if "point_forces" in arrays:
        out.update(contact_kinematics(t, sr["points"], sr["point_velocity"], np.asarray(arrays["point_forces"]),
                                      contact, W))
    if "loaded" in arrays:
        out["cop_margin_loaded"] = _min(sr["cop_loaded"])
    if "sigma2" in arrays:
        out["max_sigma2"] = float(np.max(arrays["sigma2"]))
    return out
