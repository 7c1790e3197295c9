"""The solved jump on a 1 kHz grid: q, v, a, torques and contact forces, for the numeric checks.

Joint motion from the GP layer along the optimal latent path, the base from the contact
phases' splines and, in flight, ballistic from the takeoff state with the pitch rate
integrated on the 1 kHz grid. Between the NLP's contact nodes the point forces are the edge
weights nearest the interpolated node forces that balance the sagittal base rows exactly,
unilateral and in their cones with the joint torques in their limits where such weights exist
(:func:`balanced_edge_weights`).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import minimize

from ..latent.gp_layer import GPLayer
from .base import base_to_freeflyer
from .contact import foot_points, generator_columns, point_forces, point_jacobians, toe_wrench
from .flight import ballistic_base, flight_functions
from .phases import Phases
from .robot import JumpRobot
from .solve import JumpSolution

__all__ = ["trajectory", "balanced_edge_weights"]

SAGITTAL = [0, 2, 4]


def trajectory(robot: JumpRobot, layer: GPLayer, phases: Phases, sol: JumpSolution, rate_hz: float = 1000.0) -> dict:
    """Arrays on a 1 kHz grid and at the contact nodes (module doc)."""
    nlp, ph = sol.nlp, phases
    parts = nlp.variables.unpack(sol.w)
    sp_, sps, spl = nlp.splines
    P = nlp.control_points(sol.w)
    model = robot.sym.model
    t = np.linspace(0.0, ph.duration, int(round(ph.duration * rate_hz)) + 1)
    X, Xd, Xdd = (sp_.evaluate(P, t, k) for k in range(3))
    m = layer.motion(np.hstack([X, Xd, Xdd]))
    sigma2 = layer.variance(X)[0]
    st, la = t <= ph.takeoff, t >= ph.touchdown
    fl = ~st & ~la
    B = [np.zeros((len(t), 3)) for _ in range(3)]
    for k in range(3):
        B[k][st] = sps.evaluate(parts["base_stance"], np.clip(t[st], 0, sps.duration), k)
        B[k][la] = spl.evaluate(parts["base_land"], np.clip(t[la] - ph.touchdown, 0, spl.duration), k)
    t_to = np.array([ph.takeoff])
    m_to = layer.motion(np.hstack([sp_.evaluate(P, t_to, k) for k in range(3)]))
    b_to = [sps.evaluate(parts["base_stance"], t_to, k).ravel() for k in range(2)]
    tau_f = np.concatenate([[0.0], t[fl] - ph.takeoff])
    Yf = [np.vstack([a[:1], b[fl]]).T for a, b in ((m_to.y, m.y), (m_to.yd, m.yd), (m_to.ydd, m.ydd))]
    bb = ballistic_base(flight_functions(robot.sym, robot.smap), *Yf, tau_f, b_to[0], b_to[1], m_to.y.T, m_to.yd.T)
    for k in range(3):
        B[k][fl] = bb[k].T[1:]
    q7, v6, a6 = base_to_freeflyer(*B)
    E = robot.E
    Q, V, A = (np.column_stack([b, y @ E.T]) for b, y in ((q7, m.y), (v6, m.yd), (a6, m.ydd)))

    # contact forces: node weights interpolated, then balanced (module doc)
    grid, W, mu = nlp.grid, robot.weight, robot.mu
    lam_nodes = parts["lam"].T  # 6 x contact nodes, body weights
    nS = len(grid["stance"])
    node_t = np.concatenate([grid["stance"], grid["land"]])
    lam_t = np.zeros((len(t), 6))
    for mask, cols, tn in ((st, slice(0, nS), grid["stance"]), (la, slice(nS, None), grid["land"])):
        for j in range(6):
            lam_t[mask, j] = np.interp(t[mask], tn, lam_nodes[j, cols])
    data = model.createData()
    tau = np.zeros((len(t), model.nv - 6))
    forces, wrench = np.zeros((len(t), 3, 2)), np.zeros((len(t), 6))
    correction, P_feet = np.zeros(len(t)), np.zeros((len(t), 3, 3))
    loaded = np.column_stack([ph.loaded(p, t) & (st | la) for p in ("heel", "ball", "toe")])
    for i in range(len(t)):
        full = pin.rnea(model, data, Q[i], V[i], A[i])
        if st[i] or la[i]:
            C = generator_columns(point_jacobians(model, data, Q[i], robot.geom), mu) * W
            lam_new = balanced_edge_weights(C, full, lam_t[i], np.repeat(loaded[i], 2), robot.limits.tau_min,
                                            robot.limits.tau_max)
            correction[i] = float(np.max(np.abs(lam_new - lam_t[i])))
            lam_t[i] = lam_new
            full = full - C @ lam_new
            forces[i] = np.array(point_forces(lam_new * W, mu))
            P_feet[i] = foot_points(model, data, robot.geom)
            wrench[i] = np.array(toe_wrench(lam_new * W, P_feet[i], mu)).ravel()
        tau[i] = full[6:]
    node_w = np.zeros((len(node_t), 6))
    for j, tj in enumerate(node_t):
        i = int(np.argmin(np.abs(t - tj)))
        node_w[j] = np.array(toe_wrench(lam_nodes[:, j] * W, P_feet[i], mu)).ravel()
    return {"t": t, "q": Q, "v": V, "a": A, "tau": tau, "wrench": wrench, "point_forces": forces,
            "point_lambda": lam_t, "force_correction": correction, "contact": (st | la).astype(np.int8),
            "loaded": loaded.astype(np.int8), "sigma2": sigma2, "latent": X, "control_points": P,
            "node_t": node_t, "node_wrench": node_w, "node_lambda": lam_nodes.T,
            "contact_frames": np.array(["lfoot", "lfoot_end", "ltoes_end", "rfoot", "rfoot_end", "rtoes_end"]),
            "contact_points": np.array(["heel", "ball", "toe"]), "heel_offset": robot.geom.heel_offset,
            "takeoff": ph.takeoff, "touchdown": ph.touchdown, "settle": ph.settle,
            "tau_min": robot.limits.tau_min, "tau_max": robot.limits.tau_max, "friction": mu,
            "model": model.saveToString()}


def balanced_edge_weights(C: np.ndarray, tau: np.ndarray, lam0: np.ndarray, free: np.ndarray,
                          tau_min: np.ndarray, tau_max: np.ndarray) -> np.ndarray:
    """Friction-pyramid edge weights nearest ``lam0`` whose generalized force ``C lam`` balances the
    sagittal base rows of ``tau = rnea(q, v, a)`` exactly: first with ``lam >= 0``, unloaded edges
    (``free`` False) zero and the joint torques in ``[tau_min, tau_max]``; then without the torque
    limits; last the least-norm change of the loaded edges (which may leave the cone)."""
    Cr, r = C[SAGITTAL], tau[SAGITTAL]
    scale = max(float(np.max(np.abs(Cr))), 1e-9)
    act = tau_max - tau_min > 1e-6
    Cj, tj = C[6:][act], tau[6:][act]
    x0 = np.clip(np.where(free, lam0, 0.0), 0.0, None)
    for with_torque in (True, False):
        cons = [{"type": "eq", "fun": lambda x: (Cr[:, free] @ x - r) / scale, "jac": lambda x: Cr[:, free] / scale}]
        if with_torque:
            lo, hi = tj - tau_max[act], tj - tau_min[act]
            cons.append({"type": "ineq", "fun": lambda x: np.concatenate([hi - Cj[:, free] @ x, Cj[:, free] @ x - lo]),
                         "jac": lambda x: np.vstack([-Cj[:, free], Cj[:, free]])})
        res = minimize(lambda x: float(np.sum((x - x0[free]) ** 2)), x0[free], jac=lambda x: 2 * (x - x0[free]),
                       bounds=[(0.0, None)] * int(free.sum()), constraints=cons, method="SLSQP",
                       options={"maxiter": 200, "ftol": 1e-12})
        x = np.maximum(res.x, 0.0)
        ok = np.max(np.abs(Cr[:, free] @ x - r)) <= 1e-8 * scale
        if with_torque:
            tq = tj - Cj[:, free] @ x
            ok = ok and np.all(tq >= tau_min[act] - 1e-6) and np.all(tq <= tau_max[act] + 1e-6)
        if res.success and ok:
            lam = np.zeros(6)
            lam[free] = x
            return lam
    lam = np.where(free, lam0, 0.0)
    lam[free] += np.linalg.lstsq(Cr[:, free], r - Cr @ lam, rcond=None)[0]
    return lam
