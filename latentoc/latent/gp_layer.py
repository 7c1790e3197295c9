"""The GP layer: joint motion and tube along a latent path, with derivatives, in closed form.

At K latent points z_k = (x, xd, xdd) (Eq. 23-25) the GPDM mean gives the joint motion
(Eq. 18, 26-28)::

    y = y_mean + C^T k(x),   yd = C^T dk/dt,   ydd = C^T d2k/dt2

with the RBF kernel k_i(x) = b1 exp(-b2/2 |x - x_i|^2) of Eq. 11 and C = K_Y^-1 Yc W / W
(N x D). With e_i = x - x_i, s_i = e_i . xd and p_i = e_i . xdd the kernel's time
derivatives are::

    kd_i  = -b2 k_i s_i
    kdd_i = k_i h_i,   h_i = b2^2 s_i^2 - b2 |xd|^2 - b2 p_i

Every output is C^T times one of three scalar features per training point, so the first
derivatives (:meth:`GPLayer.motion`) and the curvature contracted with multipliers
(:meth:`GPLayer.curvature`) are sums over the N training points of closed-form feature
derivatives: dense (K, N, d) arrays and a few matrix products, whatever K and N are.
The tube's sigma^2 (Eq. 19) and its derivatives are in :meth:`GPLayer.variance`.

The tangents have a fixed structure used by the robot blocks (:mod:`latentoc.nlp.blocks`):
with G0 = dy/dx, G1 = dyd/dx and G2 = dydd/dx,

    dyd/dxd = G0,   dydd/dxd = 2 G1,   dydd/dxdd = G0.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gpdm import GPDM

__all__ = ["GPLayer", "IdentityLayer", "LatentMotion"]


@dataclass
class LatentMotion:
    """Joint motion at K points and its tangents G0, G1, G2 (K x D x d each)."""

    y: np.ndarray  # K x D
    yd: np.ndarray
    ydd: np.ndarray
    G0: np.ndarray
    G1: np.ndarray
    G2: np.ndarray


def _split(Z: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    Z = np.asarray(Z, dtype=float)
    if Z.ndim != 2 or Z.shape[1] != 3 * d:
        raise ValueError(f"latent points must be K x {3 * d} (x, xd, xdd), got shape {Z.shape}")
    return Z[:, :d], Z[:, d:2 * d], Z[:, 2 * d:]


class GPLayer:
    """Closed-form GP mean motion, variance and their derivatives (module doc)."""

    def __init__(self, gpdm: GPDM):
        obs = gpdm._obs()
        self.Xt = np.asarray(gpdm.X, dtype=float)  # N x d training latent points
        self.b1, self.b2, b3 = (float(b) for b in gpdm.beta)
        self.s2_max = self.b1 + 1.0 / b3
        self.C = obs["A"] / gpdm.W[None, :]  # N x D
        self.y_mean = np.asarray(gpdm.Y_mean, dtype=float)
        self.Kinv = obs["Linv"].T @ obs["Linv"]
        self.latent_dim = self.Xt.shape[1]
        self.output_dim = self.C.shape[1]

    # ------------------------------------------------------------ features
    def _features(self, X, Xd, Xdd):
        E = X[:, None, :] - self.Xt[None, :, :]  # K x N x d
        k = self.b1 * np.exp(-0.5 * self.b2 * np.sum(E * E, axis=2))
        s = np.einsum("knd,kd->kn", E, Xd)
        p = np.einsum("knd,kd->kn", E, Xdd)
        v2 = np.sum(Xd * Xd, axis=1)[:, None]
        h = self.b2 ** 2 * s * s - self.b2 * v2 - self.b2 * p
        return E, k, s, h

    def _project(self, F: np.ndarray) -> np.ndarray:
        """C^T F for F (K x N x d): K x D x d."""
        return np.matmul(np.swapaxes(F, 1, 2), self.C).swapaxes(1, 2)

    # -------------------------------------------------------------- motion
    def motion(self, Z: np.ndarray) -> LatentMotion:
        """y, yd, ydd (Eq. 18, 26-28) and the tangents G0, G1, G2 at the rows of Z (K x 3d)."""
        X, Xd, Xdd = _split(Z, self.latent_dim)
        b2 = self.b2
        E, k, s, h = self._features(X, Xd, Xdd)
        kd, kdd = -b2 * k * s, k * h
        y = self.y_mean + k @ self.C
        dk = -b2 * k[:, :, None] * E  # d k_i / dx
        dkd = b2 * b2 * (k * s)[:, :, None] * E - b2 * k[:, :, None] * Xd[:, None, :]
        dh = 2 * b2 * b2 * s[:, :, None] * Xd[:, None, :] - b2 * Xdd[:, None, :]
        dkdd = h[:, :, None] * dk + k[:, :, None] * dh
        return LatentMotion(y, kd @ self.C, kdd @ self.C, self._project(dk), self._project(dkd), self._project(dkdd))

    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        """sum_j mu_j d2u_j/dz2 (K x 3d x 3d) for u = (y, yd, ydd) and multipliers mu (K x 3D)."""
        X, Xd, Xdd = _split(Z, self.latent_dim)
        K, d, D = X.shape[0], self.latent_dim, self.output_dim
        mu = np.asarray(mu, dtype=float).reshape(K, 3, D)
        a0, a1, a2 = np.moveaxis(mu @ self.C.T, 1, 0)  # K x N each: c_i . mu_y, c_i . mu_yd, c_i . mu_ydd
        b2 = self.b2
        E, k, s, h = self._features(X, Xd, Xdd)
        ka0, ka1, ka2 = k * a0, k * a1, k * a2
        eye = np.eye(d)

        def ee(w):  # sum_i w_i e_i e_i^T
            return np.einsum("kn,kna,knb->kab", w, E, E)

        def e_sum(w):  # sum_i w_i e_i
            return np.einsum("kn,kna->ka", w, E)

        def outer(a, b):
            return a[:, :, None] * b[:, None, :]

        H = np.zeros((K, 3 * d, 3 * d))
        # x, x
        c_ee = b2 * b2 * ka0 - b2 ** 3 * ka1 * s + b2 * b2 * ka2 * h
        c_eye = (-b2 * ka0 + b2 * b2 * ka1 * s - b2 * ka2 * h).sum(axis=1)
        v_xd = e_sum(b2 * b2 * ka1 - 2 * b2 ** 3 * ka2 * s)
        v_xdd = e_sum(b2 * b2 * ka2)
        xx = ee(c_ee) + c_eye[:, None, None] * eye + 2 * b2 * b2 * ka2.sum(axis=1)[:, None, None] * outer(Xd, Xd)
        xx += outer(v_xd, Xd) + outer(Xd, v_xd) + outer(v_xdd, Xdd) + outer(Xdd, v_xdd)
        H[:, :d, :d] = xx
        # x, xd (rows x, columns xd)
        v2 = e_sum(2 * b2 * b2 * ka2)
        xv = ee(b2 * b2 * ka1 - 2 * b2 ** 3 * ka2 * s) + (-b2 * ka1 + 2 * b2 * b2 * ka2 * s).sum(axis=1)[:, None, None] * eye
        xv += outer(v2, Xd) + outer(Xd, v2)
        H[:, :d, d:2 * d] = xv
        H[:, d:2 * d, :d] = np.swapaxes(xv, 1, 2)
        # x, xdd
        xa = ee(b2 * b2 * ka2) - b2 * ka2.sum(axis=1)[:, None, None] * eye
        H[:, :d, 2 * d:] = xa
        H[:, 2 * d:, :d] = np.swapaxes(xa, 1, 2)
        # xd, xd
        H[:, d:2 * d, d:2 * d] = ee(2 * b2 * b2 * ka2) - 2 * b2 * ka2.sum(axis=1)[:, None, None] * eye
        return H

    # ------------------------------------------------------------ variance
    def variance(self, X: np.ndarray, lam: np.ndarray | None = None):
        """sigma^2 (Eq. 19) at the rows of X (K x d) and its gradient (K x d); with ``lam`` (K)
        also the curvature lam_k d2 sigma^2/dx2 (K x d x d)."""
        X = np.asarray(X, dtype=float)
        E = X[:, None, :] - self.Xt[None, :, :]
        k = self.b1 * np.exp(-0.5 * self.b2 * np.sum(E * E, axis=2))
        alpha = k @ self.Kinv  # K_Y^-1 k (symmetric)
        s2 = self.s2_max - np.sum(alpha * k, axis=1)
        dk = -self.b2 * k[:, :, None] * E  # K x N x d
        grad = -2.0 * np.einsum("kn,knd->kd", alpha, dk)
        if lam is None:
            return s2, grad
        ak = alpha * k
        d2k = self.b2 * self.b2 * np.einsum("kn,kna,knb->kab", ak, E, E) - self.b2 * ak.sum(axis=1)[:, None, None] * np.eye(X.shape[1])
        quad = np.einsum("kna,knb->kab", dk, np.matmul(self.Kinv, dk))
        H = -2.0 * (d2k + quad) * np.asarray(lam, dtype=float).reshape(-1, 1, 1)
        return s2, grad, H


class IdentityLayer:
    """The joint-space stand-in for :class:`GPLayer`: y = x (the spline is the joint path)."""

    def __init__(self, dim: int):
        self.latent_dim = self.output_dim = int(dim)

    def motion(self, Z: np.ndarray) -> LatentMotion:
        X, Xd, Xdd = _split(Z, self.latent_dim)
        K, n = X.shape
        eye = np.broadcast_to(np.eye(n), (K, n, n))
        zero = np.zeros((K, n, n))
        return LatentMotion(X, Xd, Xdd, eye, zero, zero)

    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        K = np.asarray(Z).shape[0]
        return np.zeros((K, 3 * self.latent_dim, 3 * self.latent_dim))
