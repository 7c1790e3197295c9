"""Helpers of the NLP derivative tests: a CasADi sparsity's values as a dense matrix, and
fourth-order central differences along a direction."""
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp


def dense(sparsity, values) -> np.ndarray:
    """The matrix of ``values`` laid out in CasADi's column-compressed ``sparsity``."""
    return sp.csc_matrix((values, np.array(sparsity.row()), np.array(sparsity.colind())),
                         shape=(sparsity.size1(), sparsity.size2())).toarray()


def central4(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, dv: np.ndarray, h: float = 1e-4) -> np.ndarray:
    """d fun(x + s dv)/ds at s = 0 by fourth-order central differences (rounding, not truncation,
    at h = 1e-4)."""
    return (8 * (fun(x + h * dv) - fun(x - h * dv)) - (fun(x + 2 * h * dv) - fun(x - 2 * h * dv))) / (12 * h)
