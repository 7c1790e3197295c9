"""Lifted constraint blocks: per-node rows with compiled Jacobians, chained to the NLP variables.

A block is one SX Function ``F(u) -> r`` evaluated at K nodes whose inputs are affine in the
decision vector, ``u_k = M_k w + c_k``.  Its rows and their Jacobian are::

    g = vec(F(u_1), ..., F(u_K)),   dg/dw = blockdiag(dF/du(u_k)) M

(with a time scale the inputs are not affine and M is replaced by the sparse dU/dw).

``F`` and ``dF/du`` are generated as C and compiled once (:func:`latentoc.solver.compiled_functions`,
cached on disk), so a constraint Jacobian costs K compiled node Jacobians and one sparse
product instead of CasADi's directional derivatives through the whole graph (issue 6: 2.3 s
per Jacobian of the broad-jump NLP before, see :mod:`.transcription`).
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..solver import compiled_function_groups
from ..transcription import affine_map


@dataclass
class NodeRows:
    """A per-node row Function F(u) (SX, one vector input, one vector output) and its Jacobian."""

    rows: ca.Function
    jacobian: ca.Function

    @classmethod
    def from_expression(cls, name: str, u: ca.SX, r: ca.SX) -> "NodeRows":
        """Rows r(u) and (r, dr/du), with common subexpressions merged (about half the
        instructions of the contact node's Jacobian, and half the C to compile)."""
        r1 = ca.cse(r)
        r2, J = ca.cse([r, ca.jacobian(r, u)])
        return cls(ca.Function(name, [u], [r1], ["u"], ["r"]),
                   ca.Function(f"{name}_jac", [u], [r2, J], ["u"], ["r", "J"]))

    @property
    def n_in(self) -> int:
        return self.rows.nnz_in(0)

    @property
    def n_out(self) -> int:
        return self.rows.nnz_out(0)


def compile_node_rows(blocks: dict[str, NodeRows], jit: bool = True) -> dict[str, NodeRows]:
    """The blocks with their Functions compiled to C (one library per block, two compiled at a time)."""
    if not jit:
        return dict(blocks)
    # finite-difference derivatives only so that CasADi can build its Lagrangian-gradient
    # Function at set-up; Ipopt gets the compiled Jacobians (:func:`lifted_rows`)
    libs = compiled_function_groups([[b.rows, b.jacobian] for b in blocks.values()],
                                    external_options={"enable_fd": True})
    return {name: NodeRows(*fs) for name, fs in zip(blocks, libs)}


def lifted_rows(block: NodeRows, U: ca.MX, w: ca.MX, affine: bool = True) -> tuple[ca.MX, ca.MX]:
    """(g, dg/dw) of ``block`` at the K columns of U (n_in x K), node-major rows.

    ``affine``: U is affine in w (checked) and dU/dw = M is a constant matrix; otherwise
    (the time-scaled inputs of :mod:`.transcription`) dU/dw is CasADi's sparse Jacobian of U.
    """
    nu, K = U.shape
    if nu != block.n_in:
        raise ValueError(f"block {block.rows.name()} takes {block.n_in} inputs, U has {nu} rows")
    if affine:
        M, c = affine_map(U, w)
        Uw = ca.reshape(ca.mtimes(M, w) + c, nu, K)
    else:
        M, Uw = ca.jacobian(ca.vec(U), w), U
    g = ca.vec(block.rows.map(K)(Uw))
    J = block.jacobian.map(K)(Uw)[1]  # n_out x (nu K)
    D = ca.diagcat(*ca.horzsplit(J, nu)) if K > 1 else J
    return g, ca.mtimes(D, M)


def select_rows(g: ca.MX, jac: ca.MX, rows: np.ndarray) -> tuple[ca.MX, ca.MX]:
    """The rows ``rows`` of (g, jac)."""
    idx = [int(i) for i in rows]
    return g[idx], jac[idx, :]
