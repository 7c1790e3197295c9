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

Performance: q, v, a at all quadrature nodes as dense N x K MX matrix operations
(:func:`latentoc.latent_motion.latent_motion_grid`, closed-form RBF derivatives), then one
SX Function per node (q, v, a) -> (L, tau) (RNEA) applied with ``Function.map``; sigma^2 and
q on the constraint grid as dense MX products (:func:`~latentoc.latent_motion.gp_grid_function`);
the basis matrices are numeric constants. Measured on arm-raise (59 GPDM frames, 48
quadrature nodes): the exact Hessian of the Lagrangian costs ~4x less per evaluation than
with one SX Function per node through the GP mean (x, xd, xdd) -> (L, tau), whose N-term
sums CasADi differentiates node by node (:func:`~latentoc.latent_motion.latent_node_function`,
kept as the reference the tests check against).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from .dynamics import SymbolicModel
from .gpdm import GPDM
from .latent_motion import gp_grid_function, joint_node_function, latent_motion_grid
from .spline import BSpline

__all__ = ["SplineNLP", "TranscriptionSettings", "build_latent_nlp", "fixed_rows",
           "fit_control_points", "gauss_legendre_nodes", "constraint_times", "trapezoid_cost"]


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

    @property
    def w0(self) -> np.ndarray:
        return self.P_init[self.free].ravel()

    def control_points(self, w: np.ndarray) -> np.ndarray:
        """Full control points P (m x n) for decision vector w."""
        P = self.P_init.copy()
        P[self.free] = np.asarray(w, dtype=float).reshape(len(self.free), P.shape[1])
        return P


def fixed_rows(m: int, boundary: str) -> list[int]:
    """Rows of P held fixed: [0, m-1] for "pose", [0, 1, m-2, m-1] for "rest"."""
    if boundary == "pose":
        return [0, m - 1]
    if boundary == "rest":
        if m < 5:
            raise ValueError(f'boundary "rest" fixes 4 control points and needs m >= 5, got m = {m}')
        return [0, 1, m - 2, m - 1]
    raise ValueError(f'boundary must be "rest" or "pose", got {boundary!r}')


def fit_control_points(spline: BSpline, t: np.ndarray, X: np.ndarray, boundary: str) -> np.ndarray:
    """Least-squares control points of samples X (n x k) at times t with the boundary rows
    fixed to the first/last sample (so x(0) = X[0], x(T) = X[-1], and for "rest" zero end velocity)."""
    X = np.asarray(X, dtype=float)
    m = spline.n_control
    fixed = fixed_rows(m, boundary)
    P = np.zeros((m, X.shape[1]))
    for i in fixed:
        P[i] = X[0] if i < m // 2 else X[-1]
    B = spline.basis(np.asarray(t, dtype=float))
    free = [i for i in range(m) if i not in fixed]
    rhs = X - B[:, fixed] @ P[fixed]
    P[free] = np.linalg.lstsq(B[:, free], rhs, rcond=None)[0]
    return P


def gauss_legendre_nodes(spline: BSpline, points_per_interval: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights, ``points_per_interval`` in every knot interval."""
    xi, wi = np.polynomial.legendre.leggauss(int(points_per_interval))
    bp = spline.breakpoints
    t, w = [], []
    for a, b in zip(bp[:-1], bp[1:]):
        t.append(0.5 * (b - a) * xi + 0.5 * (a + b))
        w.append(0.5 * (b - a) * wi)
    return np.concatenate(t), np.concatenate(w)


def constraint_times(spline: BSpline, points_per_interval: int) -> np.ndarray:
    """Even grid with ``points_per_interval`` steps per knot interval, end points excluded."""
    n = (len(spline.breakpoints) - 1) * int(points_per_interval)
    return np.linspace(0.0, spline.duration, n + 1)[1:-1]


def trapezoid_cost(L: np.ndarray, dt: float) -> float:
    """Trapezoid rule on an even grid of step dt (the paper's 0.001 s reference)."""
    L = np.asarray(L, dtype=float)
    return float(dt * (L.sum() - 0.5 * (L[0] + L[-1])))


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


def torque_limit_vector(torque_limits: list[float], nv: int) -> np.ndarray | None:
    """Per-joint torque bounds from the problem's list ([] none, [s] all, or nv values)."""
    if not torque_limits:
        return None
    if len(torque_limits) == 1:
        return np.full(nv, float(torque_limits[0]))
    if len(torque_limits) != nv:
        raise ValueError(f"torque_limits has {len(torque_limits)} values, the model has {nv} joints")
    return np.asarray(torque_limits, dtype=float)


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
    Qq, Vq, Aq = latent_motion_grid(gpdm, len(quad_t))(ca.mtimes(Pt, B0), ca.mtimes(Pt, B1), ca.mtimes(Pt, B2))
    L, tau = joint_node_function(model).map(len(quad_t))(Qq, Vq, Aq)
    J = ca.mtimes(L, ca.DM(quad_w))

    grid_t = constraint_times(spline, settings.constraint_points)
    G0 = ca.DM(spline.basis(grid_t).T)
    sigma2, Qg = gp_grid_function(gpdm, len(grid_t))(ca.mtimes(Pt, G0))
    g, lbg, ubg = [sigma2.T], [np.full(len(grid_t), -np.inf)], [np.full(len(grid_t), float(tube))]
    if settings.joint_limits:
        lo, hi = np.asarray(model.model.lowerPositionLimit), np.asarray(model.model.upperPositionLimit)
        g.append(ca.vec(Qg))
        lbg.append(np.tile(lo, len(grid_t)))
        ubg.append(np.tile(hi, len(grid_t)))
    tmax = torque_limit_vector(settings.torque_limits, model.nv)
    if tmax is not None:
        g.append(ca.vec(tau))
        lbg.append(np.tile(-tmax, len(quad_t)))
        ubg.append(np.tile(tmax, len(quad_t)))
    n = len(free) * d
    return SplineNLP(spline=spline, free=free, P_init=P_init,
                     nlp={"x": w, "f": J, "g": ca.vertcat(*g)},
                     lbx=np.full(n, -np.inf), ubx=np.full(n, np.inf),
                     lbg=np.concatenate(lbg), ubg=np.concatenate(ubg),
                     quad_t=quad_t, quad_w=quad_w, grid_t=grid_t, tube_rows=slice(0, len(grid_t)), residual=tau)
