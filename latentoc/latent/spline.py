"""Clamped B-splines on [0, T] (paper Eq. 5, 20, 23-25).

``x(t, P) = sum_i p_i B_i(t)`` with ``m`` control points ``P`` (m x d). The knot vector is
clamped (the curve starts at ``p_1`` and ends at ``p_m``) and uniform inside, or uniform within
each phase of a motion with repeated knots at the phase events (:meth:`BSpline.phased`): a knot
of multiplicity k lowers a cubic's continuity there to C^(3-k). The basis matrices are numeric,
so in a transcription ``x(t_k)``, ``xdot(t_k)``, ``xddot(t_k)`` are linear maps of the control
points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from latentoc.errors import LatentocError

__all__ = ["BSpline", "SplineInputError"]


class SplineInputError(LatentocError, ValueError):
    """Spline settings or data that cannot be used."""


def _ratio(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """num / den with 0 where den = 0 (a repeated knot's empty interval)."""
    return np.divide(num, den, out=np.zeros(np.broadcast(num, den).shape), where=den != 0)


def _basis(knots: np.ndarray, degree: int, t: np.ndarray, derivative: int) -> np.ndarray:
    """The r-th derivatives of every degree-p basis function at t (len(t) x (len(knots) - p - 1)),
    by the Cox-de Boor recursion, each knot interval closed on the left, the last also on the right;
    derivatives by d/dt B_(i,p) = p (B_(i,p-1) / (k_(i+p) - k_i) - B_(i+1,p-1) / (k_(i+p+1) - k_(i+1)))."""
    k = np.asarray(knots, float)
    last = int(np.flatnonzero(k[1:] > k[:-1])[-1])  # the last non-empty interval holds t = k[-1]
    B = ((k[None, :-1] <= t[:, None]) & (t[:, None] < k[None, 1:])).astype(float)
    B[t >= k[-1], last] = 1.0
    for p in range(1, degree + 1):
        lo, hi = k[:-p - 1], k[p + 1:]  # k_i and k_(i+p+1) of the len(k) - p - 1 functions
        a, b = k[p:-1], k[1:-p]  # k_(i+p) and k_(i+1)
        if p > degree - derivative:  # a derivative's step: constant coefficients
            B = p * (_ratio(B[:, :-1], (a - lo)[None, :]) - _ratio(B[:, 1:], (hi - b)[None, :]))
        else:
            B = _ratio((t[:, None] - lo) * B[:, :-1], (a - lo)[None, :]) \
                + _ratio((hi - t[:, None]) * B[:, 1:], (hi - b)[None, :])
    return B


@dataclass(frozen=True)
class BSpline:
    """A clamped B-spline basis with ``n_control`` control points on ``[0, duration]``: uniform
    inside, or with the interior knots ``inner`` (ascending, repeats allowed)."""

    n_control: int
    duration: float
    degree: int = 3
    inner: tuple[float, ...] | None = None

    @classmethod
    def phased(cls, duration: float, events: list[float], intervals: list[int], multiplicity: list[int],
               degree: int = 3) -> "BSpline":
        """Uniform knots within each phase between the ``events`` (``intervals[i]`` polynomial pieces
        in phase i), each event a knot of ``multiplicity[i]`` (2: C1 for a cubic)."""
        bounds = [0.0, *map(float, events), float(duration)]
        if len(intervals) != len(bounds) - 1 or len(multiplicity) != len(events):
            raise SplineInputError(f"{len(events)} events need {len(events) + 1} phase interval counts and "
                                   f"{len(events)} multiplicities, got {len(intervals)} and {len(multiplicity)}")
        if any(b <= a for a, b in zip(bounds, bounds[1:])):
            raise SplineInputError(f"phase events must lie strictly inside (0, {duration}) in ascending order, got {events}")
        if any(int(n) < 1 for n in intervals) or any(not 1 <= int(k) <= degree for k in multiplicity):
            raise SplineInputError(f"each phase needs at least one interval and each event a multiplicity "
                                   f"from 1 to {degree}, got {intervals} and {multiplicity}")
        inner: list[float] = []
        for i, (a, b) in enumerate(zip(bounds, bounds[1:])):
            inner.extend(np.linspace(a, b, int(intervals[i]) + 1)[1:-1].tolist())
            if i < len(events):
                inner.extend([b] * int(multiplicity[i]))
        return cls(len(inner) + degree + 1, float(duration), degree, tuple(inner))

    def __post_init__(self) -> None:
        if self.degree < 1:
            raise SplineInputError(f"spline degree must be at least 1, got {self.degree}")
        if self.n_control < self.degree + 1:
            raise SplineInputError(
                f"a degree-{self.degree} B-spline needs at least {self.degree + 1} control points, got {self.n_control}"
            )
        if not np.isfinite(self.duration) or self.duration <= 0:
            raise SplineInputError(f"spline duration must be a positive number, got {self.duration}")
        if self.inner is not None and len(self.inner) != self.n_control - self.degree - 1:
            raise SplineInputError(f"{self.n_control} control points of degree {self.degree} need "
                                   f"{self.n_control - self.degree - 1} interior knots, got {len(self.inner)}")

    @property
    def knots(self) -> np.ndarray:
        """Clamped knot vector: ``degree + 1`` repeated knots at each end, the interior ones between."""
        inner = np.linspace(0.0, self.duration, self.n_control - self.degree + 1)[1:-1] if self.inner is None \
            else np.asarray(self.inner, float)
        return np.concatenate([np.zeros(self.degree + 1), inner, np.full(self.degree + 1, self.duration)])

    @property
    def breakpoints(self) -> np.ndarray:
        """The distinct knots: the curve is a polynomial between consecutive breakpoints."""
        return np.unique(self.knots)

    def basis(self, t: np.ndarray, derivative: int = 0, left: bool | np.ndarray = False) -> np.ndarray:
        """Matrix ``B`` (len(t) x m) with ``B[k, i] = d^r B_i / dt^r (t_k)`` (Eq. 23-25); where ``left``,
        the limit from the left (at a repeated knot the derivatives there may jump)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if np.any(t < -1e-12) or np.any(t > self.duration + 1e-12):
            raise SplineInputError(f"spline times must lie in [0, {self.duration}]")
        t = np.clip(t, 0.0, self.duration)
        t = np.where(np.asarray(left, bool) & (t > 0), np.nextafter(t, -np.inf), t)
        return _basis(self.knots, self.degree, t, int(derivative))

    def evaluate(self, P: np.ndarray, t: np.ndarray, derivative: int = 0) -> np.ndarray:
        """``x(t)`` (or its derivative) for control points ``P`` (m x d): array (len(t) x d)."""
        P = np.asarray(P, dtype=float)
        if P.shape[0] != self.n_control:
            raise SplineInputError(f"control points P has {P.shape[0]} rows, the spline has {self.n_control}")
        return self.basis(t, derivative) @ P

    def smoothing_rows(self, smoothing: float, n_points: int = 400) -> np.ndarray:
        """S (n_points x n_control) with ||S P||^2 = smoothing * int ||x''(t)||^2 dt, by the
        rectangle rule on ``n_points`` evenly spaced times (the penalty of :meth:`fit`)."""
        tq = np.linspace(0.0, self.duration, n_points)
        return np.sqrt(smoothing * self.duration / n_points) * self.basis(tq, 2)

    def fit(self, t: np.ndarray, X: np.ndarray, fix_ends: bool = True, smoothing: float = 0.0) -> np.ndarray:
        """Least-squares control points of samples ``X`` (n x d) at times ``t``.

        With ``fix_ends`` the first and last control points equal the first and last samples,
        so the fitted curve passes exactly through the end poses.  ``smoothing`` > 0 adds
        ``smoothing * int ||x''(t)||^2 dt`` (400-point rule) to the squared residual.
        """
        t = np.asarray(t, dtype=float)
        X = np.asarray(X, dtype=float)
        if X.ndim == 1:
            X = X[:, None]
        if X.shape[0] != t.size:
            raise SplineInputError(f"fit got {t.size} times but {X.shape[0]} samples")
        if not np.all(np.isfinite(X)):
            raise SplineInputError("fit samples contain NaN or inf")
        if not smoothing >= 0:
            raise SplineInputError(f"smoothing must be >= 0, got {smoothing!r}")
        B = self.basis(t)
        target = X
        if smoothing > 0:
            S = self.smoothing_rows(smoothing)
            B = np.vstack([B, S])
            target = np.vstack([X, np.zeros((S.shape[0], X.shape[1]))])
        if not fix_ends:
            return np.linalg.lstsq(B, target, rcond=None)[0]
        P = np.zeros((self.n_control, X.shape[1]))
        P[0], P[-1] = X[0], X[-1]
        rhs = target - B[:, [0]] * P[0] - B[:, [-1]] * P[-1]
        P[1:-1] = np.linalg.lstsq(B[:, 1:-1], rhs, rcond=None)[0]
        return P
