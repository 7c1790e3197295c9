"""Eq. 16 objective: value against a direct dense formula, gradient against
central finite differences, W update, sequence index construction."""

import numpy as np
import pytest

from latentoc.gpdm.objective import (GPDMProblem, neg_log_posterior, optimal_w, pack,
                                     safe_cholesky, sequence_indices, unpack)


def _problem(lengths=(7, 6), D=5, d=2, lam=1.0, seed=0):
    rng = np.random.default_rng(seed)
    N = sum(lengths)
    Y = rng.standard_normal((N, D))
    Y -= Y.mean(axis=0)
    p = GPDMProblem(Y, list(lengths), d, dynamics_weight=lam)
    v = pack(rng.standard_normal((N, d)), np.array([0.9, 1.2, 0.15, 3.0]),
             np.array([1.1, 0.8, 5.0]))
    w = rng.uniform(0.5, 2.0, D)
    return p, v, w


def _direct_value(p, v, w):
    """Eq. 16 (+ N(0,I) prior on sequence starts) written out with loops and slogdet."""
    N, D, d = p.N, p.D, p.latent_dim
    X, a, b = unpack(v, N, d)
    KY = np.array([[b[0] * np.exp(-b[1] / 2 * np.sum((xi - xj) ** 2)) for xj in X] for xi in X])
    KY += np.eye(N) / b[2]
    pairs_in, pairs_out, starts, s = [], [], [], 0
    for n in p.sequence_lengths:
        starts.append(s)
        for t in range(s + 1, s + n):
            pairs_in.append(X[t - 1])
            pairs_out.append(X[t])
        s += n
    Xin, Xout = np.array(pairs_in), np.array(pairs_out)
    KX = np.array([[a[0] * np.exp(-a[1] / 2 * np.sum((xi - xj) ** 2)) + a[2] * xi @ xj
                    for xj in Xin] for xi in Xin]) + np.eye(len(Xin)) / a[3]
    Yw = p.Y @ np.diag(w)
    LY = D / 2 * np.linalg.slogdet(KY)[1] + 0.5 * np.trace(np.linalg.solve(KY, Yw @ Yw.T))
    LX = d / 2 * np.linalg.slogdet(KX)[1] + 0.5 * np.trace(np.linalg.solve(KX, Xout @ Xout.T))
    return (LY + p.dynamics_weight * LX - N * np.sum(np.log(w)) + np.sum(np.log(a))
            + np.sum(np.log(b)) + 0.5 * sum(X[i] @ X[i] for i in starts))


@pytest.mark.parametrize("lam", [1.0, 2.5])
def test_value_matches_direct_formula(lam):
    p, v, w = _problem(lam=lam)
    f, _ = neg_log_posterior(v, p, w)
    assert f == pytest.approx(_direct_value(p, v, w), rel=1e-10, abs=1e-9)


@pytest.mark.parametrize("lengths,lam", [((13,), 1.0), ((7, 6), 2.5)])
def test_gradient_matches_central_differences(lengths, lam):
    p, v, w = _problem(lengths=lengths, lam=lam, seed=1)
    _, g = neg_log_posterior(v, p, w)
    h = 1e-6
    fd = np.empty_like(v)
    for i in range(len(v)):
        e = np.zeros_like(v)
        e[i] = h
        fd[i] = (neg_log_posterior(v + e, p, w, with_grad=False)
                 - neg_log_posterior(v - e, p, w, with_grad=False)) / (2 * h)
    # all variables: latent points and the 7 log-hyperparameters
    assert np.linalg.norm(fd - g) / np.linalg.norm(fd) < 1e-5
    assert np.max(np.abs(fd - g)) / np.max(np.abs(fd)) < 1e-5


def test_sequence_indices_exclude_starts():
    i_in, i_out, first = sequence_indices([3, 4])
    assert i_in.tolist() == [0, 1, 3, 4, 5]
    assert i_out.tolist() == [1, 2, 4, 5, 6]
    assert first.tolist() == [0, 3]
    assert not set(first.tolist()) & set(i_out.tolist())
    # each pair (in, out) is a consecutive step inside one sequence
    assert np.all(i_out - i_in == 1)


def test_optimal_w_minimises_objective_in_w():
    p, v, _ = _problem(seed=2)
    X, _, b = unpack(v, p.N, p.latent_dim)
    kappa_sq = 1e6
    w = optimal_w(p.Y, X, b, kappa_sq)

    def fw(w):  # objective in w including the N(0, kappa^2) prior on w
        return neg_log_posterior(v, p, w, with_grad=False) + np.sum(w ** 2) / (2 * kappa_sq)

    h = 1e-6
    for j in range(p.D):
        e = np.zeros(p.D)
        e[j] = h * w[j]
        deriv = (fw(w + e) - fw(w - e)) / (2 * e[j])
        assert abs(deriv) < 1e-5 * p.N / w[j]


def test_optimal_w_constant_column_is_finite_and_large():
    p, v, _ = _problem(seed=3)
    Y = p.Y.copy()
    Y[:, 2] = 0.0  # a constant column after centring
    X, _, b = unpack(v, p.N, p.latent_dim)
    w = optimal_w(Y, X, b, 1e6)
    assert np.isfinite(w).all()
    assert w[2] == pytest.approx(np.sqrt(p.N * 1e6))


def test_safe_cholesky_jitter_fallback():
    rng = np.random.default_rng(4)
    A = rng.standard_normal((6, 2))
    K = A @ A.T  # rank 2: not positive definite
    L, jitter = safe_cholesky(K)
    assert jitter > 0
    np.testing.assert_allclose(L @ L.T, K + jitter * np.eye(6), atol=1e-10)
    L2, j2 = safe_cholesky(K + np.eye(6))
    assert j2 == 0.0


def _prior_problem(lengths=(7, 6), lam=2.5, seed=5):
    """A problem with random Gamma(a, b) priors on all seven hyperparameters."""
    p, v, w = _problem(lengths=lengths, lam=lam, seed=seed)
    rng = np.random.default_rng(seed + 100)
    q = GPDMProblem(p.Y, list(lengths), p.latent_dim, dynamics_weight=lam,
                    prior_shape=rng.uniform(0.5, 3.0, 7), prior_rate=rng.uniform(0.1, 2.0, 7))
    return q, v, w


def test_profiled_gradient_with_priors_matches_central_differences():
    """W profiled out (w=None) and Gamma priors: the gradient against central differences."""
    p, v, _ = _prior_problem()
    _, g = neg_log_posterior(v, p)
    h = 1e-6
    fd = np.array([(neg_log_posterior(v + h * e, p, with_grad=False) - neg_log_posterior(v - h * e, p, with_grad=False))
                   / (2 * h) for e in np.eye(v.size)])
    assert np.max(np.abs(fd - g)) / np.max(np.abs(fd)) < 1e-6


def test_profiled_value_is_the_minimum_over_w():
    """L(w=None) = min_w [L(w) + sum w^2 / (2 kappa^2)], attained at optimal_w."""
    p, v, _ = _prior_problem(seed=6)
    X, _, b = unpack(v, p.N, p.latent_dim)
    w = optimal_w(p.Y, X, b, p.kappa_sq)

    def fw(w):
        return neg_log_posterior(v, p, w, with_grad=False) + np.sum(w ** 2) / (2 * p.kappa_sq)

    f = neg_log_posterior(v, p, with_grad=False)
    assert f == pytest.approx(fw(w), rel=1e-12)
    rng = np.random.default_rng(0)
    for _ in range(5):
        assert fw(w * np.exp(0.05 * rng.standard_normal(p.D))) > f


def test_gamma_priors_are_minus_log_gamma_densities():
    """Against scipy.stats.gamma: L(priors a, b) - L(Eq. 16's 1/theta priors) =
    sum_i [-log Gamma(theta_i; a_i, b_i) - ln theta_i] + the densities' constants."""
    from scipy.special import gammaln
    from scipy.stats import gamma

    p, v, w = _prior_problem(seed=7)
    plain = GPDMProblem(p.Y, p.sequence_lengths, p.latent_dim, dynamics_weight=p.dynamics_weight)
    _, alpha, beta = unpack(v, p.N, p.latent_dim)
    theta = np.concatenate([alpha, beta])
    a, b = p.prior_shape, p.prior_rate
    expected = np.sum(-gamma.logpdf(theta, a, scale=1 / b) - np.log(theta)
                      + a * np.log(b) - gammaln(a))
    diff = neg_log_posterior(v, p, w, with_grad=False) - neg_log_posterior(v, plain, w, with_grad=False)
    assert diff == pytest.approx(expected, rel=1e-10, abs=1e-10)


def test_eq16_is_invariant_under_the_scale_of_w():
    """(beta1, beta3, W) -> (c beta1, beta3 / c, W sqrt c) leaves Eq. 16 unchanged: the reason
    learning holds beta1 = 1."""
    p, v, w = _problem(seed=8)
    X, alpha, beta = unpack(v, p.N, p.latent_dim)
    f = neg_log_posterior(v, p, w, with_grad=False)
    for c in (0.1, 3.0, 1e3):
        vc = pack(X, alpha, beta * np.array([c, 1.0, 1.0 / c]))
        assert neg_log_posterior(vc, p, w * np.sqrt(c), with_grad=False) == pytest.approx(f, rel=1e-11, abs=1e-9)


@pytest.mark.parametrize("lengths", [(13,), (7, 6)])
def test_latent_rescaling_lowers_eq16_without_bound(lengths):
    """X -> sX, alpha -> (s^2 a1, a2 / s^2, a3, a4 / s^2), beta_2 -> beta_2 / s^2 leave K_Y and
    K_X / s^2 unchanged, so Eq. 16 changes by exactly (d n - 4) ln s + (s^2 - 1) |x_1|^2 / 2
    (n the dynamics' input points): it falls without bound as s -> 0. With Gamma priors of shape
    a > 1 on the rescaled hyperparameters it rises again."""
    p, v, w = _problem(lengths=lengths, seed=9)
    X, alpha, beta = unpack(v, p.N, p.latent_dim)
    n = p.N - len(lengths)
    x1 = float(np.sum(X[p.first_idx] ** 2))
    f = neg_log_posterior(v, p, w, with_grad=False)

    def scaled(s):
        return pack(s * X, alpha * np.array([s * s, 1 / s ** 2, 1.0, 1 / s ** 2]), beta * np.array([1.0, 1 / s ** 2, 1.0]))

    for s in (0.5, 1e-2, 1e-4):
        expected = (p.latent_dim * n - 4) * np.log(s) + 0.5 * (s * s - 1) * x1
        assert neg_log_posterior(scaled(s), p, w, with_grad=False) - f == pytest.approx(expected, rel=1e-8, abs=1e-7)
    shape = np.array([2.0, 2.0, 1.0, 2.0, 1.0, 2.0, 1.0])
    q = GPDMProblem(p.Y, list(lengths), p.latent_dim, prior_shape=shape, prior_rate=np.ones(7))
    vals = [neg_log_posterior(scaled(s), q, w, with_grad=False) for s in (1.0, 1e-2, 1e-4, 1e-6)]
    assert vals[3] > vals[2] > vals[1]
