"""The solved jump on a 1 kHz grid: q, v, a, torques and contact forces, for the numeric checks.

Joint motion from the GP layer along the optimal latent path (or the joint path itself, the
identity layer: then no latent path and no sigma^2), in the contact phases with the legs closed
and the base from the planted body (:mod:`..closure.planted_legs`) and, in flight, ballistic from the takeoff
state with the pitch rate integrated on the 1 kHz grid. The point forces are the NLP's edge weights at its contact nodes
and samples (the wrench split is part of the solution there); between them, the edge weights
interpolated and corrected to the non-negative weights nearest them that balance the sagittal base
rows (:func:`corrected_edge_weights`). The exchange (:mod:`..solve.exchange`) adds a contact sample wherever
this split does not hold the cones or the torque limits.
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import nnls

from latentoc.latent.gp_layer import Layer
from latentoc.latent.residual_layer import ResidualLayer
from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.robot.feet import EDGES, POINTS, FootGeometry, foot_points, generator_columns, point_forces, point_jacobians, toe_wrench
from latentoc.jump.closure.ballistic import ballistic_base, flight_functions
from latentoc.jump.transcription.nlp import JumpNLP
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.solve.initial_point import takeoff_state

__all__ = ["trajectory", "contact_geometry", "corrected_edge_weights"]

SAGITTAL = [0, 2, 4]


def trajectory(robot: JumpRobot, layer: Layer, phases: Phases, nlp: JumpNLP, w: np.ndarray,
               rate_hz: float = 1000.0) -> dict:
    """Arrays of solution ``w`` of ``nlp`` on a 1 kHz grid and at the contact nodes (module doc)."""
    ph = phases
    parts = nlp.variables.unpack(w)
    P = nlp.control_points(w)
    model = robot.sym.model
    t = np.linspace(0.0, ph.duration, int(round(ph.duration * rate_hz)) + 1)
    X, Xd, Xdd = (nlp.spline.evaluate(P, t, k) for k in range(3))
    m = layer.motion(np.hstack([X, Xd, Xdd]))
    d = layer.latent_coordinates  # a leg residual's path: the latent coordinates first, then the residual
    path = {"sigma2": layer.variance(X)[0], "latent": X[:, :d]} if layer.has_tube else {}
    if isinstance(layer, ResidualLayer):
        path.update(leg_residual=X[:, d:], leg_residual_control_points=P[:, d:], leg_residual_joints=layer.joints)
    st, la = ph.standing(t), ph.landed(t)
    fl = ~st & ~la
    Y, Yd, Ydd = m.y.copy(), m.yd.copy(), m.ydd.copy()
    B = [np.zeros((len(t), 3)) for _ in range(3)]
    assert robot.closure is not None
    con = st | la
    shift = robot.geom.planted_shift(la[con], float(parts["x_L"][0]))
    Y[con], Yd[con], Ydd[con], B[0][con], B[1][con], B[2][con] = robot.closure.evaluate(
        m.y[con], m.yd[con], m.ydd[con], ph.held(t[con]), shift)
    y_to, yd_to, b_to, bd_to = takeoff_state(robot, layer, nlp.spline, P, ph)
    tau_f = np.concatenate([[0.0], t[fl] - ph.takeoff])
    Yf = [np.hstack([a, b[fl].T]) for a, b in ((y_to, m.y), (yd_to, m.yd), (np.zeros_like(y_to), m.ydd))]
    bb = ballistic_base(flight_functions(robot.sym, robot.smap), Yf[0], Yf[1], Yf[2], tau_f, b_to, bd_to, y_to, yd_to)
    for k in range(3):
        B[k][fl] = bb[k].T[1:]
    q7, v6, a6 = base_to_freeflyer(*B)
    E = robot.E
    Q, V, A = (np.column_stack([b, y @ E.T]) for b, y in ((q7, Y), (v6, Yd), (a6, Ydd)))

    # contact forces: the NLP's edge weights at its nodes and samples, balanced between them (module doc)
    grid, W, mu = nlp.grid, robot.weight, robot.mu
    lam_nodes = parts["lam"]  # contact nodes x 6, body weights
    node_t = np.concatenate([grid["stance"], grid["land"]])
    knot_t = np.concatenate([node_t, nlp.selection.contact])
    knot_lam = np.vstack([lam_nodes, parts["lam_sample"]])
    order = np.argsort(knot_t, kind="stable")
    knot_t, knot_lam = knot_t[order], knot_lam[order]
    lam_t = np.zeros((len(t), EDGES))
    on_knot = np.zeros(len(t), bool)
    for mask, inside in ((st, ph.standing(knot_t)), (la, ph.landed(knot_t))):
        for j in range(EDGES):
            lam_t[mask, j] = np.interp(t[mask], knot_t[inside], knot_lam[inside, j])
        near = np.abs(t[mask, None] - knot_t[inside][None, :]) < 1e-7
        on_knot[np.flatnonzero(mask)[near.any(axis=1)]] = True
    data = model.createData()
    tau = np.zeros((len(t), model.nv - 6))
    forces, wrench = np.zeros((len(t), len(POINTS), 2)), np.zeros((len(t), 6))
    correction, P_feet = np.zeros(len(t)), np.zeros((len(t), 3, len(POINTS)))
    loaded = np.column_stack([ph.loaded(p, t) & (st | la) for p in POINTS])
    for i in range(len(t)):
        full = pin.rnea(model, data, Q[i], V[i], A[i])
        if st[i] or la[i]:
            C = generator_columns(point_jacobians(model, data, Q[i], robot.geom), mu) * W
            free = np.repeat(loaded[i], 2)
            lam_new = lam_t[i] if on_knot[i] else corrected_edge_weights(C, full, lam_t[i], free)
            correction[i] = float(np.max(np.abs(lam_new - lam_t[i])))
            lam_t[i] = lam_new
            full = full - C @ lam_new
            forces[i] = np.array(point_forces(lam_new * W, mu))
            P_feet[i] = foot_points(model, data, robot.geom)
            wrench[i] = np.array(toe_wrench(lam_new * W, P_feet[i], mu)).ravel()
        tau[i] = full[6:]
    lam_nodes = lam_nodes.T
    node_w = np.zeros((len(node_t), 6))
    for j, tj in enumerate(node_t):
        i = int(np.argmin(np.abs(t - tj)))
        node_w[j] = np.array(toe_wrench(lam_nodes[:, j] * W, P_feet[i], mu)).ravel()
    return {"t": t, "q": Q, "v": V, "a": A, "tau": tau, "wrench": wrench, "point_forces": forces,
            "point_lambda": lam_t, "force_correction": correction, "contact": (st | la).astype(np.int8),
            "loaded": loaded.astype(np.int8), **path, "control_points": P[:, :d],
            "node_t": node_t, "node_wrench": node_w, "node_lambda": lam_nodes.T,
            **contact_geometry(robot.geom),
            "takeoff": ph.takeoff, "touchdown": ph.touchdown, "settle": ph.settle,
            "tau_min": robot.limits.tau_min, "tau_max": robot.limits.tau_max, "friction": mu,
            "model": model.saveToString(), **(robot.model_limits.arrays() if robot.has_joint_limits else {})}


def contact_geometry(geom: FootGeometry) -> dict[str, np.ndarray]:
    """The result's foot: the frames of the heel, ball and toe tip (the pad shares the toe tip's),
    left then right, each point's offset in its frame and the pad's setback."""
    left = [geom.points[POINTS.index(p)].frame for p in ("heel", "ball", "toe")]
    return {"contact_frames": np.array(left + [geom.side_frame("r", f) for f in left]),
            "contact_points": np.array(POINTS), **{f"{p}_offset": geom.offset(p) for p in POINTS},
            "pad_setback": np.array(geom.pad_setback)}


def corrected_edge_weights(C: np.ndarray, tau: np.ndarray, lam0: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The non-negative edge weights nearest ``lam0`` on the loaded (``free``) edges that balance the
    sagittal base rows of ``tau = rnea(q, v, a)`` with the generalized forces ``C`` of the edges
    (nv x 8); the unloaded edges zero. Least squares with the rows weighted 1e6 over the distance
    (scipy's NNLS), then their remainder corrected least norm on the edges that carry force."""
    lam = np.zeros_like(lam0)
    Cr, r = C[SAGITTAL][:, free], tau[SAGITTAL]
    scale = np.maximum(np.linalg.norm(Cr, axis=1), 1e-12)[:, None]
    A = np.vstack([1e6 * Cr / scale, np.eye(int(free.sum()))])
    x = nnls(A, np.concatenate([1e6 * r / scale[:, 0], np.clip(lam0[free], 0.0, None)]), maxiter=200)[0]
    on = x > 0
    if on.any():
        x[on] += np.linalg.lstsq(Cr[:, on], r - Cr @ x, rcond=None)[0]
    lam[free] = x
    return lam
