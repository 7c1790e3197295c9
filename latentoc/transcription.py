"""The latent-space NLP (Kang & Park 2015, Eq. 22 with the tube of Eq. 29).

Decision variables: the free control points of the latent B-spline x(t, P) (Eq. 20).
The boundary poses are held by fixing control points of the clamped spline:

* ``boundary = "pose"``: p_1 and p_m fixed, so x(0) and x(T) (hence q(0) = mu_Q(x(0)) and
  q(T)) are the training ones;
* ``boundary = "rest"`` (the arm): p_1 = p_2 and p_(m-1) = p_m fixed as well, so in
  addition xdot(0) = xdot(T) = 0 and the motion starts and ends at rest (v = J_mu xdot = 0).

The remaining control points start from a least-squares fit of the training latent
trajectory x_r(t) with those rows fixed (Sect. 3.2, last paragraph).

Objective (Eq. 22): J = int_0^T L dt with L = |tau|^2, by Gauss-Legendre quadrature with
``quadrature_points`` nodes in each knot interval (the integrand is smooth inside an
interval; 8 nodes per interval keep the difference to the 1 ms trapezoid below ~5e-4 on arm-raise, while 4 let the optimiser exploit the gaps (errors up to 15%); the solver reports the difference
to the paper's 0.001 s trapezoid rule as ``quadrature_error``).

Constraints on an even grid of ``constraint_points`` per knot interval (the fixed end
points excluded): sigma^2(x(t_k)) <= delta (Eq. 29), joint limits on q(t_k) and, if
given, |tau| <= torque limit at the quadrature nodes.

Performance (issue 5): q, v, a at all quadrature nodes as dense N x K MX matrix operations
(:func:`latentoc.latent_motion.latent_motion_grid`, closed-form RBF derivatives); sigma^2
and q on the constraint grid as dense MX products (:func:`~latentoc.latent_motion.gp_grid_function`);
the basis matrices are numeric constants. ``grad_f``, ``jac_g`` and ``hess_lag`` go to
``nlpsol`` as custom Functions (``structured_derivatives``, default on without torque limits,
:func:`_lifted_derivatives`):

* objective: a Function of the lifted z = (x, xd, xdd) at the K quadrature nodes, affine in
  the decision vector w; per node, |tau|^2 with its gradient and 3n x 3n Hessian in
  u = (q, v, a) is C code compiled once per robot and cached on disk (``jit``,
  :func:`latentoc.latent_motion.node_derivative_functions`), and the chain rule through
  u(z) (:func:`node_objective_functions`) is left to CasADi;
* constraints: closed-form first and second derivatives of sigma^2 and mu_Q at the grid
  points (``closed_form_grid``, :func:`latentoc.latent_motion.gp_grid_derivatives`),
  assembled in w with the basis matrix (:func:`_grid_constraints`);
* Ipopt scales the rows to a largest gradient of 1 (:data:`LATENT_IPOPT_OPTIONS`).

Measured on arm-raise (d = 3, m = 9, 48 quadrature nodes, 191 grid points; CPU, 2 shared
cores; ``python -m latentoc bench arm --reference``), per evaluation, before (CasADi's
derivatives of the lifted Functions in its virtual machine) -> now: Hessian of the
Lagrangian 21 -> 7.8 ms, constraint Jacobian 2.4 -> 1.7 ms, objective gradient 1.5 -> 0.5 ms;
iterations 1x/5x/50x 151/57/24 -> 114/27/24; solve 6.8/2.5/1.45 -> 2.3/0.48/0.44 s CPU (5x: 1.84
-> 0.48 s); build 0.2 s (first build on a machine: +22 s compiling the node derivatives).
Every optimum the same to 1e-10 relative. The joint-range baseline, given the same compiled
node derivatives, solves in 0.17-0.26 s (+-20/60 deg; 1.5-2.2 s before): it has no GP and
linear constraints, so per evaluation the latent NLP stays ~7x dearer (GP mean with its
second derivatives, 1528 nonlinear rows) and Ipopt needs ~2x its time per iteration.
Not worth it (measured): ``expand=True`` (SX graph; build 35 s and the Hessian 83 ms); one
SX Hessian per node through the GP mean (62 ms for 48 nodes); compiling the whole MX
hess_lag to C (5 MB of C, gcc -O1 100 s, no faster than the VM: the time is in dense
products); splitting the node Hessian into 3 or 21 C functions (gcc -O1 still 14-16 s);
dense node blocks of J_U and the second-order term by forward (over reverse) derivatives
with one seed per lifted variable, summed by a mapped MX Function (Hessian 7.8 -> 10-11 ms,
the baseline's 1.1 -> 2.6-3.2 ms).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .dynamics import SymbolicModel
from .gpdm import GPDM
from .latent_motion import (gp_grid_derivatives, gp_grid_function, joint_node_function, latent_motion_grid,
                            node_derivative_functions)
from .kinds.min_torque import torque_limit_vector
from .spline import BSpline
from .spline_path import constraint_times, fit_control_points, fixed_rows, gauss_legendre_nodes, trapezoid_cost

__all__ = ["SplineNLP", "TranscriptionSettings", "build_latent_nlp", "fixed_rows", "node_objective_functions",
           "fit_control_points", "gauss_legendre_nodes", "constraint_times", "trapezoid_cost"]


#: Ipopt options for the latent NLP (:func:`latentoc.solver.build_solver` applies them). Row
#: scaling to a largest gradient of 1 (Ipopt's default only scales rows above 100): the sigma^2
#: rows have gradients ~1e-3, and scaling them up changes the iterates, not the problem.
#: Measured on arm-raise (d = 3), tubes 1x/5x/50x: 146/57/24 -> 114/27/24 iterations, and
#: 1.5x/2x/3x/10x/20x/100x/1000x: 39/36/30/31/29/23/36 -> 34/27/28/28/31/24/44, every optimum
#: the same to 1e-10 relative. (A target of 0.1 lands in worse local optima at 1.5x-10x, 10
#: doubles the iterations; the joint-range baseline is left at Ipopt's default: with 1.0 it
#: needs as many iterations and finds a worse optimum at +-60 deg.)
LATENT_IPOPT_OPTIONS = {"nlp_scaling_constr_target_gradient": 1.0}


@dataclass
class TranscriptionSettings:
    """How to transcribe: spline size, boundary handling, node densities, limits."""

    duration: float
    control_points: int = 9
    spline_degree: int = 3
    boundary: str = "rest"
    quadrature_points: int = 4
    constraint_points: int = 12
    joint_limits: bool = True
    torque_limits: list[float] = field(default_factory=list)
    structured_derivatives: bool = True  # lifted grad/Jacobian/Hessian (module doc, Performance)
    closed_form_grid: bool = True  # closed-form sigma^2 / mu_Q derivatives on the grid (else CasADi's)
    jit: bool = True  # per-node derivatives compiled to C, cached on disk (latentoc.solver.compiled_functions)


@dataclass
class SplineNLP:
    """A transcribed NLP over spline control points, ready for :func:`latentoc.solver.build_solver`."""

    spline: BSpline
    free: np.ndarray  # indices of the free control-point rows
    P_init: np.ndarray  # m x n initial control points (fixed rows included)
    nlp: dict  # {"x": w, "f": J, "g": g}
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    quad_t: np.ndarray
    quad_w: np.ndarray
    grid_t: np.ndarray
    tube_rows: slice | None = None  # rows of g holding sigma^2 (latent only)
    residual: object = None  # MX tau (nv x K) at the quadrature nodes: J = sum_k w_k |tau_k|^2
    derivatives: dict | None = None  # {"grad_f", "jac_g", "hess_lag"} Functions for nlpsol, or None

    @property
    def w0(self) -> np.ndarray:
        return self.P_init[self.free].ravel()

    def control_points(self, w: np.ndarray) -> np.ndarray:
        """Full control points P (m x n) for decision vector w."""
        P = self.P_init.copy()
        P[self.free] = np.asarray(w, dtype=float).reshape(len(self.free), P.shape[1])
        return P


def _basis_constants(spline: BSpline, t: np.ndarray) -> tuple[ca.DM, ca.DM, ca.DM]:
    """Transposed basis matrices (m x K) so that X^T = P^T B^T."""
    return tuple(ca.DM(spline.basis(t, r).T) for r in (0, 1, 2))


def _symbolic_control_points(w: ca.MX, P_init: np.ndarray, free: np.ndarray) -> ca.MX:
    """P (m x n) as MX: fixed rows constant, free rows taken from w (row-major)."""
    m, n = P_init.shape
    rows, k = [], 0
    for i in range(m):
        if i in set(free.tolist()):
            rows.append(ca.reshape(w[k * n:(k + 1) * n], 1, n))
            k += 1
        else:
            rows.append(ca.DM(P_init[i:i + 1]))
    return ca.vertcat(*rows)


def affine_map(expr: ca.MX, w: ca.MX) -> tuple[ca.DM, ca.DM]:
    """(M, c) with vec(expr) = M w + c for an MX expression affine in w (checked at a probe
    point; raises ValueError otherwise)."""
    expr = ca.vec(expr)
    M = ca.evalf(ca.substitute(ca.jacobian(expr, w), w, ca.DM.zeros(w.shape)))
    c = ca.evalf(ca.substitute(expr, w, ca.DM.zeros(w.shape)))
    probe = np.linspace(-1.0, 1.0, w.shape[0])
    ref = np.asarray(ca.evalf(ca.substitute(expr, w, ca.DM(probe)))).ravel()
    if not np.allclose(np.asarray(M @ probe + c).ravel(), ref, rtol=1e-12, atol=1e-12):
        raise ValueError("expression is not affine in w")
    return ca.sparsify(M), c


def node_objective_functions(z: ca.MX, U: ca.MX, quad_w: np.ndarray, nodes: dict[str, ca.Function],
                             lifted: bool = True) -> tuple[ca.Function, ca.Function]:
    """(z -> (J, dJ/dz), z -> d2J/dz2) for J = sum_k w_k L(u_k), u_k column k of U(z) (3n x K).

    L, its gradient and its Hessian per node come from ``nodes``
    (:func:`latentoc.latent_motion.node_derivative_functions`, compiled); the chain rule
    through u = U(z) is left to CasADi::

        dJ/dz = J_U^T g_w,   d2J/dz2 = J_U^T blockdiag(w_k H_k) J_U + d2(g_w . U)/dz2 (g_w fixed)

    with g_w = (w_k dL/du_k)_k. ``lifted=False`` means z = vec(U) (U is the symbol itself),
    where the Hessian is the block diagonal alone.
    """
    nu, K = U.shape
    wq = np.asarray(quad_w, dtype=float)
    L, G = nodes["grad"].map(K)(U)
    Gw = G * ca.DM(np.tile(wq, (nu, 1)))
    f_grad = ca.Function("lifted_grad_f", [z], [ca.mtimes(L, ca.DM(wq)), ca.jtimes(ca.vec(U), z, ca.vec(Gw), True)])
    _, G, HU = nodes["hess"].map(K)(U)
    HUw = HU * ca.DM(np.tile(np.repeat(wq, nu), (nu, 1)))
    H = ca.diagcat(*ca.horzsplit(HUw, nu))
    if lifted:
        lam = ca.MX.sym("lam", nu * K)
        second = ca.Function("motion_hess", [z, lam], [ca.hessian(ca.dot(lam, ca.vec(U)), z)[0]])
        Ju = ca.jacobian(ca.vec(U), z)
        H = ca.mtimes([Ju.T, H, Ju]) + second(z, ca.vec(G * ca.DM(np.tile(wq, (nu, 1)))))
    return f_grad, ca.Function("lifted_hess_f", [z], [H])


def _lifted_constraints(w: ca.MX, x_w: ca.MX, x: ca.MX, g: ca.MX, lam_g: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX]:
    """(g, dg/dw, d2 (lam_g . g)/dw2) in w for constraints g given as an expression in the
    symbol x (block diagonal per node), x = x_w = M_g w + c_g: CasADi's colouring in x, then
    the chain rule jac = dg/dx M_g, hess = M_g^T (d2 (lam_g . g)/dx2) M_g."""
    Mg, cg = affine_map(x_w, w)
    g_jac = ca.Function("lifted_jac_g", [x], [g, ca.jacobian(g, x)])
    g_hess = ca.Function("lifted_hess_g", [x, lam_g], [ca.hessian(ca.dot(lam_g, g), x)[0]])
    x_w = ca.mtimes(Mg, w) + cg
    gw, Jxw = g_jac(x_w)
    return gw, ca.mtimes(Jxw, Mg), ca.mtimes([Mg.T, g_hess(x_w, lam_g), Mg])


def _grid_constraints(gpdm: GPDM, G0f: np.ndarray, Xw: ca.MX, g_of_x: ca.Function, joint_limits: bool,
                      lam_g: ca.MX) -> tuple[ca.MX, ca.MX, ca.MX]:
    """(g, dg/dw, d2 (lam_g . g)/dw2) of the grid rows (sigma^2, then Q if ``joint_limits``)
    from the closed-form derivatives (:func:`~latentoc.latent_motion.gp_grid_derivatives`).

    x_j = sum_r G0[j, r] p_r, and w holds the free rows p_r row-major (index r d + a), so
    dg_j/dw_(r,a) = G0f[j, r] dg_j/dx_a and the Hessian is sum_(a,b) kron(G0f^T diag(h_ab) G0f, E_ab).
    """
    d, D = gpdm.latent_dim, gpdm.output_dim
    Kg, nf = G0f.shape
    ls = lam_g[:Kg].T
    lq = ca.reshape(lam_g[Kg:], D, Kg) if joint_limits else ca.DM.zeros(D, Kg)
    fns = gp_grid_derivatives(gpdm, Kg)
    dS, dQ = fns["jac"](Xw)
    Hp = fns["hess"](Xw, ls, lq)
    G = ca.DM(G0f)
    S = dS.T  # Kg x d
    jac = [ca.horzcat(*[S * ca.repmat(G[:, r], 1, d) for r in range(nf)])]
    if joint_limits:
        Dq = ca.horzcat(*[ca.vec(dQ[a * D:(a + 1) * D, :]) for a in range(d)])  # (Kg D) x d, row j D + i
        Grep = ca.DM(np.repeat(G0f, D, axis=0))
        jac.append(ca.horzcat(*[Dq * ca.repmat(Grep[:, r], 1, d) for r in range(nf)]))
    hess, p = 0, 0
    for a in range(d):
        for b in range(a, d):
            M = ca.mtimes(G.T, G * ca.repmat(Hp[p, :].T, 1, nf))
            E = np.zeros((d, d))
            E[a, b] = E[b, a] = 1.0
            hess = hess + ca.kron(M, ca.DM(E))
            p += 1
    return g_of_x(Xw), ca.vertcat(*jac), hess


def _lifted_derivatives(w: ca.MX, z_w: ca.MX, z: ca.MX, f_grad: ca.Function, f_hess: ca.Function,
                        constraints: tuple[ca.MX, ca.MX, ca.MX], lam_g: ca.MX) -> dict:
    """grad_f, jac_g and hess_lag for ``nlpsol`` through lifted variables.

    The objective is given as Functions of the symbol z (x, xd, xdd at the quadrature
    nodes: ``f_grad`` z -> (J, dJ/dz), ``f_hess`` z -> d2J/dz2, see
    :func:`node_objective_functions`), with z = z_w = M_z w + c_z in the NLP. Each node's
    terms depend on its own lifted values, so the Hessian in z is block diagonal and cheap;
    with the constant map::

        grad_f = M_z^T dJ/dz,  hess_lag = lam_f M_z^T (d2J/dz2) M_z + d2 (lam_g . g)/dw2

    ``constraints`` = (g, dg/dw, d2 (lam_g . g)/dw2) as expressions in w and the symbol
    lam_g (:func:`_lifted_constraints` or :func:`_grid_constraints`).
    """
    Mz, _ = affine_map(z_w, w)
    lam_f, p = ca.MX.sym("lam_f"), ca.MX.sym("p", 0)
    Jw, gzw = f_grad(z_w)
    Hzw = f_hess(z_w)
    gw, jac_w, hess_g = constraints
    Mz_t = Mz.T
    hess = lam_f * ca.mtimes([Mz_t, Hzw, Mz]) + hess_g
    return {
        "grad_f": ca.Function("grad_f", [w, p], [Jw, ca.mtimes(Mz_t, gzw)], ["x", "p"], ["f", "grad_f_x"]),
        "jac_g": ca.Function("jac_g", [w, p], [gw, jac_w], ["x", "p"], ["g", "jac_g_x"]),
        "hess_lag": ca.Function("hess_lag", [w, p, lam_f, lam_g], [ca.triu(ca.densify(hess))],
                                ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }


def build_latent_nlp(gpdm: GPDM, model: SymbolicModel, settings: TranscriptionSettings,
                     tube: float, t_train: np.ndarray) -> SplineNLP:
    """Transcribe Eq. 22 subject to the tube (Eq. 29), joint and torque limits."""
    d = gpdm.latent_dim
    spline = BSpline(settings.control_points, settings.duration, settings.spline_degree)
    X_train = gpdm.latent_trajectories()[0]
    P_init = fit_control_points(spline, t_train, X_train, settings.boundary)
    fixed = fixed_rows(spline.n_control, settings.boundary)
    free = np.array([i for i in range(spline.n_control) if i not in fixed], dtype=int)

    w = ca.MX.sym("w", len(free) * d)
    P = _symbolic_control_points(w, P_init, free)
    quad_t, quad_w = gauss_legendre_nodes(spline, settings.quadrature_points)
    B0, B1, B2 = _basis_constants(spline, quad_t)
    Pt = P.T  # d x m
    K, n = len(quad_t), len(free) * d
    # objective as a function of the lifted z = (x; xd; xdd) at the quadrature nodes (3d x K)
    Zs = ca.MX.sym("Z", 3 * d, K)
    Qq, Vq, Aq = latent_motion_grid(gpdm, K)(Zs[:d, :], Zs[d:2 * d, :], Zs[2 * d:, :])
    L, tau_z = joint_node_function(model).map(K)(Qq, Vq, Aq)
    J_z = ca.mtimes(L, ca.DM(quad_w))
    Zw = ca.vertcat(ca.mtimes(Pt, B0), ca.mtimes(Pt, B1), ca.mtimes(Pt, B2))
    J, tau = ca.Function("objective", [Zs], [J_z, tau_z])(Zw)

    # tube and joint-limit rows as a function of x at the constraint grid (d x Kg)
    grid_t = constraint_times(spline, settings.constraint_points)
    Kg = len(grid_t)
    G0 = ca.DM(spline.basis(grid_t).T)
    Xs = ca.MX.sym("Xg", d, Kg)
    sigma2, Qg = gp_grid_function(gpdm, Kg)(Xs)
    g_x, lbg, ubg = [sigma2.T], [np.full(Kg, -np.inf)], [np.full(Kg, float(tube))]
    if settings.joint_limits:
        lo, hi = np.asarray(model.model.lowerPositionLimit), np.asarray(model.model.upperPositionLimit)
        g_x.append(ca.vec(Qg))
        lbg.append(np.tile(lo, Kg))
        ubg.append(np.tile(hi, Kg))
    g_x = ca.vertcat(*g_x)
    Xw = ca.mtimes(Pt, G0)
    grid_fn = ca.Function("grid_constraints", [Xs], [g_x])
    g = [grid_fn(Xw)]
    tmax = torque_limit_vector(settings.torque_limits, model.nv)
    if tmax is not None:
        g.append(ca.vec(tau))
        lbg.append(np.tile(-tmax, K))
        ubg.append(np.tile(tmax, K))
    nlp = {"x": w, "f": J, "g": ca.vertcat(*g), "ipopt_options": dict(LATENT_IPOPT_OPTIONS)}
    derivatives = None
    if settings.structured_derivatives and tmax is None:
        z = ca.vec(Zs)
        f_grad, f_hess = node_objective_functions(z, ca.vertcat(Qq, Vq, Aq), quad_w,
                                                  node_derivative_functions(model, jit=settings.jit))
        lam_g = ca.MX.sym("lam_g", g_x.shape[0])
        if settings.closed_form_grid:
            rows = _grid_constraints(gpdm, spline.basis(grid_t)[:, free], Xw, grid_fn, settings.joint_limits, lam_g)
        else:
            rows = _lifted_constraints(w, ca.vec(Xw), ca.vec(Xs), g_x, lam_g)
        derivatives = _lifted_derivatives(w, ca.vec(Zw), z, f_grad, f_hess, rows, lam_g)
        nlp["derivatives"] = derivatives
    return SplineNLP(spline=spline, free=free, P_init=P_init, nlp=nlp, derivatives=derivatives,
                     lbx=np.full(n, -np.inf), ubx=np.full(n, np.inf),
                     lbg=np.concatenate(lbg), ubg=np.concatenate(ubg),
                     quad_t=quad_t, quad_w=quad_w, grid_t=grid_t, tube_rows=slice(0, Kg), residual=tau)
