"""Arm benchmark: the first solve on an empty cache, warm solve times and where they go.

Run: ``python -m latentoc bench arm [--problem arm-raise] [--tubes 5x] [--ranges 20 60]
[--repeat 5] [--no-first]``. Targets: the first solve <= 5 s, the 5x solve <= 0.3 s.

* first solve: ``python -m latentoc solve`` in a subprocess with a new, empty
  ``$LATENTOC_CACHE`` (so every robot block is generated and compiled, its large pieces quickly:
  :mod:`latentoc.nlp.upgrade`), wall time from process start to exit and where it goes (:func:`split`);
* warm solves: each NLP (:mod:`latentoc.min_torque.nlp`) built once, then solved ``--repeat``
  times from the training fit; the median wall and CPU time, Ipopt's iterations, and per
  callback (:attr:`latentoc.nlp.ipopt.IpoptResult.timings`) ms per call x calls, plus what is
  left for Ipopt itself.

The header names the threads of the mapped blocks (``$LATENTOC_THREADS``) and of numpy's BLAS
(``$OPENBLAS_NUM_THREADS``) and the machine's load average: on a shared machine, wall times
follow the load.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from latentoc.dynamics import SymbolicModel
from latentoc.min_torque.nlp import ipopt_options, joint_range_nlp, latent_nlp
from latentoc.min_torque.settings import MinTorqueSettings
from latentoc.min_torque.training import problem_gpdm, training_frames
from latentoc.motions import TRAINING_MOTIONS
from latentoc.nlp import ipopt, upgrade
from latentoc.runtime.threads import mapped_threads
from latentoc.problem.toml_files import load_problem
from latentoc.runtime.progress import set_quiet
from latentoc.results import load_result
from latentoc.robots import load_robot
from latentoc.latent.tube import resolve_tube

TARGET_FIRST_S, TARGET_5X_S = 5.0, 0.3
CALLBACKS = (("f", "nlp_f"), ("g", "nlp_g"), ("grad_f", "nlp_grad_f"), ("jac_g", "nlp_jac_g"), ("hess", "nlp_hess_l"))


def first_solve(problem: str, tube: str) -> dict:
    """``latentoc solve`` in a subprocess on an empty block cache: wall time and its result."""
    with tempfile.TemporaryDirectory(prefix="latentoc-bench-") as tmp:
        env = {**os.environ, "LATENTOC_CACHE": os.path.join(tmp, "cache"), "LATENTOC_QUIET": "1"}
        cmd = [sys.executable, "-m", "latentoc", "solve", problem, "--tube", tube, "--quiet",
               "--out", os.path.join(tmp, "out")]
        t0 = time.perf_counter()
        run = subprocess.run(cmd, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        upgrade.settle(Path(tmp) / "cache")  # its detached -O1 build must not share the next timings' cores
        if run.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({run.returncode}):\n{run.stderr[-2000:]}")
        r = load_result(os.path.join(tmp, "out"))
    t = r.times
    return {"wall": wall, "imports": _imports(), "gpdm_time_s": t.gpdm_s, "compile_time_s": t.compile_s,
            "build_time_s": t.build_s, "solve_time_s": t.solve_s, "check_time_s": t.check_s, "total_s": t.total_s,
            "iterations": r.iterations, "cost": r.cost, "status": r.status}


def _imports() -> float:
    """Wall of a Python process that imports what ``solve`` of an arm problem imports, then exits."""
    code = "import latentoc.cli.commands, latentoc.api, latentoc.problem.toml_files, latentoc.min_torque.kind"
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True)
    return time.perf_counter() - t0


def split(r: dict) -> str:
    """Where a first solve's wall goes: Python's start and the imports, then the solve's own times
    (result.json), and the rest (reading the problem, loading libraries, writing the folder)."""
    rest = r["wall"] - r["imports"] - r["total_s"]
    return (f"Python start and imports {r['imports']:.2f} s, GPDM {r['gpdm_time_s']:.2f} s, code generation and "
            f"compiling {r['compile_time_s']:.2f} s, NLP build {r['build_time_s']:.2f} s, Ipopt {r['solve_time_s']:.2f} s,"
            f" 1 kHz checks {r['check_time_s']:.2f} s, the rest (problem, libraries, writing) {rest:.2f} s")


def warm_solves(nlp, problem, repeat: int) -> dict:
    """``repeat`` solves of a built NLP: the median times and the median solve's details."""
    options = ipopt_options(nlp, tol=problem.tol, max_iter=problem.max_iter)
    runs = []
    for _ in range(repeat):
        c0 = time.process_time()
        res = ipopt.solve(nlp.nlp, nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, options, hessian=problem.hessian)
        runs.append((res.time_s, time.process_time() - c0, res))
    runs.sort(key=lambda r: r[0])
    wall, cpu, res = runs[len(runs) // 2]
    return {"wall": wall, "cpu": float(np.median([r[1] for r in runs])), "res": res}


def _line(method: str, param: str, build: float, r: dict) -> str:
    res = r["res"]
    cb = " ".join(f"{1e3 * res.timings.get(n, 0.0) / max(res.calls.get(n, 0), 1):6.2f}x{res.calls.get(n, 0):<3d}"
                  for _, n in CALLBACKS)
    rest = res.time_s - sum(res.timings.values())
    return (f"{method:12s} {param:>5s} {build:7.2f} {r['wall']:7.3f} {r['cpu']:7.3f} {res.iterations:5d} "
            f"{res.f:14.7f}  {cb} {rest:6.3f}  {res.status}")


def main(argv: list[str] | None = None) -> int:
    """Print the first solve, then one line per warm solve."""
    p = argparse.ArgumentParser(prog="arm_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--problem", default="arm-raise")
    p.add_argument("--tubes", nargs="*", default=["5x"])
    p.add_argument("--ranges", nargs="*", type=float, default=[20.0, 60.0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--no-first", action="store_true", help="skip the empty-cache first solve")
    args = p.parse_args(argv)
    problem = load_problem(args.problem)
    print(f"{args.problem}: block threads {mapped_threads()}, OPENBLAS_NUM_THREADS "
          f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, load average {os.getloadavg()[0]:.2f}", flush=True)
    if not args.no_first:
        tube = args.tubes[0] if args.tubes else str(problem.tube)
        r = first_solve(args.problem, tube)
        verdict = "met" if r["wall"] <= TARGET_FIRST_S else "NOT met"
        print(f"first solve ({args.problem}, tube {tube}, empty cache, subprocess wall): {r['wall']:.2f} s "
              f"(target {TARGET_FIRST_S:g} s: {verdict}), {r['iterations']} iterations, cost {r['cost']:.4f}, "
              f"{r['status']}\n  {split(r)}", flush=True)

    set_quiet(True)  # no progress bars between the table's lines
    gp, gpdm_time = problem_gpdm(problem)
    sym = SymbolicModel(load_robot(problem.robot))
    settings = MinTorqueSettings.from_problem(problem)
    t_train, _ = training_frames(problem)
    t_all, Q_all = (np.asarray(a) for a in TRAINING_MOTIONS[problem.training]())
    print(f"warm solves, median of {args.repeat} (GPDM learned in {gpdm_time:.2f} s, {gp.X.shape[0]} frames); "
          f"callbacks: ms per call x calls; rest = solve - callbacks (Ipopt, CasADi)")
    print(f"{'method':12s} {'param':>5s} {'build s':>7s} {'solve s':>7s} {'cpu s':>7s} {'iter':>5s} {'cost':>14s}  "
          + " ".join(f"{k:>10s}" for k, _ in CALLBACKS) + f" {'rest s':>6s}  status")
    for k in (args.tubes or ["5x"])[:1]:  # compiles what the cache lacks, then waits for its optimised libraries
        latent_nlp(gp, sym, settings, resolve_tube(k, gp.tube_size()), t_train=t_train)
    upgrade.wait()
    for tube in args.tubes:
        t0 = time.perf_counter()
        nlp = latent_nlp(gp, sym, settings, resolve_tube(tube, gp.tube_size()), t_train=t_train)
        build = time.perf_counter() - t0
        r = warm_solves(nlp, problem, args.repeat)
        print(_line("latent", tube, build, r), flush=True)
        if tube == "5x":
            verdict = "met" if r["wall"] <= TARGET_5X_S else "NOT met"
            print(f"  5x solve {r['wall']:.3f} s (target {TARGET_5X_S:g} s: {verdict})", flush=True)
    for k in args.ranges:
        t0 = time.perf_counter()
        nlp = joint_range_nlp(sym, settings, t_all, Q_all, k)
        build = time.perf_counter() - t0
        print(_line("joint-range", f"{k:g}", build, warm_solves(nlp, problem, args.repeat)), flush=True)
    print(f"load average {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
