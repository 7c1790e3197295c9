"""Arm benchmark: build and solve times per arm solve, latent vs joint-range baseline.

Run: ``python -m latentoc bench arm [--problem arm-raise] [--tubes 1x 5x 50x] [--ranges 20 60]
[--reference] [--repeat 3]``. Targets (issue 5): solve <= 1 s once built, build < 5 s, and the
latent solve clearly faster than the full configuration-space baseline.

Each row builds the NLP and the Ipopt solver the way :func:`latentoc.solve.solve` does and
prints build s (wall), solve s (wall), solve CPU s (``time.process_time``; the machine may be
shared, so CPU is the number to compare), Ipopt iterations, the optimum cost, and per
evaluation ms (CPU) and call counts of the Hessian of the Lagrangian, the constraint
Jacobian and the objective gradient (from ``solver.stats()``), plus the rest of the solve
(Ipopt itself). ``--repeat`` solves each row several times and keeps the fastest CPU time.
``--reference`` adds the rows without this repository's structured/compiled derivatives
(CasADi's derivatives in the VM), the "before" of issue 5.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import casadi as ca
import numpy as np

from latentoc.dynamics import SymbolicModel
from latentoc.joint_space import build_joint_nlp
from latentoc.latent_motion import node_derivative_functions
from latentoc.problem import TRAINING_MOTIONS, load_problem, training_motion
from latentoc.robots import load_robot
from latentoc.solve import _settings, problem_gpdm, resolve_tube
from latentoc.solver import build_solver, jit_cache_dir, solve_nlp
from latentoc.transcription import build_latent_nlp

CALLBACKS = (("hess", "nlp_hess_l"), ("jac_g", "nlp_jac_g"), ("grad_f", "nlp_grad_f"))


def _run(build, problem, repeat: int) -> dict:
    """Build (timed) and solve ``repeat`` times; the fastest solve's numbers."""
    c0, t0 = time.process_time(), time.perf_counter()
    nlp = build()
    solver = build_solver(nlp.nlp, hessian=problem.hessian, max_iter=problem.max_iter, tol=problem.tol)
    float(ca.Function("cost", [nlp.nlp["x"]], [nlp.nlp["f"]])(nlp.w0))
    row = {"build": time.perf_counter() - t0, "build_cpu": time.process_time() - c0, "cpu": np.inf}
    for _ in range(repeat):
        c0 = time.process_time()
        res = solve_nlp(solver, nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg)
        cpu = time.process_time() - c0
        if cpu < row["cpu"]:
            st = solver.stats()
            row.update(cpu=cpu, wall=res.solve_time_s, iter=res.iterations, cost=res.cost, status=res.status)
            cb = 0.0
            for key, name in CALLBACKS + (("f", "nlp_f"), ("g", "nlp_g")):
                n, t = int(st.get(f"n_call_{name}", 0)), float(st.get(f"t_proc_{name}", 0.0))
                row[key] = (n, 1e3 * t / max(n, 1))
                cb += t
            row["ipopt"] = cpu - cb
    return row


def _line(method: str, param: str, r: dict) -> str:
    ev = " ".join(f"{r[k][1]:6.2f}x{r[k][0]:<3d}" for k, _ in CALLBACKS)
    return (f"{method:24s} {param:>6s} {r['build']:7.2f} {r['wall']:7.2f} {r['cpu']:7.2f} {r['iter']:5d} "
            f"{r['cost']:15.9f}  {ev} {r['ipopt']:6.2f}  {r['status']}")


def main(argv: list[str] | None = None) -> int:
    """Print one line per solve and the latent/baseline CPU ratio."""
    p = argparse.ArgumentParser(prog="arm_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--problem", default="arm-raise")
    p.add_argument("--tubes", nargs="*", default=["1x", "5x", "50x"])
    p.add_argument("--ranges", nargs="*", type=float, default=[20.0, 60.0])
    p.add_argument("--reference", action="store_true", help="also solve without structured/compiled derivatives")
    p.add_argument("--repeat", type=int, default=1)
    args = p.parse_args(argv)
    problem = load_problem(args.problem)
    gp, gpdm_time = problem_gpdm(problem)
    sym = SymbolicModel(load_robot(problem.robot))
    t_train, _ = training_motion(problem)
    t_all, Q_all = (np.asarray(a) for a in TRAINING_MOTIONS[problem.training]())
    base = _settings(problem, problem.control_points)
    t0 = time.perf_counter()
    node_derivative_functions(sym)
    print(f"{problem.name}: GPDM learned in {gpdm_time:.2f} s ({gp.X.shape[0]} frames); node derivatives "
          f"compiled or loaded in {time.perf_counter() - t0:.2f} s (cache {jit_cache_dir()})")
    variants = [("", base)]
    if args.reference:
        variants.append((" (reference)", dataclasses.replace(base, structured_derivatives=False, jit=False,
                                                             closed_form_grid=False)))
    print(f"{'method':24s} {'param':>6s} {'build s':>7s} {'solve s':>7s} {'cpu s':>7s} {'iter':>5s} {'cost':>15s}  "
          f"{'hess ms x n':>10s} {'jac_g ms x n':>10s} {'grad ms x n':>10s} {'ipopt':>6s}  status")
    cpu: dict[str, list[float]] = {}
    for label, st in variants:
        for tube in args.tubes:
            delta = resolve_tube(tube, gp.tube_size())
            r = _run(lambda: build_latent_nlp(gp, sym, st, delta, t_train), problem, args.repeat)
            cpu.setdefault("latent" + label, []).append(r["cpu"])
            print(_line("latent" + label, tube, r), flush=True)
        for k in args.ranges:
            r = _run(lambda: build_joint_nlp(sym, st, t_all, Q_all, float(k)), problem, args.repeat)
            cpu.setdefault("joint-range" + label, []).append(r["cpu"])
            print(_line("joint-range" + label, f"{k:g}", r), flush=True)
    for label, _ in variants:
        lat, jr = cpu.get("latent" + label), cpu.get("joint-range" + label)
        if lat and jr:
            print(f"mean solve CPU{label}: latent {np.mean(lat):.3f} s, joint-range {np.mean(jr):.3f} s, "
                  f"joint-range / latent = {np.mean(jr) / np.mean(lat):.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
