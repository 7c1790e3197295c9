"""Kernel functions of the GPDM (Kang & Park 2015, Sect. 3.1).

* :func:`rbf_kernel` -- the observation kernel of Eq. 11,
  ``k_Q(x, x') = beta1 exp(-beta2/2 |x - x'|^2) + delta/beta3``.
* :func:`rbf_linear_kernel` -- the dynamics kernel of Eq. 15,
  ``k_X(x, x') = alpha1 exp(-alpha2/2 |x - x'|^2) + alpha3 x^T x' + delta/alpha4``.

The Kronecker delta (noise) term is only added for the training kernel matrix
(``noise=True`` with ``X2`` omitted), i.e. it is read as "same training point",
not "equal coordinates".
"""

from __future__ import annotations

import numpy as np

__all__ = ["sq_dist", "rbf_kernel", "rbf_linear_kernel"]


def sq_dist(X1: np.ndarray, X2: np.ndarray | None = None) -> np.ndarray:
    """Matrix of squared Euclidean distances between the rows of X1 and X2."""
    X1 = np.atleast_2d(np.asarray(X1, dtype=float))
    if X2 is None:
        s = np.sum(X1 * X1, axis=1)
        r2 = s[:, None] + s[None, :] - 2.0 * (X1 @ X1.T)
        np.fill_diagonal(r2, 0.0)
    else:
        X2 = np.atleast_2d(np.asarray(X2, dtype=float))
        r2 = (np.sum(X1 * X1, axis=1)[:, None] + np.sum(X2 * X2, axis=1)[None, :]
              - 2.0 * (X1 @ X2.T))
    return np.maximum(r2, 0.0)


def rbf_kernel(X1: np.ndarray, X2: np.ndarray | None, beta: np.ndarray,
               noise: bool = False) -> np.ndarray:
    """RBF kernel of Eq. 11 with beta = (beta1, beta2, beta3).

    With ``X2 is None`` the kernel matrix of X1 with itself is returned, plus
    ``I/beta3`` if ``noise`` is true.
    """
    b1, b2, b3 = (float(v) for v in np.asarray(beta, dtype=float)[:3])
    K = b1 * np.exp(-0.5 * b2 * sq_dist(X1, X2))
    if noise:
        if X2 is not None:
            raise ValueError("noise term only defined for the training kernel matrix (X2=None)")
        K[np.diag_indices_from(K)] += 1.0 / b3
    return K


def rbf_linear_kernel(X1: np.ndarray, X2: np.ndarray | None, alpha: np.ndarray,
                      noise: bool = False) -> np.ndarray:
    """RBF + linear kernel of Eq. 15 with alpha = (alpha1, alpha2, alpha3, alpha4).

    With ``X2 is None`` the kernel matrix of X1 with itself is returned, plus
    ``I/alpha4`` if ``noise`` is true.
    """
    a1, a2, a3, a4 = (float(v) for v in np.asarray(alpha, dtype=float)[:4])
    X1 = np.atleast_2d(np.asarray(X1, dtype=float))
    X2v = X1 if X2 is None else np.atleast_2d(np.asarray(X2, dtype=float))
    K = a1 * np.exp(-0.5 * a2 * sq_dist(X1, X2)) + a3 * (X1 @ X2v.T)
    if noise:
        if X2 is not None:
            raise ValueError("noise term only defined for the training kernel matrix (X2=None)")
        K[np.diag_indices_from(K)] += 1.0 / a4
    return K
