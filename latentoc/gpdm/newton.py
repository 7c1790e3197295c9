"""A trust-region Newton method for Eq. 16 on its exact Hessian, without an eigendecomposition: the
minimiser :func:`~latentoc.gpdm.learning.learn_gpdm` uses, written here so that its path depends only on
the objective, not on scipy's version (docs/gpdm.md has the measurements).

Each iteration takes the Hessian H (:func:`latentoc.gpdm.hessian.hessian`, assembled from the factors the
gradient computed), with the directions of the objective's exact symmetries (the latent rotations)
projected out, and one Cholesky factor of M = H + sigma I: sigma is 1e-10 of H's largest diagonal entry
where that factors (H positive definite to that shift), else the smallest shift found from the previous
iteration's that makes M positive definite. The steps minimise the quadratic model g^T s + 1/2 s^T H s
within ||s||_M <= Delta by conjugate gradients on H preconditioned by M (Steihaug-Toint: it stops on the
boundary or along a direction of negative curvature), Delta following the ratio rho of the actual to
the predicted decrease. A Hessian serves up to ``reuse`` steps while they decrease L as predicted.

Learning stops when H + sigma I is positive definite with sigma <= FLAT of H's largest diagonal entry
(no curvature below -FLAT lambda_max: flat, or none) and the Newton decrement 1/2 g^T M^-1 g, the
decrease a Newton step predicts, is at most ``ftol`` |L|: a second-order certificate. It then takes
that Newton step (if L does not rise): the point returned is the minimum to about the square of the
certified error, not wherever the path stopped.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from scipy.linalg import blas, lapack
from scipy.sparse import linalg as sparse_linalg

__all__ = ["FLAT", "SHIFT", "NewtonResult", "Point", "factor_shifted", "minimize_newton", "project_out",
           "steihaug"]

NOISE = 64 * float(np.finfo(float).eps)  # relative rounding of L summed over its terms
#: the shift every factorisation carries, relative to H's largest diagonal entry
SHIFT = 1e-10
#: curvature above -FLAT lambda_max counts as none in the convergence test (the eigenvalue floor of the
#: previous, eigendecomposition-based learner)
FLAT = 1e-8


class Point(Protocol):
    """An evaluated point: L and its gradient (whatever else the Hessian needs is the caller's)."""

    f: float
    g: np.ndarray


@dataclass(frozen=True)
class NewtonResult:
    """Where :func:`minimize_newton` stopped: the point, L, its gradient, the Newton decrement there,
    the Hessians taken (steps), the objective evaluations and whether the convergence test held."""

    z: np.ndarray
    f: float
    g: np.ndarray
    decrement: float
    steps: int
    evaluations: int
    converged: bool
    message: str


def project_out(H: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(I - Q Q^T) H (I - Q Q^T) + c Q Q^T, Q orthonormal columns (the symmetry directions), c the median
    |diagonal| of H: their curvature made positive so that no step moves along them, the rest unchanged.
    One symmetric rank-2k update of H, in place: H - Q U^T - U Q^T, U = H Q - Q (Q^T H Q)/2 - c Q/2."""
    if Q.shape[1] == 0:
        return H
    c = float(np.median(np.abs(np.diag(H))))
    HQ = H @ Q
    U = HQ - Q @ (0.5 * (Q.T @ HQ)) - (0.5 * c) * Q
    F = H.T if H.flags.c_contiguous else H  # H symmetric: its transpose is the Fortran-ordered H BLAS updates in place
    F = blas.dgemm(-1.0, Q, U, beta=1.0, c=F, trans_b=True, overwrite_c=True)
    F = blas.dgemm(-1.0, U, Q, beta=1.0, c=F, trans_b=True, overwrite_c=True)
    return F.T if H.flags.c_contiguous else F


def factor_shifted(H: np.ndarray, previous: float | None = None) -> tuple[np.ndarray, float, bool]:
    """(the lower Cholesky factor of H + sigma I, sigma, flat). sigma is SHIFT lambda (lambda = H's largest
    |diagonal| entry) where H + sigma I factors, or FLAT lambda (both: ``flat``); else, starting from a
    third of ``previous`` (the last iteration's sigma), or at the first iteration from 1.5 times the
    smallest eigenvalue's magnitude by Lanczos (4 FLAT lambda where it does not converge), tripled until
    it factors."""
    n = H.shape[0]
    scale = float(np.max(np.abs(np.diag(H))))
    A = H.copy()
    diag = np.diag_indices(n)
    tried = 0.0

    def attempt(sigma: float) -> np.ndarray | None:
        nonlocal tried
        A[diag] += sigma - tried
        tried = sigma
        L, info = lapack.dpotrf(A, lower=1, clean=1, overwrite_a=0)
        return L if info == 0 else None

    first = (SHIFT, FLAT) if previous is None or previous <= 10 * FLAT * scale else (SHIFT,)
    for rel in first:
        L = attempt(rel * scale)
        if L is not None:
            return L, rel * scale, True
    sigma = 4 * FLAT * scale
    if previous is not None:
        sigma = max(sigma, previous / 3)
    else:  # no earlier shift to start from: the smallest eigenvalue, where Lanczos finds it quickly
        try:
            lowest = float(sparse_linalg.eigsh(H, k=1, which="SA", tol=1e-2, maxiter=20, v0=np.ones(n),
                                               return_eigenvectors=False)[0])
            sigma = max(sigma, -1.5 * lowest)
        except sparse_linalg.ArpackNoConvergence:
            pass
    for _ in range(100):
        L = attempt(sigma)
        if L is not None:
            return L, sigma, False
        sigma *= 3.0
    raise np.linalg.LinAlgError("no shift makes the Hessian positive definite (not finite?)")


def steihaug(H: np.ndarray, g: np.ndarray, L: np.ndarray, delta: float, tol: float,
             max_iterations: int) -> tuple[np.ndarray, int]:
    """The Steihaug-Toint step: conjugate gradients on H s = -g preconditioned by M = L L^T, from s = 0,
    until the preconditioned residual falls by ``tol``, the step reaches ||s||_M = delta, or a direction
    of negative curvature is met (then followed to the boundary). Returns the step and the iterations."""

    def solve(r: np.ndarray) -> np.ndarray:
        return lapack.dpotrs(L, r, lower=1)[0]

    s = np.zeros_like(g)
    r = g.copy()
    y = solve(r)
    p = -y
    ry = float(r @ y)
    if not ry > 0.0:  # a zero gradient: no step
        return s, 0
    stop = tol * np.sqrt(max(ry, 0.0))
    sMs, sMp, pMp = 0.0, 0.0, ry  # s^T M s, s^T M p, p^T M p by recurrence

    def to_boundary() -> np.ndarray:
        tau = (-sMp + np.sqrt(sMp * sMp + pMp * max(delta * delta - sMs, 0.0))) / pMp
        return s + tau * p

    for k in range(max_iterations):
        Hp = H @ p
        curvature = float(p @ Hp)
        if curvature <= 0.0:
            return to_boundary(), k + 1
        alpha = ry / curvature
        if sMs + 2.0 * alpha * sMp + alpha * alpha * pMp >= delta * delta:
            return to_boundary(), k + 1
        s = s + alpha * p
        sMs += 2.0 * alpha * sMp + alpha * alpha * pMp
        r = r + alpha * Hp
        y = solve(r)
        ry_new = float(r @ y)
        if np.sqrt(max(ry_new, 0.0)) <= stop:
            return s, k + 1
        beta = ry_new / ry
        ry = ry_new
        sMp = beta * (sMp + alpha * pMp)
        pMp = ry + beta * beta * pMp
        p = -y + beta * p
    return s, max_iterations


def minimize_newton(evaluate: Callable[[np.ndarray], Point | None], hessian: Callable[[Point], np.ndarray],
                    z0: np.ndarray, lower: np.ndarray, upper: np.ndarray, ftol: float, max_steps: int,
                    on_step: Callable[[int, float, float], None] | None = None, reuse: int = 10,
                    symmetries: Callable[[np.ndarray], np.ndarray] | None = None, cg_tol: float = 1e-2,
                    max_cg: int = 50) -> NewtonResult:
    """Minimise L from ``z0`` within the box [lower, upper] (steps are clipped to it) until the convergence
    test holds (module doc), or ``max_steps`` Hessians. ``evaluate(z)`` is L and its gradient at z (None where
    L is undefined), ``hessian(point)`` its Hessian there, ``symmetries(z)`` (optional) an orthonormal basis
    of the directions L is exactly invariant along at z, projected out of every Hessian."""
    z = np.clip(np.asarray(z0, float), lower, upper)
    point = evaluate(z)
    if point is None:
        raise np.linalg.LinAlgError("the starting point's kernel matrices cannot be factored")
    evaluations, delta, sigma = 1, -1.0, None
    decrement, converged, message = np.inf, False, f"stopped after {max_steps} steps (not converged)"
    steps = 0
    for steps in range(max_steps + 1):
        H = hessian(point)
        if symmetries is not None:
            H = project_out(H, symmetries(z))
        L, sigma, flat = factor_shifted(H, sigma)
        newton = -lapack.dpotrs(L, point.g, lower=1)[0]
        decrement = -0.5 * float(point.g @ newton)
        if on_step is not None:
            on_step(steps, point.f, decrement)
        if flat and decrement <= ftol * max(abs(point.f), 1.0):
            converged, message = True, f"Newton decrement {decrement:.3g} <= ftol |L| after {steps} steps"
            # the certified Newton step itself: the minimum to about the square of the remaining error
            final = np.clip(z + newton, lower, upper)
            new = evaluate(final)
            evaluations += 1
            if new is not None and new.f <= point.f:
                z, point = final, new
            break
        if steps == max_steps:
            break
        if delta < 0:  # the first radius: a tenth of the Newton step's length in the M-norm
            delta = 0.1 * np.sqrt(2.0 * decrement)
        taken, newton_tried = 0, False
        while taken < reuse:
            s, _ = steihaug(H, point.g, L, delta, cg_tol, max_cg)
            if taken == 0 and flat and not newton_tried and _predicted(H, point.g, s) <= NOISE * abs(point.f):
                s, newton_tried = newton, True  # the radius collapsed on a flat Hessian: its Newton step
            trial = np.clip(z + s, lower, upper)
            s = trial - z
            predicted = _predicted(H, point.g, s)
            if predicted <= NOISE * abs(point.f):  # no decrease L's rounding could tell from none
                break
            new = evaluate(trial)
            evaluations += 1
            rho = (point.f - new.f) / predicted if new is not None and np.isfinite(new.f) else -1.0
            length = np.sqrt(max(float(s @ (H @ s)) + sigma * float(s @ s), 0.0))  # ||s||_M
            if rho < 0.25:
                delta = 0.25 * min(delta, length)
            elif rho > 0.75 and length >= 0.99 * delta:
                delta *= 2.0
            if rho > 1e-4 and new is not None:
                z, point = trial, new
                taken += 1
                if rho < 0.25:  # the model no longer predicts: a fresh Hessian
                    break
            elif taken > 0:  # rejected with a reused Hessian: a fresh one
                break
        if taken == 0:
            message = (f"no step lowers L (Newton decrement {decrement:.3g}, "
                       f"{'no' if flat else 'negative'} curvature)")
            break
    return NewtonResult(z=z, f=point.f, g=point.g, decrement=decrement, steps=steps, evaluations=evaluations,
                        converged=converged, message=message)


def _predicted(H: np.ndarray, g: np.ndarray, s: np.ndarray) -> float:
    """The decrease the quadratic model predicts for the step s."""
    return -float(g @ s + 0.5 * (s @ (H @ s)))
