"""Post-check of a jump on a 1 kHz grid with numeric Pinocchio (issue 6 verification).

From exported arrays only (``t``, ``q``, ``v``, ``a``, ``wrench`` = the per-foot contact
wrench at the toe tip, world-aligned, on the 1 kHz grid, optionally ``point_forces`` (n, 3, 2):
the left heel, ball and toe (fx, fz), each acting on its own body, mirrored on the right
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
  (n, 3: whether the heel, ball and toe may carry force, the contact schedule) also
  ``cop_margin_loaded``, against the rearmost loaded point (the heel, else the ball, else a
  ``toe_pad`` behind the toe tip);
* ZMP from ``pinocchio.computeCentroidalMomentumTimeVariation`` (:mod:`.zmp`) and the
  projected COM against the support polygon (:mod:`.support_polygon`) during landing
  (COM once settled);
* joint torques ``rnea[6:] - (J^T w)[6:]`` against tau_min, tau_max (joints with a
  non-zero range; the others must vanish by symmetry);
* the tube: max sigma^2;
* ``eq33_feet_distance``: the paper's objective (Eq. 33), the integral over the motion of the
  ground-projected speed of both toe tips, ``|J_xy v|`` from the frame Jacobians (twice the jump
  distance only if the feet never move backwards or sideways);
* with point forces: ``max_point_cone_violation``, max over points of |fx| - mu fz (body weights);
* ``toe_slip``: the largest horizontal travel (max - min of x) of the toe tip within one contact
  phase (stance, landing), and ``max_toe_height``: its largest |z| in contact; both 0 for a
  toe pinned to the ground, at most ``foot_tolerance`` for the spline base;
* ``toe_displacement``: the toe tip's forward travel from the first to the last sample, the jump
  distance measured on the motion itself (the NLP's objective is its landing ground point x_L).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from .contact import TOE_PAD, FootGeometry, foot_points, point_jacobians
from .support_polygon import margin, support_polygon
from .training import RIGHT_TOE, TOE
from .zmp import G, zmp


def sagittal_contact_wrench(J_feet: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Per-foot wrench (6, world-aligned at the toe tip) the motion needs: the sagittal base
    rows of ``tau = rnea(q, v, a)`` solved for (fx, fz, my), with ``J_feet`` the sum of both
    toe tips' LOCAL_WORLD_ALIGNED frame Jacobians (the feet carry equal wrenches by symmetry)."""
    rows = [0, 2, 4]
    w = np.zeros(6)
    w[rows] = np.linalg.solve(J_feet.T[np.ix_(rows, rows)], tau[rows])
    return w


def verify(model: pin.Model, arrays: dict, mu: float = 0.4, toe_pad: float = TOE_PAD) -> dict:
    """Verification numbers (see module docstring)."""
    t, Q, V, A = (np.asarray(arrays[k]) for k in ("t", "q", "v", "a"))
    Wr, contact = np.asarray(arrays["wrench"]), np.asarray(arrays["contact"]).astype(bool)
    heel_off = np.asarray(arrays["heel_offset"])
    t_td, t_settle = float(arrays["touchdown"]), float(arrays["settle"])
    tmin, tmax = np.asarray(arrays["tau_min"]), np.asarray(arrays["tau_max"])
    d = model.createData()
    mass = sum(i.mass for i in model.inertias)
    W = mass * G
    ids = {n: model.getFrameId(n) for n in (TOE, RIGHT_TOE)}
    res_max, lat_max, tau_viol, sym_tau, flight_res = 0.0, 0.0, 0.0, 0.0, 0.0
    fz_min, ratio_max, cop_margin = np.inf, 0.0, np.inf
    zmp_margin, com_margin = np.inf, np.inf
    act = tmax - tmin > 1e-6
    points = np.asarray(arrays["point_forces"]) if "point_forces" in arrays else None
    geom, cone = FootGeometry(heel_off), 0.0
    loaded = np.asarray(arrays["loaded"]).astype(bool) if "loaded" in arrays else None
    cop_loaded = np.inf
    feet_speed = np.zeros(len(t))
    toe_xz = np.zeros((len(t), 2))
    for i in range(len(t)):
        q, v, a = Q[i], V[i], A[i]
        tau = pin.rnea(model, d, q, v, a)
        with_points = contact[i] and points is not None
        if with_points:  # places the frames and joint Jacobians too
            Jp = point_jacobians(model, d, q, geom)
        else:
            pin.computeJointJacobians(model, d, q)
            pin.framesForwardKinematics(model, d, q)
        JL = pin.getFrameJacobian(model, d, ids[TOE], pin.LOCAL_WORLD_ALIGNED)
        JR = pin.getFrameJacobian(model, d, ids[RIGHT_TOE], pin.LOCAL_WORLD_ALIGNED)
        feet_speed[i] = np.linalg.norm(JL[:2] @ v) + np.linalg.norm(JR[:2] @ v)  # ground-projected (Eq. 33)
        toe_xz[i] = d.oMf[ids[TOE]].translation[[0, 2]]
        if not contact[i]:
            gen = np.zeros(model.nv)
        elif with_points:  # each point force on its own body (heel, ball: foot; toe: toes)
            gen = sum(Jp[k].T @ np.array([points[i, k, 0], 0.0, points[i, k, 1]]) for k in range(3))
            cone = max(cone, float(np.max(np.abs(points[i, :, 0]) - mu * points[i, :, 1])) / W)
        else:
            gen = (JL + JR).T @ Wr[i]
        r = tau[:6] - gen[:6]
        res_max = max(res_max, float(np.max(np.abs(r))) / W)
        if not contact[i]:
            flight_res = max(flight_res, float(np.max(np.abs(r))) / W)
        lat_max = max(lat_max, float(np.max(np.abs(r[[1, 3, 5]]))) / W)
        tj = tau[6:] - gen[6:]
        tau_viol = max(tau_viol, float(np.max(np.maximum(tmin[act] - tj[act], 0) + np.maximum(tj[act] - tmax[act], 0))))
        sym_tau = max(sym_tau, float(np.max(np.abs(tj[~act]))) if (~act).any() else 0.0)
        if not contact[i]:
            continue
        # the wrench the motion needs: solve the sagittal base rows for (fx, fz, my)
        fx, _, fz, _, my, _ = sagittal_contact_wrench(JL + JR, tau)
        fz_min = min(fz_min, fz)
        ratio_max = max(ratio_max, abs(fx) / max(fz, 1e-9))
        heel, ball, toe = foot_points(model, d, geom).T
        cop = toe[0] - my / max(fz, 1e-9)
        cop_margin = min(cop_margin, min(cop - heel[0], toe[0] - cop))
        if loaded is not None:  # the rearmost loaded point: heel, ball or the toe pad
            back = heel[0] if loaded[i, 0] else (ball[0] if loaded[i, 1] else toe[0] - toe_pad)
            cop_loaded = min(cop_loaded, min(cop - back, toe[0] - cop))
        if t[i] >= t_td - 1e-9:
            pts = np.array([heel, toe, heel * [1, -1, 1], toe * [1, -1, 1]])
            As, bs = support_polygon(pts)
            c = pin.centerOfMass(model, d, q)
            dh = pin.computeCentroidalMomentumTimeVariation(model, d, q, v, a).vector
            zmp_margin = min(zmp_margin, margin(As, bs, np.array(zmp(c, dh, mass))))
            if t[i] >= t_settle - 1e-9:
                com_margin = min(com_margin, margin(As, bs, c))
    node_mis = 0.0
    if "node_wrench" in arrays and "node_t" in arrays:
        for tn, wn in zip(np.asarray(arrays["node_t"]), np.asarray(arrays["node_wrench"])):
            i = int(np.argmin(np.abs(t - tn)))
            if contact[i]:
                node_mis = max(node_mis, float(np.max(np.abs(wn - Wr[i]))) / W)
    out = {"max_dynamics_residual": res_max, "max_flight_residual": flight_res,
           "max_node_wrench_mismatch": node_mis, "max_lateral_residual": lat_max,
           "min_normal_force": float(fz_min), "max_friction_ratio": ratio_max, "cop_margin": float(cop_margin),
           "zmp_margin": float(zmp_margin), "com_margin": float(com_margin),
           "max_torque_violation": tau_viol, "max_point_cone_violation": cone, "max_symmetric_torque": sym_tau}
    # Eq. 33: the integral of the feet's ground-projected speed, both toe tips (trapezoid rule)
    out["eq33_feet_distance"] = float(np.sum(0.5 * (feet_speed[1:] + feet_speed[:-1]) * np.diff(t)))
    out["toe_displacement"] = float(toe_xz[-1, 0] - toe_xz[0, 0])
    out["toe_slip"], out["max_toe_height"] = 0.0, 0.0
    for phase in (contact & (t < t_td - 1e-9), contact & (t >= t_td - 1e-9)):
        if phase.any():
            out["toe_slip"] = max(out["toe_slip"], float(np.ptp(toe_xz[phase, 0])))
            out["max_toe_height"] = max(out["max_toe_height"], float(np.max(np.abs(toe_xz[phase, 1]))))
    if loaded is not None:
        out["cop_margin_loaded"] = float(cop_loaded)
    if "sigma2" in arrays:
        out["max_sigma2"] = float(np.max(arrays["sigma2"]))
    return out
