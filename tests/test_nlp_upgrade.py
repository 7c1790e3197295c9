"""latentoc.nlp.upgrade: a large hot piece is compiled quickly (-O0) first and optimised (-O1) by a
detached process, which then points the block's cache index at the optimised library; both give
the same values bit for bit."""
import json

import casadi as ca
import numpy as np
import pytest

from latentoc.nlp import blocks, jit, upgrade
from latentoc.nlp.blocks import RobotBlock, block_inputs, compile_blocks


def _block() -> RobotBlock:
    y, yd, ydd, r = block_inputs(3, 1)
    f = ca.vertcat(ca.sin(y[0]) * yd[1] * ca.exp(y[2]), r[0] * ydd[0] ** 2 + ca.cos(y[1] * yd[2]))
    return RobotBlock.from_parts("lc_upgraded", (y, yd, ydd, r), {"f": f}, 2)


def _values(b: RobotBlock) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    out = []
    for f in b.functions.values():
        args = [rng.standard_normal(f.sparsity_in(i).shape) for i in range(f.n_in())]
        out += [np.asarray(v) for v in (f.call(args))]
    return out


def _names(index) -> list[str]:
    """The libraries a block's cache index names (a list per Function, one name per piece)."""
    return [name for parts in json.loads(index.read_text())["libraries"] for name in parts]


def test_a_large_piece_is_compiled_quickly_then_optimised_in_the_background(tmp_path, monkeypatch):
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setattr(upgrade, "QUICK_FIRST", 0)  # every hot piece counts as large
    quick_block = compile_blocks([_block()])[0]
    assert all(f.is_a("External") for f in quick_block.functions.values())
    index = next(tmp_path.glob("rb_*.json"))
    quick = _names(index)
    upgrade.wait()
    final = _names(index)
    assert len(json.loads(index.read_text())["libraries"]) == 3 and not set(final) & set(quick)  # the flags are part of a library's key
    assert all(jit.cached_library(name) is not None for name in final)
    assert not list(tmp_path.glob(".upgrade-*"))
    optimised = compile_blocks([_block()])[0]  # a new solve: loaded through the rewritten index
    assert sorted(optimised.functions) == sorted(quick_block.functions)
    for a, b in zip(_values(quick_block), _values(optimised)):
        assert np.array_equal(a, b)


def test_settle_waits_for_an_upgrade_it_did_not_start(tmp_path, monkeypatch):
    """settle watches the cache, not this process's children: what a benchmark or a test needs once
    a solve in a subprocess started the upgrade."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setattr(upgrade, "QUICK_FIRST", 0)
    compile_blocks([_block()])
    index = next(tmp_path.glob("rb_*.json"))
    quick = _names(index)
    assert list(tmp_path.glob(".upgrade-*"))  # the detached process is at work
    assert upgrade.settle(tmp_path, timeout=120)
    final = _names(index)  # settled: the index already names the -O1 ones
    assert not set(final) & set(quick) and all(jit.cached_library(name) is not None for name in final)
    upgrade.wait()


def test_the_process_switches_to_the_optimised_libraries_when_they_are_built(tmp_path, monkeypatch):
    """A block compiled quickly keeps evaluating; once the detached build has rewritten its index,
    its next mapped call loads the optimised libraries (named by the index), with the same values."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    monkeypatch.setattr(upgrade, "QUICK_FIRST", 0)
    monkeypatch.setattr(blocks, "UPGRADE_POLL_S", 0.0)
    b = compile_blocks([_block()])[0]
    index = next(tmp_path.glob("rb_*.json"))
    quick = _names(index)
    assert [n for parts in b.libraries for n in parts] == quick and b.upgrading == index
    args = [np.full(3, 0.3), np.full(3, -0.2), np.full(3, 0.1), np.full(1, 0.5)]
    before = b.mapped("rows", 1)(*args)
    upgrade.wait()
    after = b.mapped("rows", 1)(*args)
    assert [n for parts in b.libraries for n in parts] == _names(index) != quick and b.upgrading is None
    assert all(np.array_equal(x, y) for x, y in zip(before, after))
