"""The second-order condition at a solution of a small NLP (a spline's control points).

The Hessian of the Lagrangian is taken dense (n x n, n at most :data:`MAX_DENSE`) and projected on
the null space of the active rows' and bounds' gradients: its smallest eigenvalue is >= 0 at a
minimum and negative at a saddle, where Ipopt's first-order test also stops.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from latentoc.nlp.assemble import SparseNLP

__all__ = ["MAX_DENSE", "Curvature", "curvature"]

MAX_DENSE = 2000  # variables at most for the dense Hessian
ACTIVE_TOL = 1e-6  # a row within this of its bound, or with a multiplier above it, is active


@dataclass
class Curvature:
    """The smallest eigenvalue of the reduced Hessian, its direction (n, unit, its largest entry
    positive) and the number of active rows and bounds."""

    smallest: float
    direction: np.ndarray
    active: int


def _dense_hessian(nlp: SparseNLP, w: np.ndarray, sigma: float, lam: np.ndarray) -> np.ndarray:
    """The symmetric Hessian of sigma f + lam . g at w, dense (n x n)."""
    if nlp.n_w > MAX_DENSE:
        raise ValueError(f"a dense Hessian of {nlp.n_w} variables: more than {MAX_DENSE}")
    r, c = (np.asarray(a, np.int64) for a in nlp.hess_sparsity.get_triplet())
    H = np.zeros((nlp.n_w, nlp.n_w))
    v = nlp.hessian(w, sigma, lam)
    H[r, c] = v
    H[c, r] = v
    return H


def curvature(nlp: SparseNLP, w: np.ndarray, lam_g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray,
              lam_x: np.ndarray, lbx: np.ndarray, ubx: np.ndarray) -> Curvature:
    """The Lagrangian's Hessian at (w, lam_g) on the null space of the active rows and bounds (those
    at their bound or with a multiplier): Z^T H Z's smallest eigenvalue and its direction Z v."""
    n = nlp.n_w
    H = _dense_hessian(nlp, w, 1.0, lam_g)
    g = nlp.constraints(w)
    rows = (np.minimum(g - lbg, ubg - g) <= ACTIVE_TOL) | (np.abs(lam_g) > ACTIVE_TOL)
    bounds = (np.minimum(w - lbx, ubx - w) <= ACTIVE_TOL) | (np.abs(lam_x) > ACTIVE_TOL)
    A = np.vstack([np.asarray(ca.DM(nlp.jac_sparsity, nlp.jacobian(w)).full())[rows], np.eye(n)[bounds]])
    Z = np.eye(n)
    if len(A):
        _, s, vt = np.linalg.svd(A)
        Z = vt[int(np.sum(s > 1e-10 * max(s[0], 1.0))):].T
    if Z.shape[1] == 0:
        return Curvature(np.inf, np.zeros(n), len(A))
    e, V = np.linalg.eigh(Z.T @ H @ Z)
    d = Z @ V[:, 0]
    d = d if d[np.argmax(np.abs(d))] > 0 else -d  # a fixed sign
    return Curvature(float(e[0]), d, len(A))
