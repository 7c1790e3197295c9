"""A damped saddle-free Newton method for Eq. 16, with the exact Hessian: the minimiser
:func:`~latentoc.gpdm.learning.learn_gpdm` uses, written here so that its path depends only on the
objective, not on scipy's version.

Each iteration takes the Hessian (:func:`latentoc.gpdm.hessian.hessian`, assembled from the
factors the gradient computed), its eigenvalues made positive (|lambda|, so that saddle directions
are descended), and Levenberg steps s = -V diag(1 / (|lambda| + mu)) V^T g; mu follows the ratio of
the actual to the predicted decrease (a trust region in the Hessian's metric). A Hessian serves up
to ``reuse`` steps while they decrease L as predicted. It stops when the Newton decrement
1/2 g^T |H|^-1 g, the decrease a Newton step predicts, is at most ``ftol`` |L| on a fresh Hessian,
and takes that Newton step (if L does not rise): the point returned is the minimum to about the
square of the certified error, not wherever the path stopped.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

__all__ = ["NewtonResult", "Point", "minimize_newton"]


class Point(Protocol):
    """An evaluated point: L and its gradient (whatever else the Hessian needs is the caller's)."""

    f: float
    g: np.ndarray


@dataclass(frozen=True)
class NewtonResult:
    """Where :func:`minimize_newton` stopped: the point, L, its gradient, the Newton decrement there,
    the Hessians taken (steps), the objective evaluations and whether the decrement test held."""

    z: np.ndarray
    f: float
    g: np.ndarray
    decrement: float
    steps: int
    evaluations: int
    converged: bool
    message: str


def minimize_newton(evaluate: Callable[[np.ndarray], Point | None], hessian: Callable[[Point], np.ndarray],
                    z0: np.ndarray, lower: np.ndarray, upper: np.ndarray, ftol: float, max_steps: int,
                    on_step: Callable[[int, float, float], None] | None = None, reuse: int = 10) -> NewtonResult:
    """Minimise L from ``z0`` within the box [lower, upper] (steps are clipped to it) until the Newton
    decrement <= ftol max(|L|, 1), or ``max_steps`` Hessians. ``evaluate(z)`` is L and its gradient at
    z (None where L is undefined), ``hessian(point)`` its Hessian there. Each Hessian serves up to
    ``reuse`` steps (the gradient fresh, the curvature kept) while they do what it predicts;
    convergence is only ever tested on a fresh one."""
    z = np.clip(np.asarray(z0, float), lower, upper)
    point = evaluate(z)
    if point is None:
        raise np.linalg.LinAlgError("the starting point's kernel matrices cannot be factored")
    evaluations, mu, k = 1, -1.0, 0
    step = _Step(z, point, mu, 1.0, 0)
    decrement, converged, message = np.inf, False, f"stopped after {max_steps} steps (not converged)"
    steps = 0
    for steps in range(max_steps + 1):
        H = hessian(point)
        lam, V = np.linalg.eigh(H)
        del H
        a = np.abs(lam)
        a = np.maximum(a, 1e-8 * float(a.max()))  # flat directions (the latent rotations): no curvature to trust
        gv = V.T @ point.g
        decrement = 0.5 * float(np.sum(gv * gv / a))
        if on_step is not None:
            on_step(steps, point.f, decrement)
        if decrement <= ftol * max(abs(point.f), 1.0):
            converged, message = True, f"Newton decrement {decrement:.3g} <= ftol |L| after {steps} steps"
            # the certified Newton step itself: the minimum to about the square of the remaining error
            final = np.clip(z - V @ (gv / a), lower, upper)
            new = evaluate(final)
            evaluations += 1
            if new is not None and new.f <= point.f:
                z, point = final, new
            break
        if steps == max_steps:
            break
        if mu < 0:  # the first step: damping at the scale of the Hessian's median curvature
            mu = float(np.median(a))
        # steps with this Hessian while they keep the model's predicted decrease (rho >= 1/4)
        for k in range(reuse):
            step = _damped_step(evaluate, z, point, V, a, mu, lower, upper)
            evaluations += step.evaluations
            if step.z is None:  # with a stale Hessian: take a fresh one; with a fresh one: give up
                break
            z, point, mu = step.z, step.point, step.mu
            if step.rho < 0.25:
                break
        if step.z is None and k == 0:
            message = "no step lowers L (the damping ran away)"
            break
    return NewtonResult(z=z, f=point.f, g=point.g, decrement=decrement, steps=steps, evaluations=evaluations,
                        converged=converged, message=message)


NOISE = 64 * float(np.finfo(float).eps)  # relative rounding of L summed over its terms


@dataclass
class _Step:
    z: np.ndarray | None
    point: Point
    mu: float
    rho: float
    evaluations: int


def _damped_step(evaluate: Callable[[np.ndarray], Point | None], z: np.ndarray, point: Point, V: np.ndarray,
                 a: np.ndarray, mu: float, lower: np.ndarray, upper: np.ndarray) -> _Step:
    """One accepted Levenberg step s = -V (V^T g / (a + mu)), mu raised until L falls; z None if it
    never does. mu afterwards follows rho, the actual over the predicted decrease."""
    gv = V.T @ point.g
    noise = NOISE * abs(point.f)  # a decrease L's rounding cannot tell from none
    for k in range(80):
        c = gv / (a + mu)
        trial = np.clip(z - V @ c, lower, upper)
        predicted = float(np.sum(gv * c) - 0.5 * np.sum(a * c * c))
        if predicted <= noise:  # more damping predicts less: no step can be seen to lower L
            return _Step(None, point, mu, -1.0, k)
        new = evaluate(trial)
        rho = (point.f - new.f) / predicted if new is not None and predicted > 0 else -1.0
        if new is not None and np.isfinite(new.f) and rho > 1e-4:
            mu = mu / 3.0 if rho > 0.75 else (mu * 2.0 if rho < 0.25 else mu)
            return _Step(trial, new, mu, rho, k + 1)
        mu *= 8.0
    return _Step(None, point, mu, -1.0, 80)
