"""The GP layer: joint motion and tube along a latent path, with derivatives, in closed form.

At K latent points z_k = (x, xd, xdd) (Eq. 23-25) the GPDM mean gives the joint motion
(Eq. 18, 26-28)::

    y = y_mean + C^T k(x),   yd = C^T dk/dt,   ydd = C^T d2k/dt2

with the RBF kernel k_i(x) = b1 exp(-b2/2 |x - x_i|^2) of Eq. 11 and C = K_Y^-1 Yc W / W
(N x D). With e_i = x - x_i, s_i = e_i . xd and p_i = e_i . xdd the kernel's time
derivatives are::

    kd_i  = -b2 k_i s_i
    kdd_i = k_i h_i,   h_i = b2^2 s_i^2 - b2 |xd|^2 - b2 p_i

Every output and tangent is C^T applied to weights w_i or w_i e_i with w in (k, k s, k h),
plus outer products of these projections with xd and xdd::

    G0 = dy/dx   = -b2 C^T(k e)
    G1 = dyd/dx  =  b2^2 C^T(k s e) - b2 (C^T k) xd^T
    G2 = dydd/dx = -b2 C^T(k h e) + 2 b2^2 (C^T k s) xd^T - b2 (C^T k) xdd^T

so :meth:`GPLayer.motion` is one matrix product of a (3 K (1 + d)) x N array with C. The
contracted curvature (:meth:`GPLayer.curvature`) needs, per node, the sums sum_i w_i,
sum_i w_i e_i and sum_i w_i e_i e_i^T of three weights, one batched product of
(3 (1 + d)) x N and N x (1 + d) matrices per node. The tube's sigma^2 (Eq. 19) and its
derivatives (:meth:`GPLayer.variance`) go through the triangular factor L^-1 of K_Y^-1 =
L^-T L^-1, as :meth:`~latentoc.gpdm.GPDM.variance` does: sigma^2 = b1 + 1/b3 - |L^-1 k|^2 and
dk^T K_Y^-1 dk = |L^-1 dk|^2 lose far less to rounding than products with K_Y^-1 itself. The
kernel features at the last few inputs are kept, so the curvature at the motion's points and
the variance's curvature at its points do not compute them again.

The tangents have a fixed structure used by the robot blocks (:mod:`latentoc.nlp.blocks`):
with G0 = dy/dx, G1 = dyd/dx and G2 = dydd/dx,

    dyd/dxd = G0,   dydd/dxd = 2 G1,   dydd/dxdd = G0.
"""
from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.linalg.blas import dtrmm

from latentoc.gpdm import GPDM
from latentoc.runtime.threads import one_blas_thread

__all__ = ["GPLayer", "IdentityLayer", "Layer", "LatentMotion"]

_CACHE_ENTRIES = 6  # inputs whose kernel features are kept (a few node sets share a layer)


@dataclass
class LatentMotion:
    """Joint motion at K points and its tangents G0, G1, G2 (K x D x d each)."""

    y: np.ndarray  # K x D
    yd: np.ndarray
    ydd: np.ndarray
    G0: np.ndarray
    G1: np.ndarray
    G2: np.ndarray


def _points(A: np.ndarray, width: int, name: str, what: str) -> np.ndarray:
    A = np.asarray(A, dtype=float)
    if A.ndim != 2 or A.shape[1] != width:
        raise ValueError(f"{name}: {what} must be a K x {width} array, got shape {A.shape}")
    return np.ascontiguousarray(A)


def _split(Z: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    Z = _points(Z, 3 * d, "Z", "latent points (x, xd, xdd)")
    return Z, Z[:, :d], Z[:, d:2 * d], Z[:, 2 * d:]


def _multipliers(mu: np.ndarray, K: int, D: int) -> np.ndarray:
    mu = np.asarray(mu, dtype=float)
    if mu.shape not in ((K, 3 * D), (K * 3 * D,)):
        raise ValueError(f"mu: multipliers of (y, yd, ydd) must be a K x {3 * D} array with K = {K}, "
                         f"got shape {mu.shape}")
    return mu.reshape(K, 3 * D)


def _outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Outer products of the rows of a and b (K x n, K x m -> K x n x m)."""
    return a[:, :, None] * b[:, None, :]


def _outer_last(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Outer products with the nodes last (n x K, m x K -> n x m x K)."""
    return a[:, None, :] * b[None, :, :]


class Layer:
    """The map from the path to the joints a row family's evaluator sees: the joint motion with its
    tangents (:meth:`motion`), its curvature and, for a layer with a tube (Eq. 29), sigma^2."""

    latent_dim: int
    output_dim: int
    has_tube = False  # whether the path has a GPDM variance sigma^2 to hold in the tube

    @property
    def latent_coordinates(self) -> int:
        """The path's leading coordinates that are the latent (or joint) path itself: all of them,
        except a residual's (:class:`~latentoc.latent.ResidualLayer`)."""
        return self.latent_dim

    def motion(self, Z: np.ndarray) -> LatentMotion:
        raise NotImplementedError

    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def variance(self, X: np.ndarray, lam: np.ndarray | None = None):
        raise TypeError(f"{type(self).__name__} has no sigma^2: its path has no tube")


class GPLayer(Layer):
    """Closed-form GP mean motion, variance and their derivatives (module doc)."""

    has_tube = True

    def __init__(self, gpdm: GPDM):
        obs = gpdm._obs()
        self.Xt = np.asarray(gpdm.X, dtype=float)  # N x d training latent points
        self.b1, self.b2, b3 = (float(b) for b in gpdm.beta)
        self.s2_max = self.b1 + 1.0 / b3
        self.C = np.ascontiguousarray(obs["A"] / gpdm.W[None, :])  # N x D
        self.y_mean = np.asarray(gpdm.Y_mean, dtype=float)
        self.Linv = np.asarray(obs["Linv"], dtype=float)  # K_Y = (Linv^T Linv)^-1, lower triangular
        self.Kinv = self.Linv.T @ self.Linv
        self.latent_dim = self.Xt.shape[1]
        self.output_dim = self.C.shape[1]
        self._XtT = np.ascontiguousarray(self.Xt.T)  # d x N
        self._cache: OrderedDict[tuple, tuple] = OrderedDict()

    # ------------------------------------------------------------ features
    def _cached(self, tag: str, A: np.ndarray, make: Callable[[], tuple]) -> tuple:
        key = (tag, A.shape, A.tobytes())
        hit = self._cache.get(key)
        if hit is None:
            hit = self._cache[key] = make()
            if len(self._cache) > _CACHE_ENTRIES:
                self._cache.popitem(last=False)
        else:
            self._cache.move_to_end(key)
        return hit

    def _kernel(self, X: np.ndarray, F: np.ndarray) -> np.ndarray:
        """Write e_i = x - x_i into F[:, 1:] (K x d x N, F[:, 0] = 1) and return k (K x N)."""
        F[:, 0] = 1.0
        E = F[:, 1:]
        np.subtract(X[:, :, None], self._XtT[None, :, :], out=E)
        r2 = np.einsum("kan,kan->kn", E, E)
        return self.b1 * np.exp(-0.5 * self.b2 * r2)

    def _features(self, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """F = (1, e) (K x (1 + d) x N), k, s and h (K x N) at the rows of Z, cached."""
        def make():
            _, X, Xd, Xdd = _split(Z, self.latent_dim)
            F = np.empty((X.shape[0], self.latent_dim + 1, self.Xt.shape[0]))
            k = self._kernel(X, F)
            s = np.einsum("kan,ka->kn", F[:, 1:], Xd)
            p = np.einsum("kan,ka->kn", F[:, 1:], Xdd)
            v2 = np.sum(Xd * Xd, axis=1)[:, None]
            h = self.b2 ** 2 * s * s - self.b2 * v2 - self.b2 * p
            return F, k, s, h

        return self._cached("z", Z, make)

    # -------------------------------------------------------------- motion
    @one_blas_thread
    def motion(self, Z: np.ndarray) -> LatentMotion:
        """y, yd, ydd (Eq. 18, 26-28) and the tangents G0, G1, G2 at the rows of Z (K x 3d)."""
        Z, X, Xd, Xdd = _split(Z, self.latent_dim)
        K, d, N, D, b2 = X.shape[0], self.latent_dim, self.Xt.shape[0], self.output_dim, self.b2
        F, k, s, h = self._features(Z)
        W = np.stack([k, k * s, k * h], axis=1)  # K x 3 x N
        R = ((W[:, :, None, :] * F[:, None, :, :]).reshape(-1, N) @ self.C).reshape(K, 3, d + 1, D)
        kC, ksC, khC = R[:, 0, 0], R[:, 1, 0], R[:, 2, 0]  # C^T k, C^T (k s), C^T (k h)
        T = R[:, :, 1:]  # K x 3 x d x D: C^T (w e) for w = k, k s, k h
        # the tangents transposed (K x d x D), then viewed as K x D x d
        G0 = -b2 * T[:, 0]
        G1 = b2 * b2 * T[:, 1] - b2 * _outer(Xd, kC)
        G2 = -b2 * T[:, 2] + _outer(Xd, 2 * b2 * b2 * ksC) - b2 * _outer(Xdd, kC)
        G0, G1, G2 = (np.swapaxes(G, 1, 2) for G in (G0, G1, G2))
        return LatentMotion(self.y_mean + kC, -b2 * ksC, khC.copy(), G0, G1, G2)

    @one_blas_thread
    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        """sum_j mu_j d2u_j/dz2 (K x 3d x 3d) for u = (y, yd, ydd) and multipliers mu (K x 3D)."""
        Z, X, Xd, Xdd = _split(Z, self.latent_dim)
        K, d, D, N, b2 = X.shape[0], self.latent_dim, self.output_dim, self.Xt.shape[0], self.b2
        mu = _multipliers(mu, K, D)
        F, k, s, h = self._features(Z)
        ka = k[:, None, :] * (mu.reshape(K * 3, D) @ self.C.T).reshape(K, 3, N)  # k_i c_i . mu_(y, yd, ydd)
        ka0, ka1, ka2 = ka[:, 0], ka[:, 1], ka[:, 2]
        # weights (over b2^2) of e e^T in the (x, x), (x, xd) and (x, xdd) blocks
        W = np.stack([ka0 - b2 * ka1 * s + ka2 * h, ka1 - 2 * b2 * ka2 * s, ka2], axis=1)  # K x 3 x N
        A = (W[:, :, None, :] * F[:, None, :, :]).reshape(K, 3 * (d + 1), N)
        R = np.matmul(A, np.swapaxes(F, 1, 2)).reshape(K, 3, d + 1, d + 1)  # sum_i w_i (1, e_i) (1, e_i)^T
        # the blocks are assembled with the nodes last (long inner loops), then moved first
        R = np.ascontiguousarray(np.moveaxis(R, 0, -1))  # 3 x (d + 1) x (d + 1) x K
        tot, esum, ee = R[:, 0, 0], R[:, 0, 1:], R[:, 1:, 1:]
        xd, xdd = Xd.T, Xdd.T  # d x K
        base = b2 * b2 * ee  # b2^2 sum_i w_i e_i e_i^T - b2 sum_i w_i I, 3 x d x d x K
        for a in range(d):
            base[:, a, a] -= b2 * tot
        v_xd = b2 * b2 * esum[1] + b2 * b2 * tot[2] * xd  # the xd xd^T term split over both sides
        v_xdd = b2 * b2 * esum[2]
        H = np.zeros((3 * d, 3 * d, K))
        H[:d, :d] = base[0] + _outer_last(v_xd, xd) + _outer_last(xd, v_xd) + _outer_last(v_xdd, xdd) + _outer_last(xdd, v_xdd)
        H[:d, d:2 * d] = base[1] + 2 * (_outer_last(v_xdd, xd) + _outer_last(xd, v_xdd))  # rows x, columns xd
        H[d:2 * d, :d] = np.swapaxes(H[:d, d:2 * d], 0, 1)
        H[:d, 2 * d:] = base[2]
        H[2 * d:, :d] = np.swapaxes(base[2], 0, 1)
        H[d:2 * d, d:2 * d] = 2 * base[2]
        return np.ascontiguousarray(np.moveaxis(H, -1, 0))

    # ------------------------------------------------------------ variance
    def _tri(self, M: np.ndarray, transpose: bool = False) -> np.ndarray:
        """M L^T (or M L with ``transpose``) for M (n x N) and the lower-triangular L = Linv."""
        if M.size == 0:
            return M.copy()
        return dtrmm(1.0, self.Linv, M.T, lower=1, trans_a=int(transpose)).T

    def _variance_base(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """F = (1, e), k, alpha k (K x N), sigma^2 and its gradient at the rows of X, cached."""
        def make():
            F = np.empty((X.shape[0], self.latent_dim + 1, self.Xt.shape[0]))
            k = self._kernel(X, F)
            v = self._tri(k)  # Linv k: sigma^2 = s2_max - |v|^2, as in GPDM.variance
            ak = self._tri(v, transpose=True) * k  # (K_Y^-1 k)_i k_i
            s2 = self.s2_max - np.sum(v * v, axis=1)
            grad = 2.0 * self.b2 * np.einsum("kn,kan->ka", ak, F[:, 1:])
            return F, k, ak, s2, grad

        return self._cached("x", X, make)

    @one_blas_thread
    def variance(self, X: np.ndarray, lam: np.ndarray | None = None):
        """sigma^2 (Eq. 19) at the rows of X (K x d) and its gradient (K x d); with ``lam`` (K)
        also the curvature lam_k d2 sigma^2/dx2 (K x d x d)."""
        X = _points(X, self.latent_dim, "X", "latent points")
        K, d, N, b2 = X.shape[0], self.latent_dim, self.Xt.shape[0], self.b2
        F, k, ak, s2, grad = self._variance_base(X)
        if lam is None:
            return s2.copy(), grad.copy()
        lam = np.asarray(lam, dtype=float)
        if lam.size != K or lam.ndim > 2:
            raise ValueError(f"lam: one multiplier per point is needed (K = {K}), got shape {lam.shape}")
        E = F[:, 1:]
        V = self._tri((k[:, None, :] * E).reshape(K * d, N)).reshape(K, d, N)  # Linv dk / (-b2)
        quad = np.matmul(V, np.swapaxes(V, 1, 2))  # (dk^T K_Y^-1 dk) / b2^2
        eek = np.matmul(E * ak[:, None, :], np.swapaxes(E, 1, 2))  # sum_i alpha_i k_i e_i e_i^T
        H = -2.0 * b2 * b2 * (eek + quad) + (2.0 * b2 * np.sum(ak, axis=1))[:, None, None] * np.eye(d)
        return s2.copy(), grad.copy(), H * lam.reshape(-1, 1, 1)


class IdentityLayer(Layer):
    """The joint-space stand-in for :class:`GPLayer`: y = x (the spline is the joint path)."""

    def __init__(self, dim: int):
        self.latent_dim = self.output_dim = int(dim)

    def motion(self, Z: np.ndarray) -> LatentMotion:
        _, X, Xd, Xdd = _split(Z, self.latent_dim)
        K, n = X.shape
        eye = np.broadcast_to(np.eye(n), (K, n, n))
        zero = np.zeros((K, n, n))
        return LatentMotion(X, Xd, Xdd, eye, zero, zero)

    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        K = _split(Z, self.latent_dim)[0].shape[0]
        _multipliers(mu, K, self.output_dim)
        return np.zeros((K, 3 * self.latent_dim, 3 * self.latent_dim))
