"""Full configuration-space baseline (Kang & Park 2015, Sect. 4.1.1, Table 2 right).

The joint angles themselves are a B-spline q(t, P) = sum_i p_i B_i(t) (Eq. 5) with m
control points per joint, the same boundary handling as the latent problem (fixed
p_1, p_m, and for "rest" also p_2, p_(m-1)), the same objective (Eq. 4, L = |tau|^2
with Gauss-Legendre quadrature) and joint/torque limits. Every free control point is
limited to +-k degrees around its value in the spline fit of the training motion (the
"joint range" of Table 2).

Derivatives (``settings.structured_derivatives``, default, without torque limits): the same
treatment as the latent NLP, so the comparison is fair: the objective's gradient and
Hessian come from the compiled per-node |tau|^2 derivatives
(:func:`latentoc.latent_motion.node_derivative_functions`) through the constant map from
w to u = (q, v, a) at the quadrature nodes; the joint-limit rows are linear in w.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .dynamics import SymbolicModel
from .latent_motion import joint_node_function, node_derivative_functions
from .spline import BSpline
from .transcription import (SplineNLP, TranscriptionSettings, _lifted_constraints, _lifted_derivatives,
                            _symbolic_control_points,
                            constraint_times, fit_control_points, fixed_rows,
                            gauss_legendre_nodes, node_objective_functions, torque_limit_vector)

__all__ = ["build_joint_nlp", "joint_motion"]


def build_joint_nlp(model: SymbolicModel, settings: TranscriptionSettings, t_train: np.ndarray,
                    Q_train: np.ndarray, joint_range_deg: float) -> SplineNLP:
    """Transcribe Eq. 4 over joint-space control points limited to +-joint_range_deg."""
    n = model.nq
    spline = BSpline(settings.control_points, settings.duration, settings.spline_degree)
    P_init = fit_control_points(spline, t_train, Q_train, settings.boundary)
    fixed = fixed_rows(spline.n_control, settings.boundary)
    free = np.array([i for i in range(spline.n_control) if i not in fixed], dtype=int)
    w = ca.MX.sym("w", len(free) * n)
    P = _symbolic_control_points(w, P_init, free)
    Pt = P.T
    quad_t, quad_w = gauss_legendre_nodes(spline, settings.quadrature_points)
    B = [ca.DM(spline.basis(quad_t, r).T) for r in (0, 1, 2)]
    node = joint_node_function(model).map(len(quad_t))
    Uw = [ca.mtimes(Pt, Br) for Br in B]
    L, tau = node(*Uw)
    J = ca.mtimes(L, ca.DM(quad_w))
    grid_t = constraint_times(spline, settings.constraint_points)
    g, lbg, ubg = [], [], []
    if settings.joint_limits:
        Qg = ca.mtimes(Pt, ca.DM(spline.basis(grid_t).T))
        g.append(ca.vec(Qg))
        lbg.append(np.tile(np.asarray(model.model.lowerPositionLimit), len(grid_t)))
        ubg.append(np.tile(np.asarray(model.model.upperPositionLimit), len(grid_t)))
    tmax = torque_limit_vector(settings.torque_limits, model.nv)
    if tmax is not None:
        g.append(ca.vec(tau))
        lbg.append(np.tile(-tmax, len(quad_t)))
        ubg.append(np.tile(tmax, len(quad_t)))
    w0 = P_init[free].ravel()
    k = np.radians(float(joint_range_deg))
    nlp = {"x": w, "f": J, "g": ca.vertcat(*g) if g else ca.MX(0, 1)}
    derivatives = None
    if settings.structured_derivatives and tmax is None and settings.joint_limits:
        U = ca.MX.sym("U", 3 * n, len(quad_t))
        f_grad, f_hess = node_objective_functions(ca.vec(U), U, quad_w,
                                                  node_derivative_functions(model, jit=settings.jit), lifted=False)
        x, lam_g = ca.MX.sym("Qg", g[0].shape[0]), ca.MX.sym("lam_g", g[0].shape[0])
        rows = _lifted_constraints(w, g[0], x, x, lam_g)
        derivatives = _lifted_derivatives(w, ca.vec(ca.vertcat(*Uw)), ca.vec(U), f_grad, f_hess, rows, lam_g)
        nlp["derivatives"] = derivatives
    return SplineNLP(spline=spline, free=free, P_init=P_init, nlp=nlp, derivatives=derivatives,
                     lbx=w0 - k, ubx=w0 + k,
                     lbg=np.concatenate(lbg) if lbg else np.zeros(0),
                     ubg=np.concatenate(ubg) if ubg else np.zeros(0),
                     quad_t=quad_t, quad_w=quad_w, grid_t=grid_t, residual=tau)


def joint_motion(model: SymbolicModel, spline: BSpline, P: np.ndarray, t: np.ndarray) -> dict[str, np.ndarray]:
    """q, v, a, tau, L of the joint spline at times t (arrays len(t) x nv)."""
    q, v, a = (spline.evaluate(P, t, r) for r in (0, 1, 2))
    L, tau = joint_node_function(model).map(len(t))(q.T, v.T, a.T)
    return {"q": q, "v": v, "a": a, "tau": np.asarray(tau).T, "L": np.asarray(L).ravel()}
