"""Robot-block sizes: SX instructions of each broad-jump row family's compiled pieces.

Run: ``python -m latentoc bench blocks [--problem broad-jump] [--newton-steps N] [--compile]``. Prints,
per row family of the problem's path (its latent dimension with the leg residual), its outputs, its
local inputs and the instructions of its rows, local Jacobian and local Hessian
(:mod:`latentoc.nlp.blocks`) and one evaluation of each in CasADi's virtual machine; ``--newton-steps``:
the planted leg's closure unrolled with N Newton steps instead of
:data:`~latentoc.jump.closure.planted_legs.NEWTON_STEPS` (what the unrolling costs); with ``--compile``
also gcc's time at -O0 and -O1 for each piece (a hot one in the pieces the package compiles, one
after another: :mod:`latentoc.nlp.split`) and one evaluation mapped over the family's nodes in the
packaged problem (one thread).
"""
from __future__ import annotations

import argparse
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

NODES = {"contact": 94, "flight_dynamics": 80, "flight_clearance": 78, "pitch_rate": 159, "takeoff": 1, "touchdown": 1,
         "hinge": 2}


def main(argv: list[str] | None = None) -> int:
    from latentoc.jump.closure import planted_legs
    from latentoc.jump.problem import jump_path, problem_setup
    from latentoc.jump.rows import row_blocks
    from latentoc.nlp import split
    from latentoc.nlp.jit import c_source, compiler
    from latentoc.problem.toml_files import load_problem

    p = argparse.ArgumentParser(prog="blocks_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--problem", default="broad-jump", help="a jump problem (default: broad-jump)")
    p.add_argument("--newton-steps", type=int, default=None, help="the closure's Newton steps (default: the package's)")
    p.add_argument("--compile", action="store_true", help="also time gcc and one mapped evaluation")
    a = p.parse_args(argv)
    problem = load_problem(a.problem)
    js = problem_setup(problem)
    d = jump_path(js, problem.options["leg_residual"]).layer.latent_dim
    steps = planted_legs.NEWTON_STEPS
    if a.newton_steps is not None:
        planted_legs.NEWTON_STEPS = a.newton_steps
    try:
        blocks = row_blocks(js.robot(0.4), d)
        print(f"{a.problem}: latent dimension {d} (with the leg residual), the closure's Newton steps "
              f"{planted_legs.NEWTON_STEPS}; ms: one evaluation in CasADi's virtual machine")
        print("| family | outputs | local inputs | rows | local Jacobian | local Hessian | Jacobian ms | Hessian ms |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        fns = {}
        for name, b in blocks.items():
            fns[name] = b.derivative_functions()
            n = {k: f.n_instructions() for k, f in fns[name].items()}
            ms = {k: _median_ms(f, [np.random.default_rng(0).normal(size=f.size_in(i)) * 0.01 for i in range(f.n_in())])
                  for k, f in fns[name].items() if k in ("jac", "hess")}
            print(f"| {name} | {b.n_out} | {b.n_local} | {n['rows']:,} | {n['jac']:,} | {n['hess']:,} | "
                  f"{ms['jac']:.2f} | {ms['hess']:.2f} |", flush=True)
    finally:
        planted_legs.NEWTON_STEPS = steps
    if not a.compile:
        return 0
    cc = compiler()
    print("\n| piece | instructions | compiled as | gcc -O0 s | gcc -O1 s | map -O0 ms | map -O1 ms |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for name, group in fns.items():
            for f in group.values():
                parts = blocks[name].compiled_parts(f)
                sources = []
                for part in parts:
                    sources.append(Path(tmp) / f"{part.name()}.c")
                    sources[-1].write_text(c_source(part))
                row = [f.name(), f"{f.n_instructions():,}", f"{len(parts)} piece{'s' * (len(parts) > 1)}"]
                evals = []
                for flag in ("-O0", "-O1"):
                    t0 = time.perf_counter()
                    compiled = []
                    for part, src in zip(parts, sources):
                        lib = Path(tmp) / f"{part.name()}{flag}.so"
                        subprocess.run([cc, flag, "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
                        compiled.append(ca.external(part.name(), str(lib)))
                    row.append(f"{time.perf_counter() - t0:.1f}")
                    m = split.chain(f.name(), compiled).map(NODES.get(name, 1))  # a family not listed: one node
                    args = [np.random.default_rng(0).random(m.size_in(i)) for i in range(m.n_in())]
                    evals.append(f"{_median_ms(m, args, 5):.1f}")
                print("| " + " | ".join(row + evals) + " |", flush=True)
    return 0


def _median_ms(f: ca.Function, args: list[np.ndarray], repeat: int = 20) -> float:
    """Median ms of one evaluation of ``f`` at ``args``, after one evaluation not timed."""
    f(*args)
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f(*args)
        ts.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(ts))


if __name__ == "__main__":
    raise SystemExit(main())
