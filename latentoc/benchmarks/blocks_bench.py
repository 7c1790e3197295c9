"""Robot-block sizes: SX instructions of each broad-jump row family's compiled pieces.

Run: ``python -m latentoc bench blocks [--compile]``. Prints, per row family, its outputs, its
local inputs and the instructions of its rows, local Jacobian and local Hessian
(:mod:`latentoc.nlp.blocks`); with ``--compile`` also gcc's time at -O0 and -O1 for each piece
and one evaluation mapped over the family's nodes in the packaged problem (one thread).
"""
from __future__ import annotations

import argparse
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

NODES = {"contact": 94, "flight_dynamics": 80, "flight_clearance": 78, "pitch_rate": 159, "takeoff": 1, "touchdown": 1}


def main(argv: list[str] | None = None) -> int:
    from latentoc.jump.problem import setup
    from latentoc.jump.rows import row_blocks
    from latentoc.nlp.jit import compiler

    p = argparse.ArgumentParser(prog="blocks_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--compile", action="store_true", help="also time gcc and one mapped evaluation")
    a = p.parse_args(argv)
    js = setup(0)
    blocks = row_blocks(js.robot(0.4), js.gpdm.latent_dim)
    print("| family | outputs | local inputs | rows | local Jacobian | local Hessian |")
    print("| --- | --- | --- | --- | --- | --- |")
    fns = {}
    for name, b in blocks.items():
        fns[name] = b.derivative_functions()
        n = {k: f.n_instructions() for k, f in fns[name].items()}
        print(f"| {name} | {b.n_out} | {b.n_local} | {n['rows']:,} | {n['jac']:,} | {n['hess']:,} |", flush=True)
    if not a.compile:
        return 0
    cc = compiler()
    print("\n| piece | instructions | gcc -O0 s | gcc -O1 s | map -O0 ms | map -O1 ms |")
    print("| --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for name, group in fns.items():
            for f in group.values():
                gen = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
                gen.add(f)
                src = Path(tmp) / f"{f.name()}.c"
                src.write_text(gen.dump())
                row = [f.name(), f"{f.n_instructions():,}"]
                evals = []
                for flag in ("-O0", "-O1"):
                    lib = Path(tmp) / f"{f.name()}{flag}.so"
                    t0 = time.perf_counter()
                    subprocess.run([cc, flag, "-shared", "-fPIC", "-o", str(lib), str(src)], check=True)
                    row.append(f"{time.perf_counter() - t0:.1f}")
                    m = ca.external(f.name(), str(lib)).map(NODES[name])
                    args = [np.random.default_rng(0).random(m.size_in(i)) for i in range(m.n_in())]
                    m(*args)
                    ts = []
                    for _ in range(5):
                        t0 = time.perf_counter()
                        m(*args)
                        ts.append(time.perf_counter() - t0)
                    evals.append(f"{1e3 * float(np.median(ts)):.1f}")
                print("| " + " | ".join(row + evals) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
