"""Node inputs affine in the decision vector: s = S w + s0, built piece by piece.

Each node's local input vector is a stack of segments (a spline's value and derivatives at
the node's time, some decision variables, constants). :class:`NodeInputs` collects the
segments of K nodes and returns the sparse S ((K n_in) x n_w, node-major) and s0.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["NodeInputs"]


class NodeInputs:
    """Local inputs of K nodes, segment by segment (module doc)."""

    def __init__(self, K: int, n_w: int):
        self.K, self.n_w = int(K), int(n_w)
        self._parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []  # (node, j, col, val)
        self._const: list[np.ndarray] = []  # K x width
        self.n_in = 0

    def _add(self, node: np.ndarray, j: np.ndarray, col: np.ndarray, val: np.ndarray, const: np.ndarray) -> slice:
        width = const.shape[1]
        self._parts.append((node, j + self.n_in, col, val))
        self._const.append(const)
        seg = slice(self.n_in, self.n_in + width)
        self.n_in += width
        return seg

    def spline(self, bases: list[np.ndarray], index: np.ndarray, fixed: np.ndarray) -> slice:
        """Value and derivatives sum_r B[k, r] P[r, a] of a spline whose control points P (m x n)
        are decision variables where ``index`` (m x n) >= 0 (their positions in w) and
        ``fixed`` elsewhere; the segment is (B_0 P, B_1 P, ...) row by row: len(bases) n wide."""
        index = np.asarray(index, np.int64)
        fixed = np.where(index >= 0, 0.0, np.asarray(fixed, float))
        m, n = index.shape
        nodes, js, cols, vals, consts = [], [], [], [], []
        for r, B in enumerate(bases):
            B = np.asarray(B, float).reshape(self.K, m)
            kk, rr = np.nonzero(B)
            for a in range(n):
                free = index[rr, a] >= 0
                nodes.append(kk[free])
                js.append(np.full(free.sum(), r * n + a))
                cols.append(index[rr[free], a])
                vals.append(B[kk[free], rr[free]])
            consts.append(B @ fixed)
        return self._add(np.concatenate(nodes), np.concatenate(js), np.concatenate(cols), np.concatenate(vals),
                         np.hstack(consts))

    def variables(self, index: np.ndarray, const: np.ndarray | None = None) -> slice:
        """Decision variables w[index[k, j]] (index K x n, -1: none) plus ``const`` (K x n)."""
        index = np.asarray(index, np.int64).reshape(self.K, -1)
        kk, jj = np.nonzero(index >= 0)
        c = np.zeros(index.shape) if const is None else np.broadcast_to(np.asarray(const, float), index.shape)
        return self._add(kk, jj, index[kk, jj], np.ones(len(kk)), np.array(c))

    def constant(self, values: np.ndarray) -> slice:
        """Constant inputs (K x n)."""
        values = np.asarray(values, float).reshape(self.K, -1)
        empty = np.zeros(0, np.int64)
        return self._add(empty, empty, empty, np.zeros(0), values)

    def build(self) -> tuple[sp.csr_matrix, np.ndarray]:
        """(S, s0) with node k's inputs in rows k n_in ... (k + 1) n_in."""
        node = np.concatenate([p[0] for p in self._parts]) if self._parts else np.zeros(0, np.int64)
        j = np.concatenate([p[1] for p in self._parts]) if self._parts else np.zeros(0, np.int64)
        col = np.concatenate([p[2] for p in self._parts]) if self._parts else np.zeros(0, np.int64)
        val = np.concatenate([p[3] for p in self._parts]) if self._parts else np.zeros(0)
        S = sp.csr_matrix((val, (node * self.n_in + j, col)), shape=(self.K * self.n_in, self.n_w))
        s0 = np.hstack(self._const).ravel() if self._const else np.zeros(0)
        return S, s0
