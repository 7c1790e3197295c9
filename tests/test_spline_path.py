"""The spline path: fixed boundary rows, the fit, the decision vector, quadrature and grid nodes."""

import numpy as np
import pytest

from latentoc.latent.spline import BSpline
from latentoc.latent.spline_path import (SplinePath, constraint_times, fit_control_points, fixed_rows, gauss_legendre_nodes,
                                  trapezoid_cost)


@pytest.fixture
def samples():
    t = np.linspace(0.0, 2.9, 40)
    X = np.stack([np.sin(t), np.cos(2 * t), t ** 2], axis=1)
    return t, X


def test_rest_boundary_fixes_poses_and_zero_end_velocity(samples):
    t, X = samples
    sp = BSpline(7, 2.9)
    P = fit_control_points(sp, t, X, "rest")
    assert np.allclose(sp.evaluate(P, [0.0, 2.9]), X[[0, -1]])
    assert np.allclose(sp.evaluate(P, [0.0, 2.9], 1), 0.0, atol=1e-12)
    P2 = fit_control_points(sp, t, X, "pose")
    assert np.allclose(P2[[0, -1]], X[[0, -1]])
    assert fixed_rows(7, "rest") == [0, 1, 5, 6] and fixed_rows(7, "pose") == [0, 6]
    with pytest.raises(ValueError, match="m >= 5"):
        fixed_rows(4, "rest")
    with pytest.raises(ValueError, match="boundary"):
        fixed_rows(7, "free")


def test_decision_vector_holds_the_free_rows_row_major(samples):
    t, X = samples
    path = SplinePath.fit(BSpline(7, 2.9), t, X, "rest")
    assert list(path.free) == [2, 3, 4] and path.n_w == 9 and path.dim == 3
    w = np.arange(9.0)
    P = path.control_points(w)
    assert np.array_equal(P[2:5], w.reshape(3, 3)) and np.array_equal(P[[0, 1, 5, 6]], path.P_init[[0, 1, 5, 6]])
    assert np.array_equal(path.decision_vector(P), w) and np.array_equal(path.w0, path.P_init[2:5].ravel())
    idx = path.index
    assert np.all(idx[[0, 1, 5, 6]] == -1) and np.array_equal(idx[2:5].ravel(), np.arange(9))
    with pytest.raises(ValueError, match="shape"):
        path.decision_vector(np.zeros((6, 3)))


def test_gauss_legendre_integrates_piecewise_polynomials_exactly():
    """n nodes per knot interval are exact for degree 2n - 1 inside each interval, so for the
    squared cubic spline (degree 6) with n = 4."""
    sp = BSpline(9, 2.9)
    tq, wq = gauss_legendre_nodes(sp, 4)
    assert len(tq) == 6 * 4 and np.isclose(wq.sum(), 2.9)
    P = np.random.default_rng(0).standard_normal((9, 2))
    exact = 0.0
    for a, b in zip(sp.breakpoints[:-1], sp.breakpoints[1:]):  # 40-point rule per interval as the reference
        xi, wi = np.polynomial.legendre.leggauss(40)
        tt = 0.5 * (b - a) * xi + 0.5 * (a + b)
        exact += 0.5 * (b - a) * wi @ np.sum(sp.evaluate(P, tt) ** 2, axis=1)
    assert np.isclose(wq @ np.sum(sp.evaluate(P, tq) ** 2, axis=1), exact, rtol=1e-12)


def test_constraint_grid_and_trapezoid():
    sp = BSpline(7, 2.9)
    grid = constraint_times(sp, 6)
    assert len(grid) == 4 * 6 - 1 and grid[0] > 0 and grid[-1] < 2.9
    assert np.allclose(np.diff(grid), 2.9 / 24)
    t = np.linspace(0.0, 1.0, 1001)
    assert np.isclose(trapezoid_cost(t ** 2, t[1] - t[0]), 1 / 3, rtol=1e-6)
