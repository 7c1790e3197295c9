"""Negative log posterior of the GPDM, Eq. 16 of Kang & Park (2015), with its
exact analytic gradient; :func:`evaluate` keeps the factors its Hessian
(:mod:`latentoc.gpdm.hessian`) reuses.

Variables are packed as ``v = [vec(X), ln alpha (4), ln beta (3)]`` (X row major,
N x d).  The scale matrix ``W = diag(w)`` is profiled out in closed form
(:func:`optimal_w`) or held fixed.

The value returned by :func:`neg_log_posterior` is (constants dropped)::

    L = lam * [ d/2 ln|K_X| + 1/2 tr(K_X^-1 X_out X_out^T) ]
        + D/2 ln|K_Y| + 1/2 tr(K_Y^-1 Y W^2 Y^T) - N ln|W|
        + sum_i P(alpha_i) + sum_i P(beta_i) + 1/2 sum_s |x_1^(s)|^2

i.e. Eq. 16 plus the N(0, I) prior on the first latent point of every sequence
(the ``p(x_1)`` factor of Eq. 14).  ``lam`` is 1 for the plain GPDM and D/d for
the balanced GPDM of Urtasun et al. (2006).  With several sequences, X_in and
X_out are built per sequence (:func:`sequence_indices`) and K_X is the kernel
matrix of the stacked X_in.

Hyperparameter priors: P(theta) = -(a - 1) ln theta + b theta, the negative log
of a Gamma(a, b) density (shape a, rate b).  a = b = 0 is Eq. 16's improper
p(theta) ~ 1/theta, i.e. P = ln theta (:attr:`GPDMProblem.prior_shape`,
:attr:`GPDMProblem.prior_rate`, default zero).

W: given (``w`` passed) it is held fixed.  With ``w=None`` it is profiled out:
w_d = sqrt(N / (y_d^T K_Y^-1 y_d + 1/kappa^2)) (:func:`optimal_w`) minimises
L + sum_d w_d^2 / (2 kappa^2) (a N(0, kappa^2) prior on each w_d), and that
profiled value, whose gradient is the partial gradient at the optimal w
(envelope theorem), is returned.

Gradient in matrix form: with G = dL/dK = 1/2 (c K^-1 - K^-1 T T^T K^-1)
(c = D, T = Y W for K_Y; c = d, T = X_out for K_X) the derivative with respect to
the points of an RBF kernel is  -2 b2 (diag(M 1) X - M X),  M = G o K_rbf, and
with respect to the linear part 2 alpha3 G X_in.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import lapack

from latentoc.gpdm.kernels import sq_dist

__all__ = [
    "GPDMProblem",
    "sequence_indices",
    "pack",
    "unpack",
    "safe_cholesky",
    "chol_inverse",
    "neg_log_posterior",
    "optimal_w",
    "KAPPA_SQ",
    "HYPER_NAMES",
]

KAPPA_SQ = 1e6
#: the order of the hyperparameters in the packed vector (Eq. 15, Eq. 11)
HYPER_NAMES = ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2", "beta3")


def sequence_indices(sequence_lengths: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Row indices (into the stacked X) of X_in, X_out and the sequence starts.

    For each sequence with rows s..e-1: X_in gets s..e-2, X_out gets s+1..e-1
    (Eq. 14, per sequence); the first row s has no predecessor.
    """
    ins, outs, firsts = [], [], []
    start = 0
    for n in sequence_lengths:
        n = int(n)
        firsts.append(start)
        ins.append(np.arange(start, start + n - 1))
        outs.append(np.arange(start + 1, start + n))
        start += n
    return (np.concatenate(ins).astype(int), np.concatenate(outs).astype(int),
            np.asarray(firsts, dtype=int))


def _as_slice(idx: np.ndarray) -> slice | None:
    """Indices that are a contiguous range as a slice (indexing by it is a view, not a copy), else None."""
    if idx.size and np.all(np.diff(idx) == 1):
        return slice(int(idx[0]), int(idx[-1]) + 1)
    return None


@dataclass
class GPDMProblem:
    """Fixed data of one learning problem: centred data and sequence structure."""

    Y: np.ndarray  # centred data, N x D
    sequence_lengths: list[int]
    latent_dim: int
    dynamics_weight: float = 1.0  # lambda (D/d for balanced GPDM)
    prior_shape: np.ndarray | None = None  # (7,) Gamma shapes a (HYPER_NAMES order); None: 0
    prior_rate: np.ndarray | None = None  # (7,) Gamma rates b; None: 0 (Eq. 16)
    kappa_sq: float = KAPPA_SQ  # variance of the N(0, kappa^2) prior on w (profiled W only)
    in_idx: np.ndarray = field(init=False)
    out_idx: np.ndarray = field(init=False)
    first_idx: np.ndarray = field(init=False)
    in_rows: slice | None = field(init=False)  # in_idx, out_idx as slices where they are ranges (one sequence)
    out_rows: slice | None = field(init=False)

    def __post_init__(self) -> None:
        self.Y = np.asarray(self.Y, dtype=float)
        self.in_idx, self.out_idx, self.first_idx = sequence_indices(self.sequence_lengths)
        self.in_rows, self.out_rows = _as_slice(self.in_idx), _as_slice(self.out_idx)
        self.prior_shape = np.zeros(7) if self.prior_shape is None else np.asarray(self.prior_shape, float)
        self.prior_rate = np.zeros(7) if self.prior_rate is None else np.asarray(self.prior_rate, float)
        if self.prior_shape.shape != (7,) or self.prior_rate.shape != (7,):
            raise ValueError("prior_shape and prior_rate need one value per hyperparameter (7)")

    @property
    def N(self) -> int:
        return self.Y.shape[0]

    @property
    def D(self) -> int:
        return self.Y.shape[1]


def pack(X: np.ndarray, alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """Pack latent points and log-hyperparameters into one vector."""
    return np.concatenate([np.asarray(X, float).ravel(), np.log(alpha), np.log(beta)])


def unpack(v: np.ndarray, N: int, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`pack`: returns X (N x d), alpha (4,), beta (3,)."""
    n = N * d
    return v[:n].reshape(N, d), np.exp(v[n:n + 4]), np.exp(v[n + 4:n + 7])


def safe_cholesky(K: np.ndarray, max_tries: int = 8) -> tuple[np.ndarray, float]:
    """Lower Cholesky factor of K; adds growing diagonal jitter if K is not PD.

    Returns (L, jitter added).
    """
    K = np.asarray(K, dtype=float)
    jitter = 0.0
    scale = max(float(np.mean(np.abs(np.diag(K)))), 1e-300)
    for k in range(max_tries + 1):
        Kj = K if jitter == 0.0 else K + jitter * np.eye(K.shape[0])
        L, info = lapack.dpotrf(Kj, lower=1, clean=1, overwrite_a=0)
        if info == 0 and np.all(np.isfinite(L)):
            return L, jitter
        jitter = scale * 10.0 ** (-10 + k) if jitter == 0.0 else jitter * 10.0
    raise np.linalg.LinAlgError("kernel matrix not positive definite even with jitter %g" % jitter)


def chol_inverse(L: np.ndarray) -> np.ndarray:
    """K^-1 from the lower Cholesky factor L of K (symmetric, full)."""
    Kinv, info = lapack.dpotri(L, lower=1)
    if info != 0:
        raise np.linalg.LinAlgError("dpotri failed (info=%d)" % info)
    # L was passed with a zero upper triangle, so Kinv holds only the lower part
    Kinv = Kinv + Kinv.T
    Kinv[np.diag_indices_from(Kinv)] *= 0.5
    return Kinv


@dataclass
class KernelTerm:
    """One GP term c/2 ln|K| + 1/2 tr(K^-1 T T^T) at a point, kept for the gradient and the
    Hessian-vector products (:mod:`latentoc.gpdm.hessian`): one Cholesky factor per point."""

    X: np.ndarray  # the kernel's input points (n x d)
    R2: np.ndarray  # |x_i - x_j|^2
    E: np.ndarray  # the RBF part s1 exp(-s2/2 R2)
    P: np.ndarray  # K^-1
    B: np.ndarray  # K^-1 T
    G: np.ndarray  # dL/dK = 1/2 (c K^-1 - B B^T)
    M: np.ndarray  # G o E
    c: float  # D or d
    s2: float  # beta_2 or alpha_2 (the inverse squared length scale)
    noise: float  # beta_3 or alpha_4 (the noise precision)
    lin: float  # alpha_3 (the linear part's weight; 0 for K_Y)


def _kernel(X: np.ndarray, s1: float, s2: float, lin: float, noise: float,
            R2: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """R2, E, 1/2 ln|K| and K^-1 of K = s1 exp(-s2/2 R2) + lin X X^T + I/noise (Eq. 11, 15); R2 if known."""
    R2 = sq_dist(X) if R2 is None else R2
    E = R2 * (-0.5 * s2)
    np.exp(E, out=E)
    E *= s1
    if lin:
        K = X @ X.T
        K *= lin
        K += E
    else:
        K = E.copy()
    K[np.diag_indices_from(K)] += 1.0 / noise
    L, _ = safe_cholesky(K)
    del K
    return R2, E, float(np.sum(np.log(np.diag(L)))), chol_inverse(L)


def _term(X: np.ndarray, R2: np.ndarray, E: np.ndarray, P: np.ndarray, B: np.ndarray, c: float, s2: float,
          noise: float, lin: float) -> KernelTerm:
    G = B @ B.T
    G *= -0.5
    G += (0.5 * c) * P
    return KernelTerm(X, R2, E, P, B, G, G * E, c, s2, noise, lin)


def rbf_point_grad(M: np.ndarray, X: np.ndarray, s2: float) -> np.ndarray:
    """d/dX of sum(G o E) for E = s1 exp(-s2/2 R2(X)), given M = G o E (G symmetric)."""
    return -2.0 * s2 * (np.sum(M, axis=1)[:, None] * X - M @ X)


@dataclass
class Evaluation:
    """Eq. 16 (:func:`neg_log_posterior`) at one point: the value ``f``, the gradient ``g`` and what
    the Hessian-vector products reuse (both kernel terms, the profiled scales ``w``)."""

    problem: GPDMProblem
    v: np.ndarray
    f: float
    g: np.ndarray
    obs: KernelTerm  # K_Y (c = D, T = Y W)
    dyn: KernelTerm  # K_X (c = d, T = X_out); its contributions are weighted by lam
    w: np.ndarray
    profiled: bool


def evaluate(v: np.ndarray, problem: GPDMProblem, w: np.ndarray | None = None) -> Evaluation:
    """Eq. 16 (+ first-point prior, hyperparameter priors, optional balancing) and its exact gradient
    at ``v`` (:func:`pack`); W profiled out if ``w`` is None (module docstring).

    The length-scale derivatives use sum_ij M_ij |x_i - x_j|^2 = -sum_i x_i . g_i / s2, where g is
    the point gradient of sum(G o E); this saves one N x N pass.
    """
    N, D, d = problem.N, problem.D, problem.latent_dim
    v = np.asarray(v, dtype=float)
    X, alpha, beta = unpack(v, N, d)
    lam = float(problem.dynamics_weight)

    # ---- observation term (Eq. 10, 11)
    b1, b2, b3 = (float(b) for b in beta)
    R2, E, half_logdet_Y, P = _kernel(X, b1, b2, 0.0, b3)
    profiled = w is None
    if w is None:  # profiled: w_d = sqrt(N / (q_d + 1/kappa^2))
        B0 = P @ problem.Y
        q = np.sum(problem.Y * B0, axis=0)
        w = np.sqrt(N / (q + 1.0 / problem.kappa_sq))
        BY = B0 * w[None, :]
        valY = D * half_logdet_Y + 0.5 * float(np.sum(w * w * (q + 1.0 / problem.kappa_sq)))
    else:
        w = np.asarray(w, dtype=float)
        BY = P @ (problem.Y * w[None, :])
        valY = D * half_logdet_Y + 0.5 * float(np.sum((problem.Y * w[None, :]) * BY))
    obs = _term(X, R2, E, P, BY, float(D), b2, b3, 0.0)

    # ---- dynamics term (Eq. 14, 15)
    a1, a2, a3, a4 = (float(a) for a in alpha)
    Xin = X[problem.in_idx]
    Xout = X[problem.out_idx]
    rows = problem.in_rows  # one sequence: X_in's distances are a block of X's
    R2, E, half_logdet_X, P = _kernel(Xin, a1, a2, a3, a4, None if rows is None else obs.R2[rows, rows])
    BX = P @ Xout
    valX = d * half_logdet_X + 0.5 * float(np.sum(Xout * BX))
    dyn = _term(Xin, R2, E, P, BX, float(d), a2, a4, a3)

    theta = np.concatenate([alpha, beta])
    a_p, b_p = np.asarray(problem.prior_shape, float), np.asarray(problem.prior_rate, float)
    X1 = X[problem.first_idx]
    f = (valY + lam * valX - N * float(np.sum(np.log(w)))
         + float(np.sum(-(a_p - 1.0) * np.log(theta) + b_p * theta))
         + 0.5 * float(np.sum(X1 * X1)))

    # ---- gradient (the prior's d/d ln theta = -(a - 1) + b theta)
    g_prior = -(a_p - 1.0) + b_p * theta
    gX = rbf_point_grad(obs.M, X, b2)
    g_lb = np.array([np.sum(obs.M), 0.5 * float(np.sum(X * gX)), -np.trace(obs.G) / b3]) + g_prior[4:]
    g_rbf_in = rbf_point_grad(dyn.M, Xin, a2)
    GXin = dyn.G @ Xin
    gX[problem.in_idx] += lam * (g_rbf_in + 2.0 * a3 * GXin)
    gX[problem.out_idx] += lam * BX
    g_la = np.array([
        lam * np.sum(dyn.M),
        0.5 * lam * float(np.sum(Xin * g_rbf_in)),
        lam * a3 * float(np.sum(Xin * GXin)),
        -lam * np.trace(dyn.G) / a4,
    ]) + g_prior[:4]
    gX[problem.first_idx] += X1
    return Evaluation(problem, v, float(f), np.concatenate([gX.ravel(), g_la, g_lb]), obs, dyn, w, profiled)


def neg_log_posterior(v: np.ndarray, problem: GPDMProblem, w: np.ndarray | None = None,
                      with_grad: bool = True) -> tuple[float, np.ndarray] | float:
    """Eq. 16 (+ first-point prior, hyperparameter priors, optional balancing) and its exact gradient.

    Parameters: ``v`` packed variables (:func:`pack`), ``problem`` the data,
    ``w`` the per-dimension scales (D,) or None to profile them out (module
    docstring).  Returns ``(L, dL/dv)`` or ``L`` (:func:`evaluate` keeps the factors as well).
    """
    ev = evaluate(v, problem, w)
    return (ev.f, ev.g) if with_grad else ev.f


def optimal_w(Y: np.ndarray, X: np.ndarray, beta: np.ndarray,
              kappa_sq: float = KAPPA_SQ) -> np.ndarray:
    """Closed-form scales w_d = sqrt(N / (y_d^T K_Y^-1 y_d + 1/kappa^2)).

    This maximises Eq. 16 in W given X and beta, with a N(0, kappa^2) prior on
    each w_d so that a constant (zero after centring) column gets w_d = kappa
    sqrt(N) instead of infinity.
    """
    Y = np.asarray(Y, dtype=float)
    N = Y.shape[0]
    b1, b2, b3 = np.asarray(beta, dtype=float)
    KY = b1 * np.exp(-0.5 * b2 * sq_dist(X))
    KY[np.diag_indices(N)] += 1.0 / b3
    L, _ = safe_cholesky(KY)
    Z, info = lapack.dtrtrs(L, Y, lower=1)
    q = np.sum(Z * Z, axis=0)
    return np.sqrt(N / (q + 1.0 / kappa_sq))
