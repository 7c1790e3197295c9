"""Lifted constraint blocks: per-node rows with compiled Jacobians, chained to the NLP variables.

A block is one SX Function ``F(u) -> r`` evaluated at K nodes whose inputs are affine in the
decision vector, ``u_k = M_k w + c_k``.  Its rows and their Jacobian are::

    g = vec(F(u_1), ..., F(u_K)),   dg/dw = blockdiag(dF/du(u_k)) M

(with a time scale the inputs are not affine and M is replaced by the sparse dU/dw).
The exact Hessian of ``l . g`` (:func:`lifted_hessian`) is, with l_k the multipliers of node k::

    sum_k M_k^T H_k M_k + sum_i v_i d2U_i/dw2,   H_k = d2(l_k . F)/du2 (u_k),  v = blockdiag(dF/du)^T l

(the second term only for non-affine inputs).

``F`` and ``dF/du`` are generated as C and compiled once (:func:`latentoc.solver.compiled_libraries`,
cached on disk, and found again from the rows alone, :func:`compile_node_rows`), so a constraint Jacobian costs K compiled node Jacobians and one sparse
product instead of CasADi's directional derivatives through the whole graph (issue 6: 2.3 s
per Jacobian of the broad-jump NLP before, see :mod:`.transcription`).
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from ..solver import JIT_FLAGS, compiled_libraries, jit_cache_dir, jit_compiler, jit_enabled
from ..transcription import affine_map


@dataclass
class NodeRows:
    """A per-node row Function F(u) (SX, one vector input, one vector output) and its Jacobian
    (and Hessian); ``jacobian`` is None until :meth:`with_jacobian` (a block built with
    ``lazy=True``, so that a compiled block found on disk needs no symbolic derivatives)."""

    rows: ca.Function
    jacobian: ca.Function | None = None
    hessian: ca.Function | None = None  # (u, l) -> (triu(d2(l . r)/du2), d(l . r)/du), or None
    expression: tuple[ca.SX, ca.SX] | None = field(default=None, repr=False)  # (u, r) the rows came from

    @classmethod
    def from_expression(cls, name: str, u: ca.SX, r: ca.SX, hessian: bool = False, lazy: bool = False) -> "NodeRows":
        """Rows r(u) and (r, dr/du), with common subexpressions merged (about half the
        instructions of the contact node's Jacobian, and half the C to compile); with
        ``hessian`` also the upper triangle of the Hessian of l . r(u) for multipliers l;
        ``lazy``: the rows only, derivatives on demand."""
        block = cls(ca.Function(name, [u], [ca.cse(r)], ["u"], ["r"]), expression=(u, r))
        if lazy:
            return block
        block = block.with_jacobian()
        return block.with_hessian() if hessian else block

    def with_jacobian(self) -> "NodeRows":
        """The block with its Jacobian Function (r, dr/du)."""
        if self.jacobian is not None:
            return self
        u, r = self.expression
        r2, J = ca.cse([r, ca.jacobian(r, u)])
        jac = ca.Function(f"{self.rows.name()}_jac", [u], [r2, J], ["u"], ["r", "J"])
        return NodeRows(self.rows, jac, self.hessian, self.expression)

    def with_hessian(self) -> "NodeRows":
        """The block with its Hessian Function (self.rows must be an SX Function, not compiled)."""
        if self.hessian is not None:
            return self
        u = ca.SX.sym("u", self.n_in)
        lam = ca.SX.sym("l", self.n_out)
        H, grad = ca.hessian(ca.dot(lam, self.rows(u)), u)
        H, grad = ca.cse([ca.triu(H), grad])
        hess = ca.Function(f"{self.rows.name()}_hess", [u, lam], [H, grad], ["u", "l"], ["H", "grad"])
        return NodeRows(self.rows, self.jacobian, hess, self.expression)

    @property
    def n_in(self) -> int:
        return self.rows.nnz_in(0)

    @property
    def n_out(self) -> int:
        return self.rows.nnz_out(0)


# bump when the derivative Functions made from the same rows change (:meth:`NodeRows.with_jacobian`,
# :meth:`NodeRows.with_hessian`): the on-disk index of compiled blocks is keyed by it
DERIVATIVES_VERSION = "1"


def compile_node_rows(blocks: dict[str, NodeRows], jit: bool = True, hessian: bool = False) -> dict[str, NodeRows]:
    """The blocks with their Jacobians (and with ``hessian``, or where a block has one, their
    Hessians) compiled to C: rows and Jacobian in one library, the Hessian in another (so the
    first stays the same, and cached, whether a block has its Hessian or not), two compiled at
    a time.

    Compiled blocks are also indexed on disk by a hash of their rows' serialized SX (with the
    compiler flags, CasADi's version and :data:`DERIVATIVES_VERSION`): a later process finds
    the libraries from the rows alone, without building the derivatives' SX or their C
    (issue 6: 90 s of the broad jump's build).  Without JIT the derivatives are built as SX."""
    want = {name: hessian or b.hessian is not None for name, b in blocks.items()}
    if not (jit and jit_enabled()):
        return {name: _with_derivatives(b, want[name]) for name, b in blocks.items()}
    index = {name: _index_file(b, want[name]) for name, b in blocks.items()}
    out, missing = {}, {}
    for name, b in blocks.items():
        found = _indexed(index[name], b.rows.name(), want[name])
        if found is None:
            missing[name] = b
        else:
            out[name] = found
    if missing:
        built = {name: _with_derivatives(b, want[name]) for name, b in missing.items()}
        groups = [[b.rows, b.jacobian] for b in built.values()]
        hess = [name for name, b in built.items() if b.hessian is not None]
        libs = compiled_libraries(groups + [[built[n].hessian] for n in hess])
        libs_of = {name: [lib] for name, lib in zip(built, libs)}
        for name, lib in zip(hess, libs[len(groups):]):
            libs_of[name].append(lib)
        for name, b in built.items():
            if any(lib is None for lib in libs_of[name]):  # no compiler, or it failed (warned): SX
                out[name] = b
                continue
            _write_index(index[name], b.rows.name(), libs_of[name])
            out[name] = _loaded(libs_of[name], b.rows.name())
    return {name: out[name] for name in blocks}


def _with_derivatives(block: NodeRows, hessian: bool) -> NodeRows:
    block = block.with_jacobian()
    return block.with_hessian() if hessian else block


# finite-difference derivatives only so that CasADi can build its Lagrangian-gradient Function at
# set-up; Ipopt gets the compiled Jacobians (:func:`lifted_rows`)
_EXTERNAL_OPTIONS = {"enable_fd": True}


def _index_file(block: NodeRows, hessian: bool) -> Path:
    key = "\0".join([block.rows.serialize(), str(hessian), DERIVATIVES_VERSION, ca.__version__, str(jit_compiler()),
                      *JIT_FLAGS])
    return jit_cache_dir() / f"nr_{hashlib.sha256(key.encode()).hexdigest()[:24]}.json"


def _indexed(path: Path, name: str, hessian: bool) -> NodeRows | None:
    """The compiled block ``name`` from its index entry ``path``, or None (no entry, or a
    library of it is gone)."""
    try:
        entry = json.loads(path.read_text())
        libs = [Path(p) for p in entry["libraries"]]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if len(libs) != 1 + hessian or not all(lib.exists() for lib in libs):
        return None
    return _loaded(libs, name)


def _loaded(libs: list[Path], name: str) -> NodeRows:
    """Block ``name`` from its libraries: rows and Jacobian, and the Hessian if there is a second."""
    rows, jac = (ca.external(n, str(libs[0]), _EXTERNAL_OPTIONS) for n in (name, f"{name}_jac"))
    hess = ca.external(f"{name}_hess", str(libs[1]), _EXTERNAL_OPTIONS) if len(libs) > 1 else None
    return NodeRows(rows, jac, hess)


def _write_index(path: Path, block: str, libs: list[Path]) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    tmp.write_text(json.dumps({"block": block, "libraries": [str(p) for p in libs]}))
    os.replace(tmp, path)  # atomic: readers see no entry or a complete one


def threads() -> int:
    """Threads for the per-node evaluations of compiled blocks: ``$LATENTOC_THREADS``, else the
    number of CPUs.  (2 threads on 2 cores: 1.9x on a compiled test function; in CasADi's
    virtual machine threads were slower, so uncompiled blocks run serially.)"""
    n = os.environ.get("LATENTOC_THREADS")
    if not n:
        return max(1, os.cpu_count() or 1)
    if not n.strip().isdigit() or int(n) < 1:
        raise ValueError(f"LATENTOC_THREADS must be a positive integer, got {n!r}")
    return int(n)


def node_map(f: ca.Function, K: int) -> ca.Function:
    """``f`` mapped over K nodes, on :func:`threads` threads when f is compiled."""
    n = threads()
    if K > 1 and n > 1 and f.class_name() == "External":
        return f.map(K, "thread", min(n, K))
    return f.map(K)


def lifted_rows(block: NodeRows, U: ca.MX, w: ca.MX, affine: bool = True) -> tuple[ca.MX, ca.MX]:
    """(g, dg/dw) of ``block`` at the K columns of U (n_in x K), node-major rows.

    ``affine``: U is affine in w (checked) and dU/dw = M is a constant matrix; otherwise
    (the time-scaled inputs of :mod:`.transcription`) dU/dw is CasADi's sparse Jacobian of U.
    """
    nu, K = U.shape
    if nu != block.n_in:
        raise ValueError(f"block {block.rows.name()} takes {block.n_in} inputs, U has {nu} rows")
    Uw, M = _inputs(U, w, affine)
    g = ca.vec(node_map(block.rows, K)(Uw))
    J = node_map(block.jacobian, K)(Uw)[1]  # n_out x (nu K)
    D = ca.diagcat(*ca.horzsplit(J, nu)) if K > 1 else J
    return g, ca.mtimes(D, M)


def _inputs(U: ca.MX, w: ca.MX, affine: bool) -> tuple[ca.MX, ca.MX]:
    """(U as M w + c, M) for affine inputs, else (U, dU/dw)."""
    if affine:
        M, c = affine_map(U, w)
        return ca.reshape(ca.mtimes(M, w) + c, *U.shape), M
    return U, ca.jacobian(ca.vec(U), w)


def lifted_hessian(block: NodeRows, U: ca.MX, w: ca.MX, lam: ca.MX, affine: bool = True) -> tuple[ca.MX, ca.MX]:
    """The (symmetric, full) Hessian over w of ``lam . g`` for g = :func:`lifted_rows`'s rows
    (``lam``: n_out K multipliers, node-major; module doc), and its gradient over w,
    (dU/dw)^T v, from the same node evaluations."""
    if block.hessian is None:
        raise ValueError(f"block {block.rows.name()} was built without its Hessian")
    nu, K = U.shape
    Uw, M = _inputs(U, w, affine)
    L = ca.reshape(lam, block.n_out, K)
    Hn, V = node_map(block.hessian, K)(Uw, L)  # n_in x (n_in K) upper triangles; n_in x K gradients
    D = ca.diagcat(*ca.horzsplit(Hn, nu)) if K > 1 else Hn
    D = D + D.T - ca.diag(ca.diag(D))
    H = ca.mtimes(M.T, ca.mtimes(D, M))
    if not affine:  # curvature of the inputs: sum_i v_i d2U_i/dw2, v = d(l . F)/du per node
        vs = ca.MX.sym("v", nu * K)
        curv = ca.Function("input_curvature", [w, vs], [ca.hessian(ca.dot(vs, ca.vec(U)), w)[0]])
        H = H + curv(w, ca.vec(V))
    return H, ca.mtimes(M.T, ca.vec(V))


def select_rows(g: ca.MX, jac: ca.MX, rows: np.ndarray) -> tuple[ca.MX, ca.MX]:
    """The rows ``rows`` of (g, jac)."""
    idx = [int(i) for i in rows]
    return g[idx], jac[idx, :]
