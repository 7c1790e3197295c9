"""B-spline basis against scipy's de Boor evaluation, finite differences and exact fits."""

import numpy as np
import pytest

from latentoc.latent.spline import BSpline, SplineInputError


def test_partition_of_unity_and_clamped_ends():
    s = BSpline(9, 2.9)
    t = np.linspace(0, 2.9, 301)
    B = s.basis(t)
    assert np.allclose(B.sum(axis=1), 1.0, atol=1e-12)
    assert np.allclose(B[0], np.eye(9)[0]) and np.allclose(B[-1], np.eye(9)[-1])
    assert np.allclose(s.basis(t, 1).sum(axis=1), 0.0, atol=1e-10)


def test_derivatives_match_finite_differences():
    s = BSpline(7, 1.3)
    P = np.random.default_rng(0).normal(size=(7, 3))
    t = np.linspace(0.05, 1.25, 50)
    h = 1e-6
    for r in (1, 2):
        fd = (s.evaluate(P, t + h, r - 1) - s.evaluate(P, t - h, r - 1)) / (2 * h)
        assert np.allclose(s.evaluate(P, t, r), fd, rtol=1e-5, atol=1e-4)


def test_fit_reproduces_a_cubic_exactly():
    # a cubic polynomial lies in the spline space: the least-squares fit is exact
    s = BSpline(6, 2.0)
    t = np.linspace(0, 2, 80)
    X = np.stack([t**3 - t, 0.5 * t**2 + 1], axis=1)
    P = s.fit(t, X)
    assert np.allclose(s.evaluate(P, t), X, atol=1e-10)
    assert np.allclose(P[0], X[0]) and np.allclose(P[-1], X[-1])


def test_bad_input():
    with pytest.raises(SplineInputError, match="at least 4 control points"):
        BSpline(3, 1.0)
    with pytest.raises(SplineInputError, match="duration"):
        BSpline(5, -1.0)
    with pytest.raises(SplineInputError, match="NaN"):
        BSpline(5, 1.0).fit(np.linspace(0, 1, 10), np.full((10, 2), np.nan))


def test_smoothing_trades_fit_for_curvature_and_tends_to_the_line():
    """The smoothing penalty lowers int ||x''||^2 monotonically; a huge one leaves the straight
    line through the fixed end samples (analytic: the clamped spline reproduces linear functions)."""
    sp = BSpline(12, 2.0)
    t = np.linspace(0.0, 2.0, 80)
    rng = np.random.default_rng(0)
    X = np.column_stack([np.sin(3 * t), t ** 2]) + 0.05 * rng.standard_normal((80, 2))
    tq = np.linspace(0.0, 2.0, 2001)

    def curvature(P):
        return np.trapezoid(np.sum(sp.evaluate(P, tq, 2) ** 2, axis=1), tq)

    c = [curvature(sp.fit(t, X, smoothing=lam)) for lam in (0.0, 1e-4, 1e-2, 1.0)]
    assert np.all(np.diff(c) < 0)
    assert np.allclose(sp.fit(t, X, smoothing=0.0), sp.fit(t, X))
    P = sp.fit(t, X, smoothing=1e9)
    line = X[0] + (X[-1] - X[0]) * (tq / 2.0)[:, None]
    assert np.max(np.abs(sp.evaluate(P, tq) - line)) < 1e-4
    with pytest.raises(SplineInputError, match="smoothing"):
        sp.fit(t, X, smoothing=-1.0)


def test_smoothing_rows_integrate_the_squared_second_derivative():
    """||S P||^2 = smoothing * int ||x''||^2 dt, analytic for x = t^3 on [0, 2]: 36 * 8 / 3 = 96."""
    sp = BSpline(8, 2.0)
    t = np.linspace(0.0, 2.0, 50)
    P = sp.fit(t, t[:, None] ** 3)
    assert np.isclose(np.sum((sp.smoothing_rows(0.5) @ P) ** 2), 0.5 * 96.0, rtol=1e-2)


def test_phased_knots_lower_the_continuity_at_the_events_only():
    """BSpline.phased: a double knot at each event leaves the path and its velocity continuous there
    and lets the acceleration jump (C1), uniform pieces in each phase (C2 at their joints), against
    one-sided values; a single knot keeps C2; piecewise cubics of the phases are fitted exactly."""
    sp = BSpline.phased(1.3, [0.2, 0.3, 0.7], [2, 1, 4, 5], [2, 2, 1])
    assert sp.n_control == len(sp.knots) - 4 and sp.n_control == 2 + 1 + 4 + 5 + 3 - 1 + 3
    np.testing.assert_allclose(sp.breakpoints, [0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.82, 0.94, 1.06, 1.18, 1.3])
    P = np.random.default_rng(3).normal(size=(sp.n_control, 2))
    e = 1e-10
    for t, jumps in ((0.2, True), (0.3, True), (0.7, False), (0.5, False)):
        left, right = ([sp.evaluate(P, [t + s], k) for k in range(3)] for s in (-e, e))
        np.testing.assert_allclose(left[0], right[0], atol=1e-8)
        np.testing.assert_allclose(left[1], right[1], atol=1e-6)
        assert (np.abs(left[2] - right[2]).max() > 1.0) == jumps
    # a motion made of a different cubic on each side of a double knot is in the space
    t = np.linspace(0, 1.3, 200)
    s = t - 0.3  # C1 at 0.3: 1.027, slope 0.27 both sides
    x = np.where(s < 0, 1 + t ** 3, 1.027 + 0.27 * s + 0.9 * s ** 2 - 2 * s ** 3)
    fit = sp.fit(t, x[:, None], fix_ends=False)
    np.testing.assert_allclose(sp.evaluate(fit, t)[:, 0], x, atol=1e-10)


def test_phased_spline_refuses_events_and_counts_that_do_not_fit():
    with pytest.raises(SplineInputError, match="events must lie strictly inside"):
        BSpline.phased(1.0, [0.5, 0.4], [1, 1, 1], [2, 2])
    with pytest.raises(SplineInputError, match="need 3 phase interval counts"):
        BSpline.phased(1.0, [0.4, 0.5], [1, 1], [2, 2])
    with pytest.raises(SplineInputError, match="multiplicity from 1 to 3"):
        BSpline.phased(1.0, [0.4], [1, 1], [4])
    with pytest.raises(SplineInputError, match="interior knots"):
        BSpline(8, 1.0, inner=(0.5,))


@pytest.mark.parametrize("spline", [BSpline(9, 2.9), BSpline(7, 1.0, 2), BSpline(5, 2.0, 1),
                                    BSpline.phased(1.3, [0.4, 0.6], [3, 2, 4], [2, 2]),
                                    BSpline.phased(1.3, [0.4, 0.6, 0.9], [3, 2, 4, 2], [2, 1, 3])])
def test_basis_equals_scipys_de_boor_evaluation(spline):
    """Every derivative scipy defines (it refuses those beyond a repeated knot's continuity), at
    even times, at every knot and at random times, from the right and from the left."""
    from scipy.interpolate import BSpline as ScipyBSpline

    k = spline.knots
    t = np.concatenate([np.linspace(0, spline.duration, 301), np.unique(k),
                        np.random.default_rng(0).uniform(0, spline.duration, 50)])
    ref = ScipyBSpline(k, np.eye(spline.n_control), spline.degree, extrapolate=False)
    compared = 0
    for r in range(spline.degree + 1):
        try:
            fn = ref.derivative(r) if r else ref
        except ValueError:
            continue
        for left in (False, True):
            tt = np.where(left & (t > 0), np.nextafter(t, -np.inf), t)
            want = np.nan_to_num(fn(tt), nan=0.0)
            np.testing.assert_allclose(spline.basis(t, r, left), want, rtol=0, atol=1e-12 * max(1.0, np.abs(want).max()))
            compared += 1
    assert compared >= 4
