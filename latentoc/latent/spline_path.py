"""The optimised path: a clamped B-spline whose boundary control points are held (Eq. 5, 20).

x(t) = sum_i p_i B_i(t) (Eq. 20 in the latent space, Eq. 5 in joint space). The boundary rows
of P are fixed:

* ``boundary = "pose"``: p_1 and p_m, so x(0) and x(T) are the reference's end points;
* ``boundary = "rest"``: also p_2 and p_(m-1), so in addition xd(0) = xd(T) = 0 (the motion
  starts and ends at rest).

The other rows are the decision variables (row-major in w), started from the least-squares fit
of a reference path with those rows fixed (Sect. 3.2, last paragraph). The time nodes of the
NLPs are here too: Gauss-Legendre nodes in every knot interval for the objective integral
(Eq. 22), an even grid for the path constraints, and the trapezoid rule on the paper's 1 ms grid.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from latentoc.latent.spline import BSpline

__all__ = ["SplinePath", "fixed_rows", "fit_control_points", "gauss_legendre_nodes", "constraint_times",
           "trapezoid_cost"]


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
    """Even grid with ``points_per_interval`` steps per knot interval, end points excluded
    (the fixed boundary rows decide the path there)."""
    n = (len(spline.breakpoints) - 1) * int(points_per_interval)
    return np.linspace(0.0, spline.duration, n + 1)[1:-1]


def trapezoid_cost(L: np.ndarray, dt: float) -> float:
    """Trapezoid rule on an even grid of step dt (the paper's 0.001 s reference)."""
    L = np.asarray(L, dtype=float)
    return float(dt * (L.sum() - 0.5 * (L[0] + L[-1])))


@dataclass(frozen=True)
class SplinePath:
    """A spline path with its fixed rows: ``P_init`` (m x n, the fit) and the ``free`` rows."""

    spline: BSpline
    P_init: np.ndarray
    free: np.ndarray

    @classmethod
    def fit(cls, spline: BSpline, t: np.ndarray, X: np.ndarray, boundary: str) -> "SplinePath":
        """The path fitted to samples X at times t (:func:`fit_control_points`)."""
        P = fit_control_points(spline, t, X, boundary)
        fixed = fixed_rows(spline.n_control, boundary)
        return cls(spline, P, np.array([i for i in range(spline.n_control) if i not in fixed], dtype=int))

    @property
    def dim(self) -> int:
        return self.P_init.shape[1]

    @property
    def n_w(self) -> int:
        return len(self.free) * self.dim

    @property
    def w0(self) -> np.ndarray:
        """The fit's decision vector."""
        return self.P_init[self.free].ravel()

    @property
    def index(self) -> np.ndarray:
        """Position in w of each control-point entry (m x n), -1 where the row is fixed."""
        index = -np.ones(self.P_init.shape, dtype=np.int64)
        index[self.free] = np.arange(self.n_w).reshape(len(self.free), self.dim)
        return index

    def control_points(self, w: np.ndarray) -> np.ndarray:
        """Full control points P (m x n) for the decision vector w."""
        P = self.P_init.copy()
        P[self.free] = np.asarray(w, dtype=float).reshape(len(self.free), self.dim)
        return P

    def decision_vector(self, P: np.ndarray) -> np.ndarray:
        """w of full control points P (their free rows)."""
        P = np.asarray(P, dtype=float)
        if P.shape != self.P_init.shape:
            raise ValueError(f"control points have shape {P.shape}, the path's are {self.P_init.shape}")
        return P[self.free].ravel()
