"""Robot blocks: the rows of one row family at one node, a Function of robot quantities only.

A block's rows are an SX Function ``F(y, yd, ydd, r)`` of the joint motion (y, yd, ydd: D
each, the GP layer's outputs) and the node's other inputs r (base state, contact forces,
phase data, ...). The NLP sees a node through its local inputs s = (dx, dxd, dxdd, dr): the
latent point's tangents (3d) and r. With the GP layer's tangents G0, G1, G2
(:mod:`latentoc.latent.gp_layer`) the joint motion moves as

    dy = G0 dx,   dyd = G1 dx + G0 dxd,   dydd = G2 dx + 2 G1 dxd + G0 dxdd,

so each block is compiled as three small Functions, mapped over its nodes:

* ``rows``: (y, yd, ydd, r) -> F
* ``jac``: (y, yd, ydd, r, G0, G1, G2) -> (F, dF/ds)
* ``hess``: (y, yd, ydd, r, G0, G1, G2, l) -> (d2(l . F)/ds2 with the GP curvature left out,
  d(l . F)/d(y, yd, ydd)), the second output for the GP layer's curvature term.

Fed by the identity layer (the joint path itself, y = x: G0 = I, G1 = G2 = 0), a block marked
``identity`` takes its derivatives in (y, yd, ydd, r) directly: the tangents are constants of
its derivatives, not symbols to multiply by (with d = D = 37 the products with symbolic 37 x 37
tangents would dominate them); it takes the same inputs.

Their size depends on the robot and the row definition, not on the GPDM: they are cached on
disk keyed by the serialized rows and d, so a new GPDM, tube, motion or node count reuses them.
Common subexpressions are eliminated (``ca.cse``) only before C is generated, where gcc's time and
the hot code shrink with them; in the virtual machine (no JIT) it would cost 3-4x the build for
~30 % quicker evaluations (docs/derivatives.md).
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from latentoc.runtime.progress import bar
from latentoc.nlp import jit, split, upgrade

__all__ = ["RobotBlock", "MappedCall", "block_inputs", "compile_blocks", "compile_seconds"]

_COMPILE_SECONDS = [0.0]  # this process's time in compile_blocks building and compiling derivatives


def compile_seconds() -> float:
    """Seconds this process has spent building and compiling blocks' derivatives (a solve reports
    the difference over its build and its rounds as its compile time)."""
    return _COMPILE_SECONDS[0]

# bump when the derivative Functions made from the same rows change: the cache index keys on it
BLOCK_VERSION = "3"
PIECES = ("rows", "jac", "hess")
UPGRADE_POLL_S = 2.0  # s between looks at a block's cache index while its optimised libraries are built


def block_inputs(D: int, n_extra: int) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """SX symbols (y, yd, ydd, r) for a block's rows."""
    return ca.SX.sym("y", D), ca.SX.sym("yd", D), ca.SX.sym("ydd", D), ca.SX.sym("r", n_extra)


@dataclass
class RobotBlock:
    """One row family's node Function and its compiled derivative pieces (module doc)."""

    name: str
    rows_sx: ca.Function  # (y, yd, ydd, r) -> F, SX
    latent_dim: int
    layout: dict[str, slice] = field(default_factory=dict)  # named row ranges of F
    hot: bool = True  # evaluated at many nodes every iteration: compiled for speed (:func:`jit.flags_for`)
    identity: bool = False  # fed by the identity layer: tangents (I, 0, 0) as constants (module doc)
    functions: dict[str, ca.Function] = field(default_factory=dict, repr=False)
    instructions: dict[str, int] = field(default_factory=dict, repr=False)  # of the compiled pieces
    _maps: dict = field(default_factory=dict, repr=False)
    libraries: list[list[str]] = field(default_factory=list, repr=False)  # the loaded pieces' library names
    upgrading: Path | None = field(default=None, repr=False)  # the index a background build will rewrite
    _polled: float = field(default=0.0, repr=False)

    @classmethod
    def from_parts(cls, name: str, inputs: tuple[ca.SX, ca.SX, ca.SX, ca.SX], parts: dict[str, ca.SX],
                   latent_dim: int, hot: bool = True) -> "RobotBlock":
        """A block whose rows are the named ``parts`` stacked in order; ``hot``: evaluated at many
        nodes every iteration (else at one, e.g. a phase transition)."""
        layout, off = {}, 0
        for key, e in parts.items():
            layout[key] = slice(off, off + e.numel())
            off += e.numel()
        F = ca.vertcat(*[ca.vec(e) for e in parts.values()])
        fn = ca.Function(name, list(inputs), [F], ["y", "yd", "ydd", "r"], ["F"])
        return cls(name, fn, int(latent_dim), layout, hot)

    @property
    def output_dim(self) -> int:
        return self.rows_sx.nnz_in(0)

    @property
    def n_extra(self) -> int:
        return self.rows_sx.nnz_in(3)

    @property
    def n_out(self) -> int:
        return self.rows_sx.nnz_out(0)

    @property
    def n_local(self) -> int:
        return 3 * self.latent_dim + self.n_extra

    def derivative_functions(self, pieces: tuple[str, ...] = PIECES, cse: bool = True) -> dict[str, ca.Function]:
        """The SX Functions ``rows``, ``jac`` and ``hess`` (module doc), or those of ``pieces``;
        ``cse``: with common subexpressions eliminated."""
        D, d, nr, name = self.output_dim, self.latent_dim, self.n_extra, self.name
        if self.identity and D != d:
            raise ValueError(f"block {name}: an identity block needs d = D, got d = {d}, D = {D}")
        y, yd, ydd, r = block_inputs(D, nr)
        G = [ca.SX.sym(f"G{i}", D, d) for i in range(3)]
        T = [ca.DM.eye(D), ca.DM(D, d), ca.DM(D, d)] if self.identity else G  # the tangents in the rows
        s = ca.SX.sym("s", self.n_local)
        sx, sv, sa, sr = s[:d], s[d:2 * d], s[2 * d:3 * d], s[3 * d:]
        lin = (y + T[0] @ sx, yd + T[1] @ sx + T[0] @ sv, ydd + T[2] @ sx + 2 * T[1] @ sv + T[0] @ sa, r + sr)
        zero = ca.DM.zeros(s.shape)
        shared = ca.cse if cse else (lambda e: e)
        F = self.rows_sx(y, yd, ydd, r)
        ins, names = [y, yd, ydd, r], ["y", "yd", "ydd", "r"]
        out = {}
        if "rows" in pieces:
            out["rows"] = ca.Function(name, ins, [shared(F)], names, ["F"])
        if "jac" in pieces:
            J = ca.substitute(ca.jacobian(self.rows_sx(*lin), s), s, zero)
            out["jac"] = ca.Function(f"{name}_jac", ins + G, shared([F, J]), names + ["G0", "G1", "G2"], ["F", "J"])
        if "hess" in pieces:
            lam = ca.SX.sym("l", self.n_out)
            H = ca.substitute(ca.hessian(ca.dot(lam, self.rows_sx(*lin)), s)[0], s, zero)
            mu = ca.gradient(ca.dot(lam, F), ca.vertcat(y, yd, ydd))
            out["hess"] = ca.Function(f"{name}_hess", ins + G + [lam], shared([H, mu]),
                                      names + ["G0", "G1", "G2", "l"], ["H", "mu"])
        return out

    def function(self, which: str) -> ca.Function:
        """Piece ``which``: compiled, or (without JIT) its SX Function, built when first asked for."""
        if which not in self.functions:
            self.functions.update(self.derivative_functions((which,), cse=False))
        return self.functions[which]

    def compiled_parts(self, f: ca.Function) -> list[ca.Function]:
        """The Functions derivative Function ``f`` is compiled as: pieces (:mod:`.split`) when the
        block is hot, else ``f`` whole."""
        return split.split_function(f, jit.PIECE_INSTRUCTIONS) if self.hot else [f]

    def mapped(self, which: str, K: int) -> "MappedCall":
        """Piece ``which`` mapped over K nodes, called on numpy arrays (:class:`MappedCall`)."""
        if self.upgrading is not None:
            self._load_upgrade()
        key = (which, K)
        if key not in self._maps:
            f = self.function(which)
            self._maps[key] = MappedCall(jit.node_map(f, K, self.instructions.get(which, 0), not f.is_a("SXFunction")))
        return self._maps[key]

    def _load_upgrade(self) -> None:
        """Once the background build (:mod:`.upgrade`) has rewritten the cache index, load the
        optimised libraries it names (the same values bit for bit); the index is read at most every
        :data:`UPGRADE_POLL_S` s."""
        now = time.monotonic()
        if self.upgrading is None or now - self._polled < UPGRADE_POLL_S:
            return
        self._polled = now
        try:
            entry = json.loads(self.upgrading.read_text())
            if entry["libraries"] == self.libraries:
                return
            libs = _cached_libraries(entry)
        except (OSError, ValueError, KeyError, TypeError):
            return
        if libs is not None:
            self.functions, self.libraries, self.upgrading = _load(self, libs), entry["libraries"], None
            self._maps.clear()


class MappedCall:
    """A Function evaluated in place on numpy arrays through CasADi's buffers: no DM is made.

    Arguments are the inputs' dense data in CasADi's column-major order (for a mapped block's
    D x K input: the K x D array, node by node); results are the outputs' dense data in the same
    order, each a new array."""

    def __init__(self, f: ca.Function):
        self.f = f
        self._buf, self._eval = f.buffer()
        self._args = [np.zeros(f.nnz_in(i)) for i in range(f.n_in())]
        for i, a in enumerate(self._args):
            if f.sparsity_in(i).nnz() != f.numel_in(i):
                raise ValueError(f"{f.name()}: input {i} is not dense")
            self._buf.set_arg(i, memoryview(a))  # type: ignore[call-arg, arg-type]  # CasADi's stub: (i, ptr, size)
        self._res, self._scatter = [], []
        for i in range(f.n_out()):
            sp = f.sparsity_out(i)
            nz = np.zeros(sp.nnz())
            self._buf.set_res(i, memoryview(nz))  # type: ignore[call-arg, arg-type]
            rows, cols = np.array(sp.get_triplet()[0], np.int64), np.array(sp.get_triplet()[1], np.int64)
            dense = sp.nnz() == sp.numel()
            self._res.append(nz)
            self._scatter.append(None if dense else (cols * sp.size1() + rows, sp.numel()))

    def __call__(self, *args: np.ndarray) -> list[np.ndarray]:
        for a, v in zip(self._args, args):
            a[:] = np.ravel(v)
        self._eval()
        out = []
        for nz, sc in zip(self._res, self._scatter):
            if sc is None:
                out.append(nz.copy())
            else:
                full = np.zeros(sc[1])
                full[sc[0]] = nz
                out.append(full)
        return out


def _index_file(block: RobotBlock) -> Path:
    key = "\0".join([block.rows_sx.serialize(), str(block.latent_dim), BLOCK_VERSION, jit.CASADI_VERSION,
                     str(jit.compiler()), str(block.hot), *jit.JIT_FLAGS, *jit.ONCE_FLAGS, str(jit.PIECE_INSTRUCTIONS),
                     *(["identity"] if block.identity else [])])
    return jit.cache_dir() / f"rb_{hashlib.sha256(key.encode()).hexdigest()[:24]}.json"


def _load(block: RobotBlock, libs: list[list[str]]) -> dict[str, ca.Function]:
    """The compiled pieces (their libraries ``libs``, one list per piece) chained (:mod:`.split`)."""
    names = {"rows": block.name, "jac": f"{block.name}_jac", "hess": f"{block.name}_hess"}
    out = {}
    for (k, n), parts in zip(names.items(), libs):
        ext = [ca.external(n if len(parts) == 1 else split.piece_name(n, i), lib) for i, lib in enumerate(parts)]
        out[k] = split.chain(n, ext)
    return out


def _cached_libraries(entry: dict) -> list[list[str]] | None:
    """The verified libraries a cache index names, one list per piece; None if any is missing."""
    libs = [[jit.cached_library(name) for name in parts] for parts in entry["libraries"]]
    if len(libs) != len(PIECES) or any(lib is None for parts in libs for lib in parts):
        return None
    return [[str(lib) for lib in parts] for parts in libs]


def compile_blocks(blocks: list[RobotBlock]) -> list[RobotBlock]:
    """Give each block its ``rows``, ``jac`` and ``hess`` Functions: compiled C from the disk
    cache (its index names the libraries, verified by :func:`jit.cached_library`), else generated
    and compiled now (a progress bar over the libraries), else (no
    compiler, ``LATENTOC_JIT=0``) CasADi's SX Functions."""
    todo = []
    for b in blocks:
        if b.functions or not jit.enabled():  # without JIT the SX pieces are built when first used
            continue
        try:  # the index names its libraries; they are looked up in the cache and verified
            entry = json.loads(_index_file(b).read_text())
            cached = _cached_libraries(entry)
            if cached is not None:
                b.functions, b.libraries = _load(b, cached), entry["libraries"]
                b.instructions = {str(k): int(v) for k, v in dict(entry.get("instructions", {})).items()}
                continue
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            pass
        todo.append(b)
    if not todo:
        return blocks
    started = time.perf_counter()
    try:
        _compile(todo)
    finally:
        _COMPILE_SECONDS[0] += time.perf_counter() - started
    return blocks


def _compile(todo: list[RobotBlock]) -> None:
    """Build, compile (or find compiled) and load the derivative libraries of the blocks ``todo``: a
    hot Function in pieces (:mod:`.split`), each large hot piece's quick library first and its
    optimised one in the background (:mod:`.upgrade`)."""
    fns: dict[str, dict[str, ca.Function]] = {}
    futures: dict[str, list[list]] = {}  # block -> Function -> its pieces' libraries
    later: dict[str, dict[tuple[int, int], tuple[str, tuple[str, ...], str]]] = {}  # (Function, piece) -> optimised build
    with jit.Compiler() as cc:
        for b in bar(todo, desc="building the robot blocks' derivatives", unit="block"):
            fns[b.name] = b.derivative_functions()
            futures[b.name], later[b.name] = [], {}
            for i, f in enumerate(fns[b.name].values()):
                futures[b.name].append([])
                for j, part in enumerate(b.compiled_parts(f)):
                    source, flags = jit.c_source(part), jit.flags_for(b.hot)
                    final = jit.library_path(source, flags).name
                    if upgrade.quick_first(part.n_instructions(), flags) and jit.cached_library(final) is None:
                        later[b.name][i, j] = (source, flags, final)
                        flags = jit.ONCE_FLAGS
                    futures[b.name][i].append(cc.submit(part.name(), source, flags))
    for b in todo:
        built: list[list[Path | None]] = [[f.result() for f in parts] for parts in futures[b.name]]
        if any(lib is None for parts in built for lib in parts):
            b.functions = fns[b.name]
            continue
        libs: list[list[Path]] = built  # type: ignore[assignment]  # none is None
        index = _index_file(b)
        tmp = index.with_name(f".{index.name}.{os.getpid()}")
        b.instructions = {k: f.n_instructions() for k, f in fns[b.name].items()}
        entry: dict[str, Any] = {"block": b.name, "libraries": [[p.name for p in parts] for parts in libs],
                                 "instructions": b.instructions}
        tmp.write_text(json.dumps(entry))
        os.replace(tmp, index)
        b.functions, b.libraries = _load(b, [[str(p) for p in parts] for parts in libs]), entry["libraries"]
        if later[b.name]:
            optimised = [[later[b.name][i, j][2] if (i, j) in later[b.name] else lib.name for j, lib in enumerate(parts)]
                         for i, parts in enumerate(libs)]
            upgrade.start(index, {**entry, "libraries": optimised}, list(later[b.name].values()))
            b.upgrading = index


def stack_tangents(G: np.ndarray) -> np.ndarray:
    """K x D x d tangents as the data of the D x (K d) matrix a mapped block takes (column-major)."""
    return np.transpose(G, (0, 2, 1))
