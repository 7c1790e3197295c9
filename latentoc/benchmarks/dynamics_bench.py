"""Benchmark of the symbolic dynamics: build time, SX size and evaluation cost.

``python -m latentoc bench dynamics`` prints, per robot: nq, SX nodes of rnea, time to build
all Functions of :class:`~latentoc.dynamics.SymbolicModel`, and the time of one rnea
evaluation and of its Jacobian, CasADi next to numeric Pinocchio.
"""

from __future__ import annotations

import argparse
import time

import casadi
import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.robots import load_robot

DEFAULT_ROBOTS = ("panda", "ur5", "talos", "human", "cmu-humanoid")


def _per_call(fn, repeats: int) -> float:
    fn()
    start = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - start) / repeats


def bench_robot(name: str, repeats: int = 200) -> dict:
    """Measure one robot; times in seconds."""
    model = load_robot(name)
    start = time.perf_counter()
    sym = SymbolicModel(model)
    functions = [sym.rnea, sym.com, sym.centroidal_momentum, sym.centroidal_momentum_rate,
                 sym.mass_matrix, sym.integrate, sym.difference]
    frame = model.frames[model.nframes - 1].name
    functions += [sym.frame_placement(frame), sym.frame_velocity(frame), sym.frame_jacobian(frame)]
    build = time.perf_counter() - start

    q = pin.neutral(model)
    rng = np.random.default_rng(0)
    v, a = rng.normal(size=model.nv), rng.normal(size=model.nv)
    qs, vs, as_ = (casadi.SX.sym(n, k) for n, k in (("q", model.nq), ("v", model.nv), ("a", model.nv)))
    tau = sym.rnea(qs, vs, as_)
    jac = casadi.Function("rnea_jac", [qs, vs, as_], [casadi.jacobian(tau, casadi.vertcat(qs, vs, as_))])
    data = model.createData()
    return {
        "robot": name,
        "nq": model.nq,
        "nv": model.nv,
        "backend": sym.backend,
        "rnea_nodes": sym.rnea.n_instructions(),
        "build_s": build,
        "rnea_casadi_s": _per_call(lambda: sym.rnea(q, v, a), repeats),
        "rnea_pinocchio_s": _per_call(lambda: pin.rnea(model, data, q, v, a), repeats),
        "jac_casadi_s": _per_call(lambda: jac(q, v, a), max(repeats // 10, 5)),
        "jac_pinocchio_s": _per_call(lambda: pin.computeRNEADerivatives(model, data, q, v, a), repeats),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="latentoc bench dynamics", description=__doc__.splitlines()[0])
    parser.add_argument("robots", nargs="*", default=list(DEFAULT_ROBOTS))
    parser.add_argument("--repeats", type=int, default=200)
    args = parser.parse_args(argv)
    header = (f"{'robot':<14}{'nq':>4}{'rnea SX nodes':>15}{'build all [s]':>15}"
              f"{'rnea casadi':>13}{'rnea pin':>11}{'jac casadi':>12}{'jac pin':>11}")
    print(header)
    print("-" * len(header))
    for name in args.robots:
        r = bench_robot(name, args.repeats)
        print(f"{r['robot']:<14}{r['nq']:>4}{r['rnea_nodes']:>15}{r['build_s']:>15.3f}"
              f"{r['rnea_casadi_s'] * 1e6:>11.1f}us{r['rnea_pinocchio_s'] * 1e6:>9.1f}us"
              f"{r['jac_casadi_s'] * 1e6:>10.1f}us{r['jac_pinocchio_s'] * 1e6:>9.1f}us")
    print(f"backend: {r['backend']}; build = all Functions of SymbolicModel incl. 3 frame Functions")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
