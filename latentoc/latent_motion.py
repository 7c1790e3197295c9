"""Joint motion of a latent trajectory through the GPDM mean (Kang & Park 2015, Eq. 21, 26-28).

For a latent point x with velocity xd and acceleration xdd (Eq. 23-25, linear in the
control points), the joint motion is::

    q   = mu_Q(x)                                   (Eq. 21, 26)
    v   = J_mu(x) xd                                (Eq. 27)
    a   = J_mu(x) xdd + d/dx (J_mu(x) xd) xd        (Eq. 28)

computed by CasADi's forward mode (``jtimes``) on the GPDM's SX mean function, so no
Jacobian of mu_Q is ever formed explicitly. Torques follow from ``SymbolicModel.rnea``
(Eq. 1-2), and the minimum-torque integrand is L = |tau|^2.

:func:`latent_node_function` is the one per-node SX Function the transcription maps over
its quadrature nodes. :func:`gp_grid_function` evaluates sigma^2 (Eq. 19) and mu_Q at K
latent points at once as dense MX matrix products: the variance costs O(N^2) per point,
which is ~10x cheaper as one dense product than as N^2 scalar SX operations.

:func:`node_derivative_functions` gives the per-node cost L(u) = |tau(u)|^2 of u = (q, v, a)
with its gradient and 3n x 3n Hessian as SX Functions, compiled to C and cached on disk
(:func:`latentoc.solver.compiled_functions`): the Hessian (47k SX instructions for the
7-DOF arm) costs 0.02 ms per node compiled against 0.3 ms in CasADi's virtual machine.
Both transcriptions assemble their exact Hessians from it (chain rule through the lifted
node variables).
"""

from __future__ import annotations

import hashlib

import casadi as ca
import numpy as np

from .dynamics import SymbolicModel
from .gpdm import GPDM

__all__ = ["latent_kinematics", "latent_node_function", "gp_grid_function", "joint_node_function",
           "latent_motion_grid", "numeric_latent_motion", "node_derivative_functions", "gp_grid_derivatives"]


def latent_kinematics(gpdm: GPDM) -> ca.Function:
    """SX Function (x, xd, xdd) [d] -> (q, v, a) [D] of Eq. 26-28."""
    d = gpdm.latent_dim
    mean = gpdm.mean_function()
    x, xd, xdd = ca.SX.sym("x", d), ca.SX.sym("xd", d), ca.SX.sym("xdd", d)
    q = mean(x)
    v = ca.jtimes(q, x, xd)
    a = ca.jtimes(q, x, xdd) + ca.jtimes(v, x, xd)
    return ca.Function("latent_kinematics", [x, xd, xdd], [q, v, a],
                       ["x", "xd", "xdd"], ["q", "v", "a"])


def _torque_cost(tau: ca.SX) -> ca.SX:
    return ca.sumsqr(tau)


def latent_node_function(gpdm: GPDM, model: SymbolicModel) -> ca.Function:
    """SX Function (x, xd, xdd) -> (L, tau, q, v, a) with L = |tau|^2 (minimum torque)."""
    if model.nq != gpdm.output_dim or model.nv != model.nq:
        raise ValueError(f"the GPDM outputs {gpdm.output_dim} joint angles but the model has "
                         f"nq = {model.nq}, nv = {model.nv}; the latent transcription needs nq = nv = D")
    kin = latent_kinematics(gpdm)
    d = gpdm.latent_dim
    x, xd, xdd = ca.SX.sym("x", d), ca.SX.sym("xd", d), ca.SX.sym("xdd", d)
    q, v, a = kin(x, xd, xdd)
    tau = model.rnea(q, v, a)
    return ca.Function("latent_node", [x, xd, xdd], [_torque_cost(tau), tau, q, v, a],
                       ["x", "xd", "xdd"], ["L", "tau", "q", "v", "a"])


def joint_node_function(model: SymbolicModel) -> ca.Function:
    """SX Function (q, v, a) -> (L, tau) for the full configuration-space baseline."""
    n = model.nv
    q, v, a = ca.SX.sym("q", model.nq), ca.SX.sym("v", n), ca.SX.sym("a", n)
    tau = model.rnea(q, v, a)
    return ca.Function("joint_node", [q, v, a], [_torque_cost(tau), tau], ["q", "v", "a"], ["L", "tau"])


_NODE_DERIVATIVES: dict[tuple[str, bool], dict[str, ca.Function]] = {}


def node_derivative_functions(model: SymbolicModel, jit: bool = True) -> dict[str, ca.Function]:
    """Per-node Functions of u = (q; v; a) [3n]: ``"grad"`` u -> (L, dL/du) and ``"hess"``
    u -> (L, dL/du, d2L/du2) with L = |tau|^2; compiled to C if ``jit`` (and a compiler is
    there), else CasADi SX Functions. Built once per model and process."""
    key = (hashlib.sha256(model.rnea.serialize().encode()).hexdigest(), bool(jit))
    if key not in _NODE_DERIVATIVES:
        n = model.nv
        q, v, a = ca.SX.sym("q", model.nq), ca.SX.sym("v", n), ca.SX.sym("a", n)
        u = ca.vertcat(q, v, a)
        L = _torque_cost(model.rnea(q, v, a))
        H, g = ca.hessian(L, u)
        fns = [ca.Function("latentoc_node_grad", [u], [L, g], ["u"], ["L", "grad"]),
               ca.Function("latentoc_node_hess", [u], [L, g, H], ["u"], ["L", "grad", "hess"])]
        if jit:
            from .solver import compiled_functions  # solver imports nothing from here
            fns = compiled_functions(fns)
        _NODE_DERIVATIVES[key] = {"grad": fns[0], "hess": fns[1]}
    return _NODE_DERIVATIVES[key]


def gp_grid_function(gpdm: GPDM, n_points: int) -> ca.Function:
    """MX Function X (d x K) -> (sigma2 (1 x K), Q (D x K)): Eq. 19 and Eq. 18 at K points."""
    d, N = gpdm.latent_dim, gpdm.X.shape[0]
    K = int(n_points)
    obs = gpdm._obs()  # K_Y^-1 factors, cached by the GPDM
    b1, b2, b3 = (float(b) for b in gpdm.beta)
    X = ca.MX.sym("X", d, K)
    r2 = 0
    for j in range(d):
        diff = ca.repmat(ca.DM(gpdm.X[:, j]), 1, K) - ca.repmat(X[j, :], N, 1)
        r2 = r2 + diff * diff
    kmat = b1 * ca.exp(-0.5 * b2 * r2)  # N x K
    V = ca.mtimes(ca.DM(obs["Linv"]), kmat)
    sigma2 = (b1 + 1.0 / b3) - ca.sum1(V * V)
    Q = ca.repmat(ca.DM(gpdm.Y_mean), 1, K) + ca.mtimes(ca.DM(obs["A"].T / gpdm.W[:, None]), kmat)
    return ca.Function("gp_grid", [X], [sigma2, Q], ["X"], ["sigma2", "Q"])


def gp_grid_derivatives(gpdm: GPDM, n_points: int) -> dict[str, ca.Function]:
    """Closed-form first and second derivatives of sigma^2 (Eq. 19) and mu_Q (Eq. 18) at K
    latent points: MX Functions ``"jac"`` X (d x K) -> (dS, dQ) and ``"hess"``
    (X, lam_s (1 x K), lam_q (D x K)) -> H.

    dS[a, j] = d sigma^2_j / dx_a, rows a*D..(a+1)*D of dQ are dQ_j / dx_a, and row p of H
    (pairs a <= b in row-major order) is d2/dx_a dx_b (lam_s_j sigma^2_j + lam_q_j . Q_j).
    With k_i = b1 exp(-b2/2 |e_i|^2), e_i = x - x_i, alpha = K_Y^-1 k, C = K_Y^-1 Yc W / W::

        dk_i/dx_a = -b2 k_i e_ia,  d2k_i/dx_a dx_b = k_i (b2^2 e_ia e_ib - b2 delta_ab)
        d sigma^2 = -2 alpha . dk,  d2 sigma^2 = -2 (alpha . d2k + dk_a^T K_Y^-1 dk_b)
        dQ = C dk,                  lam_q . d2Q = (C^T lam_q) . d2k
    """
    d, N, D = gpdm.latent_dim, gpdm.X.shape[0], gpdm.output_dim
    K = int(n_points)
    b1, b2, _ = (float(b) for b in gpdm.beta)
    obs = gpdm._obs()
    Linv = ca.sparsify(ca.DM(np.tril(obs["Linv"])))
    C = ca.DM(obs["A"].T / gpdm.W[:, None])  # D x N
    X, ls, lq = ca.MX.sym("X", d, K), ca.MX.sym("lam_s", 1, K), ca.MX.sym("lam_q", D, K)
    E = [ca.repmat(X[a, :], N, 1) - ca.repmat(ca.DM(gpdm.X[:, a]), 1, K) for a in range(d)]
    r2 = E[0] * E[0]
    for a in range(1, d):
        r2 = r2 + E[a] * E[a]
    kmat = b1 * ca.exp(-0.5 * b2 * r2)
    Dk = [-b2 * kmat * e for e in E]
    LD = [ca.mtimes(Linv, g) for g in Dk]
    alpha = ca.mtimes(Linv.T, ca.mtimes(Linv, kmat))
    dS = ca.vertcat(*[-2.0 * ca.sum1(alpha * g) for g in Dk])
    dQ = ca.vertcat(*[ca.mtimes(C, g) for g in Dk])
    Wk = (-2.0 * ca.repmat(ls, N, 1) * alpha + ca.mtimes(C.T, lq)) * kmat
    swk = ca.sum1(Wk)
    rows = []
    for a in range(d):
        for b in range(a, d):
            h = b2 * b2 * ca.sum1(Wk * E[a] * E[b]) - 2.0 * ls * ca.sum1(LD[a] * LD[b])
            rows.append(h - b2 * swk if a == b else h)
    return {"jac": ca.Function("gp_grid_jac", [X], [dS, dQ], ["X"], ["dS", "dQ"]),
            "hess": ca.Function("gp_grid_hess", [X, ls, lq], [ca.vertcat(*rows)], ["X", "lam_s", "lam_q"], ["H"])}


def latent_motion_grid(gpdm: GPDM, n_points: int) -> ca.Function:
    """MX Function (X, Xd, Xdd) (d x K) -> (Q, V, A) (D x K): Eq. 26-28 at K points at once.

    Closed form for the RBF kernel k_i(x) = b1 exp(-b2/2 |x - x_i|^2), e_i = x - x_i::

        dk_i/dt   = -b2 k_i (e_i . xd)
        d2k_i/dt2 = k_i (b2^2 (e_i . xd)^2 - b2 |xd|^2 - b2 e_i . xdd)

    and q = Y_mean + C^T k with C = K_Y^-1 Yc W / W. Written as dense N x K matrix
    operations, CasADi's derivatives (and the exact Hessian) stay matrix-level, which is
    several times faster than differentiating the N-term SX sums node by node.
    """
    d, N = gpdm.latent_dim, gpdm.X.shape[0]
    K = int(n_points)
    b1, b2, _ = (float(b) for b in gpdm.beta)
    C = ca.DM(gpdm._obs()["A"].T / gpdm.W[:, None])  # D x N
    X, Xd, Xdd = ca.MX.sym("X", d, K), ca.MX.sym("Xd", d, K), ca.MX.sym("Xdd", d, K)
    r2, ed, edd = 0, 0, 0
    for j in range(d):
        e = ca.repmat(X[j, :], N, 1) - ca.repmat(ca.DM(gpdm.X[:, j]), 1, K)
        r2 = r2 + e * e
        ed = ed + e * ca.repmat(Xd[j, :], N, 1)
        edd = edd + e * ca.repmat(Xdd[j, :], N, 1)
    kmat = b1 * ca.exp(-0.5 * b2 * r2)
    speed2 = ca.repmat(ca.sum1(Xd * Xd), N, 1)
    dk = -b2 * kmat * ed
    ddk = kmat * (b2 * b2 * ed * ed - b2 * speed2 - b2 * edd)
    Q = ca.repmat(ca.DM(gpdm.Y_mean), 1, K) + ca.mtimes(C, kmat)
    return ca.Function("latent_motion_grid", [X, Xd, Xdd], [Q, ca.mtimes(C, dk), ca.mtimes(C, ddk)],
                       ["X", "Xd", "Xdd"], ["Q", "V", "A"])


def numeric_latent_motion(gpdm: GPDM, model: SymbolicModel, x: np.ndarray, xd: np.ndarray,
                          xdd: np.ndarray) -> dict[str, np.ndarray]:
    """Evaluate q, v, a, tau, L along K latent samples (arrays K x d); returns K x n arrays."""
    f = latent_node_function(gpdm, model).map(x.shape[0])
    L, tau, q, v, a = f(x.T, xd.T, xdd.T)
    return {"L": np.asarray(L).ravel(), "tau": np.asarray(tau).T, "q": np.asarray(q).T,
            "v": np.asarray(v).T, "a": np.asarray(a).T}
