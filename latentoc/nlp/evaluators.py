"""Local evaluators: the values, local Jacobians and local Hessians of one row family at K nodes.

A family's node k sees the decision vector only through its local inputs s_k (affine in w,
:mod:`.assemble`). An evaluator gives, for s (K x n_in) and multipliers l (K x n_out)::

    values(s)      -> F                          K x n_out
    jacobian(s)    -> (F, dF/ds)                 K x n_out x n_in
    hessian(s, l)  -> d2(l_k . F_k)/ds_k^2        K x n_in x n_in

:class:`BlockEvaluator` chains a compiled robot block (:mod:`.blocks`) through the GP layer
(:mod:`latentoc.latent.gp_layer`): J = J_block (its tangents), H = H_block + the GP layer's
curvature contracted with d(l . F)/d(y, yd, ydd). :class:`VarianceEvaluator` is the tube's
sigma^2 (Eq. 19, 29) from the GP layer alone.
"""
from __future__ import annotations

import numpy as np

from latentoc.latent.gp_layer import GPLayer, IdentityLayer, LatentMotion, Layer
from latentoc.nlp.blocks import RobotBlock, compile_blocks, stack_tangents

__all__ = ["BlockEvaluator", "MeanEvaluator", "VarianceEvaluator"]


def _dm(x) -> np.ndarray:
    return np.asarray(x, dtype=float) if not hasattr(x, "full") else x.full()


class BlockEvaluator:
    """A robot block fed by a GP layer; local inputs s = (x, xd, xdd, r) per node."""

    def __init__(self, block: RobotBlock, layer: Layer):
        if block.latent_dim != layer.latent_dim or block.output_dim != layer.output_dim:
            raise ValueError(f"block {block.name} takes d = {block.latent_dim}, D = {block.output_dim}; "
                             f"the layer has d = {layer.latent_dim}, D = {layer.output_dim}")
        if block.identity and not isinstance(layer, IdentityLayer):
            raise ValueError(f"block {block.name} takes its tangents as (I, 0, 0): it needs the identity layer")
        compile_blocks([block])
        self.block, self.layer = block, layer
        self.n_in, self.n_out = block.n_local, block.n_out
        self._last: tuple[np.ndarray, LatentMotion] | None = None

    def _motion(self, s: np.ndarray) -> LatentMotion:
        Z = s[:, :3 * self.layer.latent_dim]
        if self._last is None or self._last[0].shape != Z.shape or not np.array_equal(self._last[0], Z):
            self._last = (Z.copy(), self.layer.motion(Z))
        return self._last[1]

    # mapped blocks take and give their data column-major: a D x K input is the K x D array
    def _args(self, s: np.ndarray) -> list[np.ndarray]:
        m = self._motion(s)
        return [m.y, m.yd, m.ydd, s[:, 3 * self.layer.latent_dim:]]

    def _tangents(self, s: np.ndarray) -> list[np.ndarray]:
        m = self._motion(s)
        return [stack_tangents(G) for G in (m.G0, m.G1, m.G2)]

    def values(self, s: np.ndarray) -> np.ndarray:
        K = s.shape[0]
        return self.block.mapped("rows", K)(*self._args(s))[0].reshape(K, self.n_out)

    def jacobian(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        K = s.shape[0]
        F, J = self.block.mapped("jac", K)(*self._args(s), *self._tangents(s))
        return F.reshape(K, self.n_out), J.reshape(K, self.n_in, self.n_out).transpose(0, 2, 1)

    def hessian(self, s: np.ndarray, lam: np.ndarray) -> np.ndarray:
        K = s.shape[0]
        H, mu = self.block.mapped("hess", K)(*self._args(s), *self._tangents(s), np.asarray(lam, float))
        H = H.reshape(K, self.n_in, self.n_in)  # symmetric: its transpose is itself
        nz = 3 * self.layer.latent_dim
        H[:, :nz, :nz] += self.layer.curvature(s[:, :nz], mu.reshape(K, -1))
        return H


class MeanEvaluator:
    """The GP mean y = mu_Q(x) (Eq. 18) at K latent points, for rows on the pose alone (joint
    limits); local inputs s = x."""

    def __init__(self, layer: GPLayer):
        self.layer = layer
        self.n_in, self.n_out = layer.latent_dim, layer.output_dim

    def _Z(self, s: np.ndarray) -> np.ndarray:
        return np.hstack([s, np.zeros((s.shape[0], 2 * s.shape[1]))])

    def values(self, s: np.ndarray) -> np.ndarray:
        return self.layer.motion(self._Z(s)).y

    def jacobian(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m = self.layer.motion(self._Z(s))
        return m.y, m.G0

    def hessian(self, s: np.ndarray, lam: np.ndarray) -> np.ndarray:
        mu = np.hstack([np.asarray(lam, float), np.zeros((s.shape[0], 2 * self.n_out))])
        d = self.n_in
        return self.layer.curvature(self._Z(s), mu)[:, :d, :d]


class VarianceEvaluator:
    """sigma^2(x) (Eq. 19) at K latent points; local inputs s = x."""

    def __init__(self, layer: Layer):
        self.layer = layer
        self.n_in, self.n_out = layer.latent_dim, 1

    def values(self, s: np.ndarray) -> np.ndarray:
        return self.layer.variance(s)[0][:, None]

    def jacobian(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s2, g = self.layer.variance(s)
        return s2[:, None], g[:, None, :]

    def hessian(self, s: np.ndarray, lam: np.ndarray) -> np.ndarray:
        return self.layer.variance(s, np.asarray(lam, float)[:, 0])[2]
