"""The assembled broad-jump NLP (latentoc.jump.nlp.build_nlp): its exact derivatives against
central differences, on a jump with few nodes (every row family, wrench samples every 50 ms).

The Jacobian is compared column by column with central differences of the constraints, the
objective's gradient with those of the objective, and the exact Hessian of the Lagrangian
(sigma f + lam . g, upper triangle in its sparsity pattern) along random directions with
central differences of the Lagrangian's gradient (sigma grad f + J^T lam); each row against
its own scale, so a small row family's error is not hidden by a large one's.
"""
import numpy as np
import pytest
import scipy.sparse as sp

H_FD = 1e-6


def _csc(sparsity, values):
    return sp.csc_matrix((values, np.array(sparsity.row()), np.array(sparsity.colind())),
                         shape=(sparsity.size1(), sparsity.size2())).toarray()


def _points(sj):
    """The training start with random multipliers, and a random point near it with others."""
    rng = np.random.default_rng(11)
    x0, m = sj.x0, sj.nlp.nlp.m
    x1 = x0 + 0.02 * rng.standard_normal(x0.size) * np.maximum(1.0, np.abs(x0))
    return {"start": (x0, 1.0, rng.standard_normal(m)), "random": (x1, 0.7, rng.standard_normal(m))}


@pytest.fixture(scope="module", params=["start", "random"])
def point(request, small_jump):
    return (small_jump, *_points(small_jump)[request.param])


def test_jacobian_and_gradient_match_central_differences(point):
    """Every column of the sparse Jacobian (its pattern included) against central differences of
    the constraints, row by row relative to the row's largest entry; the objective's gradient
    against central differences of the objective."""
    sj, x, _, _ = point
    nlp = sj.nlp.nlp
    J = _csc(nlp.jac_sparsity, nlp.jacobian(x))
    grad = nlp.gradient(x)
    assert J.shape == (nlp.m, x.size)
    fd, fd_grad = np.empty_like(J), np.empty_like(grad)
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = H_FD
        fd[:, j] = (nlp.constraints(x + e) - nlp.constraints(x - e)) / (2 * H_FD)
        fd_grad[j] = (nlp.objective(x + e) - nlp.objective(x - e)) / (2 * H_FD)
    scale = np.maximum(1.0, np.abs(J).max(axis=1))
    err = np.abs(fd - J).max(axis=1) / scale
    worst = int(np.argmax(err))
    assert err[worst] < 1e-6, (sj.nlp.row_names[worst], err[worst])
    # every row family has entries, and the pattern is not padded with many structural zeros
    names = sj.nlp.row_names
    for name in set(names):
        assert np.abs(J[names == name]).max() > 0, name
    assert np.count_nonzero(J) > 0.5 * nlp.jac_sparsity.nnz()
    np.testing.assert_allclose(grad, fd_grad, atol=1e-7)
    assert grad[sj.nlp.variables.index("x_L")[0]] == pytest.approx(-1.0)  # maximise the distance


def test_exact_hessian_matches_central_differences_of_the_lagrangian_gradient(point):
    """The Hessian of the Lagrangian (node Hessians through the GP layer's tangents and curvature,
    chained through the affine node inputs) against central differences of sigma grad f + J^T lam
    along random directions and along each variable block's first coordinate (fourth-order
    central differences)."""
    sj, x, sigma, lam = point
    nlp, var = sj.nlp.nlp, sj.nlp.variables
    Hu = _csc(nlp.hess_sparsity, nlp.hessian(x, sigma, lam))
    assert np.allclose(np.tril(Hu, -1), 0.0)
    H = Hu + Hu.T - np.diag(np.diag(Hu))

    def grad_lagrangian(v):
        return sigma * nlp.gradient(v) + _csc(nlp.jac_sparsity, nlp.jacobian(v)).T @ lam

    rng = np.random.default_rng(12)
    directions = [rng.standard_normal(x.size) for _ in range(4)]
    directions += [np.eye(x.size)[var.slices[name].start] for name in var.shapes]
    h = 1e-4  # fourth-order central differences: rounding, not truncation, at 1e-6
    for dv in directions:
        fd = (8 * (grad_lagrangian(x + h * dv) - grad_lagrangian(x - h * dv))
              - (grad_lagrangian(x + 2 * h * dv) - grad_lagrangian(x - 2 * h * dv))) / (12 * h)
        an = H @ dv
        scale = np.maximum(1.0, np.abs(H) @ np.abs(dv))
        assert np.max(np.abs(fd - an) / scale) < 3e-8
    # the objective's and the rows' parts separately: sigma alone, then the multipliers alone
    H_f = _csc(nlp.hess_sparsity, nlp.hessian(x, sigma, np.zeros(nlp.m)))
    H_g = _csc(nlp.hess_sparsity, nlp.hessian(x, 0.0, lam))
    np.testing.assert_allclose(H_f + H_g, Hu, atol=1e-9 * max(1.0, np.abs(Hu).max()))
