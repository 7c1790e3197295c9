"""Independent references for the GPDM learner's tests: the Hessian of Eq. 16 by central differences
of its exact gradient, and the Newton decrement 1/2 g^T |H|^-1 g it gives (the convergence test of
latentoc.gpdm.newton, recomputed without the learner's analytic Hessian)."""
from collections.abc import Callable

import numpy as np

from latentoc.gpdm.learning import learning_problem
from latentoc.runtime.threads import blas_threads
from latentoc.gpdm.objective import HYPER_NAMES, neg_log_posterior, pack


def central_hessian(grad: Callable[[np.ndarray], np.ndarray], z: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """(grad(z + h e_j) - grad(z - h e_j)) / 2h by columns, symmetrised (one BLAS thread, as learning)."""
    H = np.empty((z.size, z.size))
    with blas_threads(1):
        for j in range(z.size):
            e = np.zeros(z.size)
            e[j] = h
            H[:, j] = (grad(z + e) - grad(z - e)) / (2 * h)
    return 0.5 * (H + H.T)


def decrement(H: np.ndarray, g: np.ndarray, floor: float = 1e-8) -> float:
    """1/2 g^T |H|^-1 g, |eigenvalues| floored at ``floor`` times the largest (the latent rotations)."""
    lam, V = np.linalg.eigh(H)
    a = np.maximum(np.abs(lam), floor * np.abs(lam).max())
    return float(0.5 * np.sum((V.T @ g) ** 2 / a))


def model_objective(model):
    """(L, gradient over the learned variables, the function giving it, the learned variables) of a GPDM's
    learning problem at the model (W profiled, its settings' priors and fixed hyperparameters)."""
    p = learning_problem(model.Y - model.Y_mean, model.sequence_lengths, model.settings)
    v = pack(model.X, model.alpha, model.beta)
    free = np.ones(v.size, dtype=bool)
    for name in model.settings.fixed:
        free[v.size - 7 + HYPER_NAMES.index(name)] = False

    def grad(z: np.ndarray) -> np.ndarray:
        w = v.copy()
        w[free] = z
        return neg_log_posterior(w, p)[1][free]

    return float(neg_log_posterior(v, p, with_grad=False)), grad(v[free]), grad, v[free]


def aligned_difference(A: np.ndarray, B: np.ndarray) -> float:
    """max |A R - B| over orthogonal R (Procrustes): Eq. 16 is invariant under latent rotations."""
    U, _, Vt = np.linalg.svd(A.T @ B)
    return float(np.max(np.abs(A @ (U @ Vt) - B)))


def polish(grad: Callable[[np.ndarray], np.ndarray], z: np.ndarray, N: int, d: int, steps: int = 3) -> np.ndarray:
    """Newton steps with the central-difference Hessian, across the latent rotations (their tangents
    X Omega projected out): from near a minimum, the minimum to rounding."""
    z = z.copy()
    for _ in range(steps):
        g, H = grad(z), central_hessian(grad, z)
        X = z[:N * d].reshape(N, d)
        T = []
        for a in range(d):
            for b in range(a + 1, d):
                Om = np.zeros((d, d))
                Om[a, b], Om[b, a] = 1.0, -1.0
                t = np.zeros(z.size)
                t[:N * d] = (X @ Om).ravel()
                T.append(t)
        U, S, _ = np.linalg.svd(np.array(T).T, full_matrices=False)
        Q = U[:, S > 1e-9 * S.max()]
        P = np.eye(z.size) - Q @ Q.T
        z -= np.linalg.solve(P @ H @ P + np.abs(np.diag(H)).max() * (Q @ Q.T), P @ g)
    return z
