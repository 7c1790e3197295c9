"""The GP layer plus a joint-space residual on some joints (the jump's leg residual, :func:`latentoc.jump.schedule.path.leg_residual_path`).

The path is (x, r): x the latent spline (d), r a residual added to the joints ``joints`` (r of
them): y = GP mean(x) + E r, so dy/dr = E and the residual is linear (no curvature); the tube
(Eq. 29) is sigma^2 of x alone.
"""
from __future__ import annotations

import numpy as np

from latentoc.gpdm import GPDM
from latentoc.latent.gp_layer import GPLayer, Layer, LatentMotion, _split

__all__ = ["ResidualLayer"]


class ResidualLayer(Layer):
    """:class:`GPLayer` on the first d coordinates of the path, a residual on ``joints`` in the rest."""

    has_tube = True

    def __init__(self, gpdm: GPDM, joints: np.ndarray):
        self.gp = GPLayer(gpdm)
        self.joints = np.asarray(joints, int)
        self.d, self.r = self.gp.latent_dim, len(self.joints)
        self.latent_dim = self.d + self.r
        self.output_dim = self.gp.output_dim
        self.s2_max = self.gp.s2_max
        self.E = np.zeros((self.output_dim, self.r))
        self.E[self.joints, np.arange(self.r)] = 1.0

    @property
    def latent_coordinates(self) -> int:
        return self.d

    def _parts(self, Z: np.ndarray):
        Z, X, Xd, Xdd = _split(Z, self.latent_dim)
        d = self.d
        return np.hstack([X[:, :d], Xd[:, :d], Xdd[:, :d]]), X[:, d:], Xd[:, d:], Xdd[:, d:]

    def motion(self, Z: np.ndarray) -> LatentMotion:
        Zg, R, Rd, Rdd = self._parts(Z)
        m = self.gp.motion(Zg)
        K = Zg.shape[0]
        y, yd, ydd = m.y.copy(), m.yd.copy(), m.ydd.copy()
        y[:, self.joints] += R
        yd[:, self.joints] += Rd
        ydd[:, self.joints] += Rdd
        E = np.broadcast_to(self.E, (K, self.output_dim, self.r))
        zero = np.zeros((K, self.output_dim, self.r))
        return LatentMotion(y, yd, ydd, np.concatenate([m.G0, E], axis=2), np.concatenate([m.G1, zero], axis=2),
                            np.concatenate([m.G2, zero], axis=2))

    def _index(self) -> np.ndarray:
        n, d = self.latent_dim, self.d
        return np.concatenate([np.arange(d), n + np.arange(d), 2 * n + np.arange(d)])

    def curvature(self, Z: np.ndarray, mu: np.ndarray) -> np.ndarray:
        Zg = self._parts(Z)[0]
        Hg = self.gp.curvature(Zg, mu)
        n = self.latent_dim
        H = np.zeros((Zg.shape[0], 3 * n, 3 * n))
        i = self._index()
        H[:, i[:, None], i[None, :]] = Hg
        return H

    def variance(self, X: np.ndarray, lam: np.ndarray | None = None):
        X = np.asarray(X, float)
        out = self.gp.variance(X[:, :self.d], lam)
        K, n = X.shape[0], self.latent_dim
        grad = np.zeros((K, n))
        grad[:, :self.d] = out[1]
        if lam is None:
            return out[0], grad
        H = np.zeros((K, n, n))
        H[:, :self.d, :self.d] = out[2]
        return out[0], grad, H
