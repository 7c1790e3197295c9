"""The NLP assembled from row families: values, sparse Jacobian and exact Hessian by the chain rule.

A :class:`Family` is a local evaluator (:mod:`.evaluators`) at K nodes whose local inputs are
affine in the decision vector w::

    s_k = S_k w + s0_k        (S: (K n_in) x n_w, sparse and constant: spline bases, selections)

Its node outputs F (K n_out) enter the constraints and the objective linearly::

    g_f = C_g vec(F) + L w + c,     f += c_f . vec(F)

so that one family also expresses sums over nodes (an integral, the objective's quadrature).
The derivatives follow with no symbolic composition::

    dg_f/dw  = C_g blockdiag(dF_k/ds_k) S + L
    d2(l . g + sigma f)/dw2 = sum_k S_k^T d2(m_k . F_k)/ds_k^2 S_k,   m = C_g^T l + sigma c_f

assembled node by node in dense (n_out x n_c) and (n_c x n_c) blocks over the n_c variables
node k touches, and scattered into fixed compressed-column patterns. Small terms of w alone
(a distance, a regulariser) are an SX Function (``objective_terms``) differentiated by CasADi.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import casadi as ca
import numpy as np
import scipy.sparse as sp

__all__ = ["Family", "SparseNLP"]


class LocalEvaluator(Protocol):
    """What a family evaluates at its K nodes (:mod:`.evaluators`)."""

    n_in: int
    n_out: int

    def values(self, s: np.ndarray) -> np.ndarray: ...

    def jacobian(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def hessian(self, s: np.ndarray, lam: np.ndarray) -> np.ndarray: ...


@dataclass
class Family:
    """One row family: an evaluator at K nodes, its affine local inputs, and how its outputs
    enter the constraints (``Cg``, ``L``, ``c``) and the objective (``cf``)."""

    name: str
    evaluator: LocalEvaluator | None
    S: sp.spmatrix  # (K n_in) x n_w
    s0: np.ndarray  # K n_in
    Cg: sp.spmatrix | None = None  # m x (K n_out); None: no constraint rows
    L: sp.spmatrix | None = None  # m x n_w
    c: np.ndarray | None = None  # m
    cf: np.ndarray | None = None  # K n_out objective weights
    layout: dict[str, slice] = field(default_factory=dict)  # named row ranges of its constraint rows

    def __post_init__(self) -> None:
        counts = {k: m.shape[0] for k, m in (("Cg", self.Cg), ("L", self.L)) if m is not None}
        if self.c is not None:
            counts["c"] = np.size(self.c)
        if len(set(counts.values())) > 1:
            raise ValueError(f"family {self.name!r}: its row counts differ ({counts}); Cg, L and c must have "
                             f"the same number of rows")

    @property
    def n_rows(self) -> int:
        """Constraint rows: those of Cg, else of L, else of c."""
        for m in (self.Cg, self.L):
            if m is not None:
                return m.shape[0]
        return 0 if self.c is None else int(np.size(self.c))

    @property
    def K(self) -> int:
        return self.S.shape[0] // max(self.evaluator.n_in, 1) if self.evaluator is not None else 0

    def local_inputs(self, w: np.ndarray) -> np.ndarray:
        n_in = self.evaluator.n_in if self.evaluator is not None else 0
        return (self.S @ w + self.s0).reshape(self.K, n_in)


class _Plan:
    """Precomputed dense node blocks of S and the scatter positions of one family."""

    def __init__(self, fam: Family, n_w: int):
        if fam.evaluator is None:
            raise ValueError(f"family {fam.name!r} has no evaluator to plan")
        ev = self.ev = fam.evaluator
        self.fam = fam
        n_in, K = ev.n_in, fam.K
        # node k's rows of S, k * n_in ... (k + 1) * n_in - 1, on the columns they touch (ascending)
        S = sp.csr_matrix(fam.S).tocoo()
        node = S.row.astype(np.int64) // n_in
        keys = np.unique(node * S.shape[1] + S.col)  # (node, column) pairs, sorted
        key_node = keys // S.shape[1]
        counts = np.bincount(key_node, minlength=K)
        n_c = int(counts.max(initial=0))
        slot = np.arange(len(keys)) - np.concatenate([[0], np.cumsum(counts)[:-1]])[key_node]
        self.cols = np.full((K, n_c), -1, dtype=np.int64)
        self.cols[key_node, slot] = keys % S.shape[1]
        self.Sd = np.zeros((K, n_in, n_c))
        np.add.at(self.Sd, (node, S.row % n_in, slot[np.searchsorted(keys, node * S.shape[1] + S.col)]), S.data)
        self.n_c = n_c
        Cg = sp.coo_matrix(fam.Cg) if fam.Cg is not None else None
        self.C_rows = Cg.row if Cg is not None else np.zeros(0, np.int64)
        self.C_node = Cg.col // ev.n_out if Cg is not None else np.zeros(0, np.int64)
        self.C_out = Cg.col % ev.n_out if Cg is not None else np.zeros(0, np.int64)
        self.C_val = Cg.data if Cg is not None else np.zeros(0)
        self.CgT = sp.csr_matrix(fam.Cg.T) if fam.Cg is not None else None
        self.cf = None if fam.cf is None else np.asarray(fam.cf, float).reshape(K, ev.n_out)


def _pattern(rows: np.ndarray, cols: np.ndarray, n_rows: int, n_cols: int) -> tuple[ca.Sparsity, np.ndarray]:
    """Compressed-column sparsity of the (row, col) pairs and their sorted keys col * n_rows + row."""
    keys = np.unique(cols.astype(np.int64) * n_rows + rows.astype(np.int64))
    r, c = keys % n_rows, keys // n_rows
    colind = np.concatenate([[0], np.cumsum(np.bincount(c, minlength=n_cols))]).astype(np.int64)
    return ca.Sparsity(n_rows, n_cols, colind.tolist(), r.tolist()), keys


def _positions(keys: np.ndarray, rows: np.ndarray, cols: np.ndarray, n_rows: int, valid: np.ndarray) -> np.ndarray:
    """Index of each (row, col) in the pattern; len(keys) (a dropped slot) where not ``valid``."""
    pos = np.searchsorted(keys, cols.astype(np.int64) * n_rows + rows.astype(np.int64))
    return np.where(valid, pos, len(keys))


class SparseNLP:
    """Objective, constraints and their exact derivatives in fixed sparsity patterns.

    ``families`` are stacked in order into g (each its :attr:`Family.n_rows` rows), and all of
    them add their ``cf`` terms to the objective, as does ``objective_terms`` (SX Function w -> f).
    """

    def __init__(self, n_w: int, families: list[Family], objective_terms: ca.Function | None = None):
        self.n_w = int(n_w)
        self.families = [f for f in families if f.n_rows or f.cf is not None]
        self.row_offset: dict[str, int] = {}
        off = 0
        for f in self.families:
            if f.name in self.row_offset:
                raise ValueError(f"two row families are named {f.name!r}")
            self.row_offset[f.name] = off
            off += f.n_rows
        self.m = off
        self.plans = [_Plan(f, n_w) if f.evaluator is not None and f.K else None for f in self.families]
        self._objective_terms(objective_terms)
        self._jacobian_pattern()
        self._hessian_pattern()
        self._cache: dict[str, Any] = {}

    # ------------------------------------------------------------ patterns
    def _objective_terms(self, terms: ca.Function | None) -> None:
        w = ca.SX.sym("w", self.n_w)
        f = terms(w) if terms is not None else ca.SX(0)
        H = ca.triu(ca.hessian(f, w)[0])
        self._terms = ca.Function("objective_terms", [w], [f, ca.gradient(f, w)])
        self._terms_hess = ca.Function("objective_terms_hess", [w], [H])
        self._terms_hess_sp = H.sparsity()

    def _jacobian_pattern(self) -> None:
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        for f, plan in zip(self.families, self.plans):
            r0 = self.row_offset[f.name]
            if plan is not None and len(plan.C_rows):
                c = plan.cols[plan.C_node]  # nnzC x n_c
                rr = np.broadcast_to((r0 + plan.C_rows)[:, None], c.shape)
                rows.append(rr[c >= 0])
                cols.append(c[c >= 0])
            if f.L is not None:
                L = sp.coo_matrix(f.L)
                rows.append(r0 + L.row)
                cols.append(L.col)
        all_rows = np.concatenate(rows) if rows else np.zeros(0, np.int64)
        all_cols = np.concatenate(cols) if cols else np.zeros(0, np.int64)
        self.jac_sparsity, keys = _pattern(all_rows, all_cols, self.m, self.n_w)
        self._jac_nnz = len(keys)
        self._jac_dest: list[np.ndarray | None] = []
        self._lin_dest: list[tuple[np.ndarray, np.ndarray] | None] = []
        for f, plan in zip(self.families, self.plans):
            r0 = self.row_offset[f.name]
            dest = None
            if plan is not None and len(plan.C_rows):
                c = plan.cols[plan.C_node]
                rr = np.broadcast_to((r0 + plan.C_rows)[:, None], c.shape)
                dest = _positions(keys, rr, np.maximum(c, 0), self.m, c >= 0)
            self._jac_dest.append(dest)
            lin = None
            if f.L is not None:
                L = sp.coo_matrix(f.L)
                lin = (_positions(keys, r0 + L.row, L.col, self.m, np.ones(L.nnz, bool)), L.data)
            self._lin_dest.append(lin)

    def _hessian_pattern(self) -> None:
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        for plan in self.plans:
            if plan is None:
                continue
            a, b = plan.cols[:, :, None], plan.cols[:, None, :]
            ok = (a >= 0) & (b >= 0) & (a <= b)
            rows.append(np.broadcast_to(a, ok.shape)[ok])
            cols.append(np.broadcast_to(b, ok.shape)[ok])
        tsp = self._terms_hess_sp
        tr, tc = np.array(tsp.get_triplet()[0], np.int64), np.array(tsp.get_triplet()[1], np.int64)
        rows.append(tr)
        cols.append(tc)
        self.hess_sparsity, keys = _pattern(np.concatenate(rows), np.concatenate(cols), self.n_w, self.n_w)
        self._hess_nnz = len(keys)
        self._hess_dest: list[np.ndarray | None] = []
        for plan in self.plans:
            if plan is None:
                self._hess_dest.append(None)
                continue
            a = np.broadcast_to(plan.cols[:, :, None], (len(plan.cols), plan.n_c, plan.n_c))
            b = np.broadcast_to(plan.cols[:, None, :], a.shape)
            ok = (a >= 0) & (b >= 0) & (a <= b)
            self._hess_dest.append(_positions(keys, np.maximum(a, 0), np.maximum(b, 0), self.n_w, ok))
        self._terms_dest = _positions(keys, tr, tc, self.n_w, np.ones(len(tr), bool))  # triplets: nonzero order

    # ------------------------------------------------------------ evaluation
    def _inputs(self, w: np.ndarray) -> list[np.ndarray | None]:
        key = w.tobytes()
        if self._cache.get("w") != key:
            self._cache = {"w": key, "s": [None if p is None else p.fam.local_inputs(w) for p in self.plans]}
        return self._cache["s"]

    def _jacobians(self, w: np.ndarray):
        self._inputs(w)
        if "jac" not in self._cache:
            self._cache["jac"] = [None if p is None else p.ev.jacobian(s)
                                  for p, s in zip(self.plans, self._cache["s"])]
        return self._cache["jac"]

    def _values(self, w: np.ndarray):
        self._inputs(w)
        if "jac" in self._cache:
            return [None if j is None else j[0] for j in self._cache["jac"]]
        if "F" not in self._cache:
            self._cache["F"] = [None if p is None else p.ev.values(s)
                                for p, s in zip(self.plans, self._cache["s"])]
        return self._cache["F"]

    def objective(self, w: np.ndarray) -> float:
        w = np.asarray(w, float).ravel()
        f = float(self._terms(w)[0])
        for plan, F in zip(self.plans, self._values(w)):
            if plan is not None and plan.cf is not None:
                f += float(np.sum(plan.cf * F))
        return f

    def gradient(self, w: np.ndarray) -> np.ndarray:
        w = np.asarray(w, float).ravel()
        grad = np.asarray(self._terms(w)[1], float).ravel()
        for plan, jac in zip(self.plans, self._jacobians(w)):
            if plan is None or plan.cf is None:
                continue
            gs = np.einsum("ko,kos->ks", plan.cf, jac[1])  # K x n_in
            gc = np.einsum("ks,ksc->kc", gs, plan.Sd)
            ok = plan.cols >= 0
            grad += np.bincount(plan.cols[ok], gc[ok], minlength=self.n_w)
        return grad

    def constraints(self, w: np.ndarray) -> np.ndarray:
        w = np.asarray(w, float).ravel()
        out = []
        for f, plan, F in zip(self.families, self.plans, self._values(w)):
            if not f.n_rows:
                continue
            g = np.zeros(f.n_rows)
            if plan is not None and f.Cg is not None:
                g += f.Cg @ F.ravel()
            if f.L is not None:
                g += f.L @ w
            if f.c is not None:
                g += f.c
            out.append(g)
        return np.concatenate(out) if out else np.zeros(0)

    def jacobian(self, w: np.ndarray) -> np.ndarray:
        """Nonzeros of dg/dw in :attr:`jac_sparsity`'s compressed-column order."""
        w = np.asarray(w, float).ravel()
        vals = np.zeros(self._jac_nnz + 1)
        for plan, jac, dest, lin in zip(self.plans, self._jacobians(w), self._jac_dest, self._lin_dest):
            if dest is not None and plan is not None:
                Jw = np.matmul(jac[1], plan.Sd)  # K x n_out x n_c
                v = plan.C_val[:, None] * Jw[plan.C_node, plan.C_out, :]
                vals += np.bincount(dest.ravel(), v.ravel(), minlength=self._jac_nnz + 1)
            if lin is not None:
                vals += np.bincount(lin[0], lin[1], minlength=self._jac_nnz + 1)
        return vals[:-1]

    def hessian(self, w: np.ndarray, sigma: float, lam: np.ndarray) -> np.ndarray:
        """Nonzeros of the upper triangle of d2(sigma f + lam . g)/dw2 in :attr:`hess_sparsity`'s order."""
        w = np.asarray(w, float).ravel()
        lam = np.asarray(lam, float).ravel()
        s_all = self._inputs(w)
        vals = np.zeros(self._hess_nnz + 1)
        if sigma != 0.0:
            vals[self._terms_dest] += sigma * np.asarray(self._terms_hess(w).nonzeros())
        for f, plan, s, dest in zip(self.families, self.plans, s_all, self._hess_dest):
            if plan is None or s is None or dest is None:
                continue
            m = np.zeros(plan.Sd.shape[0] * plan.ev.n_out)
            if plan.CgT is not None:
                r0 = self.row_offset[f.name]
                m += plan.CgT @ lam[r0:r0 + f.n_rows]
            if plan.cf is not None:
                m += sigma * plan.cf.ravel()
            if not np.any(m):
                continue
            Hs = plan.ev.hessian(s, m.reshape(-1, plan.ev.n_out))
            Hw = np.matmul(np.swapaxes(plan.Sd, 1, 2), np.matmul(Hs, plan.Sd))
            vals += np.bincount(dest.ravel(), Hw.ravel(), minlength=self._hess_nnz + 1)
        return vals[:-1]
