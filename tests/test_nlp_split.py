"""latentoc.nlp.split: an SX Function cut into pieces and chained again gives the whole Function's
values bit for bit, in CasADi's virtual machine and compiled; a robot block compiled in pieces is
loaded through its cache index as the chain of its pieces' libraries."""
import json

import casadi as ca
import numpy as np
import pytest

from latentoc.nlp import jit, split
from latentoc.nlp.blocks import compile_blocks
from test_nlp_blocks import make_block


def _function() -> ca.Function:
    """Several outputs, one sparse, one an input itself and one written by the first instructions."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p", 2)
    e = x
    for i in range(6):
        e = ca.sin(e * p[0] + ca.vertcat(e[1:], e[0])) + ca.atan2(e, 1.5 + p[1] ** 2) * ca.exp(-e ** 2)
    H = ca.hessian(ca.dot(e, e) * p[1], x)[0]
    sparse = ca.SX(ca.Sparsity.lower(4), ca.vertcat(*[H[i, j] for j in range(4) for i in range(j, 4)]))
    return ca.Function("f", [x, p], [x[0] * 2.0, e, sparse, p], ["x", "p"], ["first", "e", "H", "p_out"])


def _args(f: ca.Function, seed: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.uniform(-1.5, 1.5, f.size_in(i)) for i in range(f.n_in())]


def _same(a, b) -> bool:
    return all(x.sparsity() == y.sparsity() and np.array_equal(np.asarray(x.nonzeros()), np.asarray(y.nonzeros()))
               for x, y in zip(a, b))


def test_pieces_chained_give_the_whole_functions_values_bit_for_bit():
    f = _function()
    size = f.n_instructions() // 5
    pieces = split.split_function(f, size)
    assert len(pieces) >= 4
    assert sum(p.n_instructions() for p in pieces) >= f.n_instructions()
    g = split.chain("f", pieces)
    assert g.name_in() == f.name_in() and g.name_out() == f.name_out()
    for seed in range(5):
        args = _args(f, seed)
        assert _same(f.call(args), g.call(args))
    K = 7  # mapped over nodes, as the blocks are called
    args = [np.hstack([a] * K) + 0.1 * np.arange(K) for a in _args(f, 9)]
    assert _same(f.map(K).call(args), g.map(K, "thread", 2).call(args))


def test_a_short_function_is_its_own_only_piece():
    f = _function()
    assert split.split_function(f, f.n_instructions()) == [f]
    assert split.chain("f", [f]) is f


def test_compiled_pieces_give_the_virtual_machines_values(tmp_path):
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    f = _function()
    pieces = split.split_function(f, f.n_instructions() // 3)
    compiled = []
    for p in pieces:
        gen = ca.CodeGenerator(f"{p.name()}.c", {"with_header": False})
        gen.add(p)
        lib = jit.build_library(jit.compiler(), gen.dump(), jit.JIT_FLAGS, tmp_path / f"{p.name()}.so")
        compiled.append(ca.external(p.name(), str(lib)))
    g = split.chain("f", compiled)
    for seed in range(3):
        args = _args(f, seed)
        assert _same(f.call(args), g.call(args))


def test_a_block_compiled_in_pieces_is_loaded_as_their_chain(tmp_path, monkeypatch):
    """With a small piece size the block's local Hessian is compiled as several libraries, named
    in order by the cache index; a new compile loads their chain, with the SX Function's values."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    sx = make_block().derivative_functions()
    monkeypatch.setattr(jit, "PIECE_INSTRUCTIONS", sx["hess"].n_instructions() // 3)
    compile_blocks([make_block()])
    entry = json.loads(next(tmp_path.glob("rb_*.json")).read_text())
    assert len(entry["libraries"][2]) >= 3
    b = compile_blocks([make_block()])[0]  # through the index
    assert b.functions["hess"].is_a("MXFunction")
    for k, f in sx.items():
        args = _args(f, 4)
        assert _same(f.call(args), b.functions[k].call(args))
