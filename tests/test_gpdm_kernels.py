"""Kernels of Eq. 11 and Eq. 15 against element-by-element formulas."""

import numpy as np
import pytest

from latentoc.gpdm.kernels import rbf_kernel, rbf_linear_kernel, sq_dist


def _rbf_loop(X1, X2, b1, b2):
    K = np.empty((len(X1), len(X2)))
    for i, a in enumerate(X1):
        for j, b in enumerate(X2):
            K[i, j] = b1 * np.exp(-b2 / 2 * np.dot(a - b, a - b))
    return K


@pytest.fixture
def pts():
    rng = np.random.default_rng(3)
    return rng.standard_normal((9, 3)), rng.standard_normal((5, 3))


def test_sq_dist_matches_loop(pts):
    X1, X2 = pts
    ref = np.array([[np.sum((a - b) ** 2) for b in X2] for a in X1])
    np.testing.assert_allclose(sq_dist(X1, X2), ref, rtol=1e-12, atol=1e-12)
    S = sq_dist(X1)
    assert np.all(np.diag(S) == 0.0) and np.all(S >= 0.0)
    np.testing.assert_allclose(S, S.T, atol=0)


def test_rbf_kernel_eq11(pts):
    X1, X2 = pts
    beta = np.array([1.7, 0.6, 25.0])
    np.testing.assert_allclose(rbf_kernel(X1, X2, beta), _rbf_loop(X1, X2, 1.7, 0.6), rtol=1e-12)
    K = rbf_kernel(X1, None, beta, noise=True)
    ref = _rbf_loop(X1, X1, 1.7, 0.6) + np.eye(len(X1)) / 25.0
    np.testing.assert_allclose(K, ref, rtol=1e-12)
    # a valid covariance: symmetric positive definite, smallest eigenvalue >= noise
    assert np.min(np.linalg.eigvalsh(K)) > 1 / 25.0 - 1e-12


def test_rbf_linear_kernel_eq15(pts):
    X1, X2 = pts
    alpha = np.array([0.9, 1.3, 0.2, 40.0])
    ref = _rbf_loop(X1, X2, 0.9, 1.3) + 0.2 * np.array([[a @ b for b in X2] for a in X1])
    np.testing.assert_allclose(rbf_linear_kernel(X1, X2, alpha), ref, rtol=1e-12)
    K = rbf_linear_kernel(X1, None, alpha, noise=True)
    ref = (_rbf_loop(X1, X1, 0.9, 1.3) + 0.2 * X1 @ X1.T) + np.eye(len(X1)) / 40.0
    np.testing.assert_allclose(K, ref, rtol=1e-12)


def test_noise_only_for_training_matrix(pts):
    X1, X2 = pts
    with pytest.raises(ValueError):
        rbf_kernel(X1, X2, [1, 1, 1], noise=True)
    with pytest.raises(ValueError):
        rbf_linear_kernel(X1, X2, [1, 1, 1, 1], noise=True)
