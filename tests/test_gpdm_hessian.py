"""The Hessian of Eq. 16: its products with a vector against central differences of the exact gradient,
the assembled Hessian against those products, column by column; the symmetries it must show."""

import numpy as np
import pytest

from latentoc.gpdm.hessian import hessian, hessian_vector
from latentoc.gpdm.objective import GPDMProblem, evaluate, pack


def _problem(lengths=(7, 6), D=5, d=3, lam=2.5, seed=0, priors=True):
    rng = np.random.default_rng(seed)
    N = sum(lengths)
    Y = rng.standard_normal((N, D))
    Y -= Y.mean(axis=0)
    shape, rate = (rng.uniform(0.5, 3.0, 7), rng.uniform(0.1, 2.0, 7)) if priors else (None, None)
    p = GPDMProblem(Y, list(lengths), d, dynamics_weight=lam, prior_shape=shape, prior_rate=rate)
    v = pack(rng.standard_normal((N, d)), np.array([0.9, 1.2, 0.15, 3.0]), np.array([1.1, 0.8, 5.0]))
    return p, v, rng.uniform(0.5, 2.0, D)


@pytest.mark.parametrize("lengths,lam,profiled", [((13,), 1.0, True), ((7, 6), 2.5, True), ((7, 6), 2.5, False)])
def test_hessian_vector_is_the_gradients_central_difference(lengths, lam, profiled):
    """H u against (g(v + h u) - g(v - h u)) / 2h for random directions in all variables (points and the
    seven log-hyperparameters), W profiled out or held."""
    p, v, w = _problem(lengths=lengths, lam=lam, seed=1)
    w = None if profiled else w
    ev = evaluate(v, p, w)
    rng = np.random.default_rng(2)
    h = 1e-5
    for _ in range(3):
        u = rng.standard_normal(v.size)
        fd = (evaluate(v + h * u, p, w).g - evaluate(v - h * u, p, w).g) / (2 * h)
        assert np.max(np.abs(hessian_vector(ev, u) - fd)) <= 1e-7 * np.max(np.abs(fd))


@pytest.mark.parametrize("lengths,d,profiled", [((13,), 3, True), ((7, 6), 3, True), ((7, 6), 2, False)])
def test_assembled_hessian_equals_its_products_column_by_column(lengths, d, profiled):
    p, v, w = _problem(lengths=lengths, d=d, seed=3)
    ev = evaluate(v, p, None if profiled else w)
    H = hessian(ev)
    cols = np.array([hessian_vector(ev, e) for e in np.eye(v.size)]).T
    assert np.max(np.abs(H - cols)) <= 1e-12 * np.max(np.abs(cols))
    assert np.max(np.abs(H - H.T)) <= 1e-12 * np.max(np.abs(H))


def test_latent_rotations_are_flat_at_a_stationary_point_only_through_the_gradient():
    """Eq. 16 is invariant under X -> X R (R orthogonal), so g(X R) = g(X) R: along a rotation generator
    t = X Omega the gradient has no component, and H t = (g_X Omega, 0), zero only where g is."""
    p, v, _ = _problem(seed=4)
    ev = evaluate(v, p)
    N, d = p.N, p.latent_dim
    X = v[:N * d].reshape(N, d)
    Om = np.zeros((d, d))
    Om[0, 1], Om[1, 0] = 1.0, -1.0
    t = np.zeros(v.size)
    t[:N * d] = (X @ Om).ravel()
    assert abs(ev.g @ t) <= 1e-10 * np.linalg.norm(ev.g) * np.linalg.norm(t)
    gX = ev.g[:N * d].reshape(N, d)
    expected = np.zeros(v.size)  # d/ds g(X e^(s Omega)) = d/ds g(X) e^(s Omega) at s = 0
    expected[:N * d] = (gX @ Om).ravel()
    np.testing.assert_allclose(hessian_vector(ev, t), expected, atol=1e-9 * np.max(np.abs(hessian(ev))))


def test_fixed_hyperparameters_are_left_out():
    """With beta_1 fixed (learning's default), the Hessian of the other variables: the full one without
    that row and column."""
    p, v, _ = _problem(seed=5)
    ev = evaluate(v, p)
    keep = np.ones(7, dtype=bool)
    keep[4] = False
    free = np.r_[np.ones(v.size - 7, dtype=bool), keep]
    np.testing.assert_array_equal(hessian(ev, keep), hessian(ev)[np.ix_(free, free)])
