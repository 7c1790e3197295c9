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
