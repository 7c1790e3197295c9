"""A damped saddle-free Newton method for Eq. 16: the minimiser :func:`~latentoc.gpdm.learning.learn_gpdm`
uses, written here so that its path depends only on the objective, not on scipy's version.

Each step takes the Hessian by forward differences of the exact gradient, its eigenvalues made
positive (|lambda|, so that saddle directions are descended), and the Levenberg step
s = -V diag(1 / (|lambda| + mu)) V^T g; mu follows the ratio of the actual to the predicted decrease
(a trust region in the Hessian's metric). It stops when the Newton decrement 1/2 g^T |H|^-1 g, the
decrease a Newton step predicts, is at most ``ftol`` |L|. Tens of iterations, each far from
rounding noise, so the same data give the same model on any BLAS, thread count or library version.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["NewtonResult", "fd_hessian", "minimize_newton"]

Objective = Callable[[np.ndarray], tuple[float, np.ndarray]]


@dataclass(frozen=True)
class NewtonResult:
    """Where :func:`minimize_newton` stopped: the point, L, its gradient, the Newton decrement there,
    the steps taken, the objective evaluations and whether the decrement test held."""

    z: np.ndarray
    f: float
    g: np.ndarray
    decrement: float
    steps: int
    evaluations: int
    converged: bool
    message: str


def fd_hessian(grad: Callable[[np.ndarray], np.ndarray], z: np.ndarray, g: np.ndarray,
               rel_step: float = 1e-6) -> np.ndarray:
    """Hessian by forward differences of the exact gradient ``grad`` (``g`` = grad(z)), symmetrised."""
    n = z.size
    H = np.empty((n, n))
    for j in range(n):
        h = rel_step * max(1.0, abs(float(z[j])))
        e = z.copy()
        e[j] += h
        H[:, j] = (grad(e) - g) / h
    return 0.5 * (H + H.T)


def minimize_newton(fg: Objective, z0: np.ndarray, lower: np.ndarray, upper: np.ndarray, ftol: float,
                    max_steps: int, on_step: Callable[[int, float, float], None] | None = None,
                    reuse: int = 10) -> NewtonResult:
    """Minimise ``fg`` (value and gradient) from ``z0`` within the box [lower, upper] (steps are
    clipped to it) until the Newton decrement <= ftol max(|L|, 1), or ``max_steps`` Hessians. Each
    Hessian serves up to ``reuse`` steps (the gradient fresh, the curvature kept) while they do
    what it predicts; convergence is only ever tested on a fresh one."""
    z = np.clip(np.asarray(z0, float), lower, upper)
    f, g = fg(z)
    evaluations, mu = 1, -1.0
    step, k = _Step(z, f, g, mu, 1.0, 0), 0
    decrement, converged, message = np.inf, False, f"stopped after {max_steps} steps (not converged)"
    steps = 0
    for steps in range(max_steps + 1):
        H = fd_hessian(lambda x: fg(x)[1], z, g)
        evaluations += z.size
        lam, V = np.linalg.eigh(H)
        a = np.abs(lam)
        a = np.maximum(a, 1e-8 * float(a.max()))  # flat directions (the latent rotations): no curvature to trust
        gv = V.T @ g
        decrement = 0.5 * float(np.sum(gv * gv / a))
        if on_step is not None:
            on_step(steps, f, decrement)
        if decrement <= ftol * max(abs(f), 1.0):
            converged, message = True, f"Newton decrement {decrement:.3g} <= ftol |L| after {steps} steps"
            break
        if steps == max_steps:
            break
        if mu < 0:  # the first step: damping at the scale of the Hessian's median curvature
            mu = float(np.median(a))
        # steps with this Hessian while they keep the model's predicted decrease (rho >= 1/4)
        for k in range(reuse):
            step = _damped_step(fg, z, f, g, V, a, mu, lower, upper)
            evaluations += step.evaluations
            if step.z is None:  # with a stale Hessian: take a fresh one; with a fresh one: give up
                break
            z, f, g, mu = step.z, step.f, step.g, step.mu
            if step.rho < 0.25:
                break
        if step.z is None and k == 0:
            message = "no step lowers L (the damping ran away)"
            break
    return NewtonResult(z=z, f=f, g=g, decrement=decrement, steps=steps, evaluations=evaluations,
                        converged=converged, message=message)


@dataclass
class _Step:
    z: np.ndarray | None
    f: float
    g: np.ndarray
    mu: float
    rho: float
    evaluations: int


def _damped_step(fg: Objective, z: np.ndarray, f: float, g: np.ndarray, V: np.ndarray, a: np.ndarray, mu: float,
                 lower: np.ndarray, upper: np.ndarray) -> _Step:
    """One accepted Levenberg step s = -V (V^T g / (a + mu)), mu raised until L falls; z None if it
    never does. mu afterwards follows rho, the actual over the predicted decrease."""
    gv = V.T @ g
    for k in range(80):
        c = gv / (a + mu)
        trial = np.clip(z - V @ c, lower, upper)
        predicted = float(np.sum(gv * c) - 0.5 * np.sum(a * c * c))
        f_new, g_new = fg(trial)
        rho = (f - f_new) / predicted if predicted > 0 else -1.0
        if np.isfinite(f_new) and rho > 1e-4:
            mu = mu / 3.0 if rho > 0.75 else (mu * 2.0 if rho < 0.25 else mu)
            return _Step(trial, float(f_new), g_new, mu, rho, k + 1)
        mu *= 8.0
    return _Step(None, f, g, mu, -1.0, 80)
