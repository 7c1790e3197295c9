"""Broad-jump benchmark: the first solve on an empty cache, cold solves, where their time goes.

Run: ``python -m latentoc bench jump [--tubes 0.02] [--no-first] [--no-second-gpdm] [--families]``.
Targets (issue 27): the first solve <= 3 min with all compilation; a second GPDM on a warm
cache compiles nothing; a cold solve <= 20 s; function evaluations <= 50 ms per iteration.

* first solve: ``python -m latentoc solve broad-jump`` in a subprocess with a new, empty
  ``$LATENTOC_CACHE``: wall time from process start to exit, the robot blocks' compile time,
  the peak resident memory of the process;
* second GPDM: with that cache, the blocks of a jump learned on every 2nd frame (another GPDM):
  how many libraries are compiled (none: the blocks are the robot's);
* cold solves: phase 1 and phase 2's exchange rounds from the training fit; iterations, wall
  times, and per callback (:attr:`latentoc.nlp.ipopt.IpoptResult.timings`) ms per call x calls,
  the evaluations' ms per iteration and what is left for Ipopt itself (MUMPS, line search).
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from latentoc.nlp import upgrade
from latentoc.results import load_result

TARGET_FIRST_S, TARGET_COLD_S, TARGET_EVAL_MS = 180.0, 20.0, 50.0
CALLBACKS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l")


def first_solve(tube: float, cache: str) -> dict:
    """``latentoc solve broad-jump`` in a subprocess on the (empty) block cache ``cache``."""
    with tempfile.TemporaryDirectory(prefix="latentoc-bench-") as tmp:
        env = {**os.environ, "LATENTOC_CACHE": cache, "LATENTOC_QUIET": "1"}
        cmd = [sys.executable, "-m", "latentoc", "solve", "broad-jump", "--tube", str(tube), "--quiet",
               "--keep-failed", "--out", os.path.join(tmp, "out")]
        t0 = time.perf_counter()
        run = subprocess.run(cmd, env=env, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        upgrade.settle(Path(cache))  # its detached -O1 builds must not share the next timings' cores
        if run.returncode not in (0, 1):
            raise RuntimeError(f"{' '.join(cmd)} failed ({run.returncode}):\n{run.stderr[-2000:]}")
        r = load_result(os.path.join(tmp, "out"))
    rss_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return {"wall": wall, "rss_mb": rss_mb, "compile_time_s": r.times.compile_s, "status": r.status,
            "distance": r.cost}


def second_gpdm(cache: str) -> int:
    """Libraries compiled for the blocks of a jump whose GPDM learns every 2nd frame."""
    from latentoc.jump.problem import setup

    old = os.environ.get("LATENTOC_CACHE")
    os.environ["LATENTOC_CACHE"] = cache
    try:
        before = set(Path(cache).glob("*.so"))
        js = setup(0, stride=2)
        js.blocks(js.robot(0.4))
        return len(set(Path(cache).glob("*.so")) - before)
    finally:
        if old is None:
            del os.environ["LATENTOC_CACHE"]
        else:
            os.environ["LATENTOC_CACHE"] = old


def cold_solve(tube: float) -> dict:
    from latentoc.jump.problem import problem_setup, settings_from_problem
    from latentoc.jump.solve.solve import solve_jump
    from latentoc.latent.gp_layer import GPLayer
    from latentoc.problem.toml_files import load_problem

    problem = load_problem("broad-jump")
    js = problem_setup(problem)
    s = settings_from_problem(problem, tube)
    robot = js.robot(s.mu)
    t0 = time.perf_counter()
    blocks = js.blocks(robot)
    load = time.perf_counter() - t0
    sol = solve_jump(robot, GPLayer(js.gpdm), blocks, js.phases, s, js.init, js.model)
    return {"load": load, "sol": sol}


def family_times(tube: float, repeat: int = 5) -> list[tuple]:
    """Median ms of each row family's values, local Jacobians and local Hessians at the training
    start of phase 2's first NLP (every node row, samples on the packaged grids)."""
    import numpy as np

    from latentoc.jump.schedule.phases import contact_sample_grid, flight_sample_grid
    from latentoc.jump.transcription.nlp import build_nlp, tube_times
    from latentoc.jump.problem import problem_setup, settings_from_problem
    from latentoc.jump.transcription.selection import Selection
    from latentoc.jump.solve.initial_point import initial_point
    from latentoc.latent.gp_layer import GPLayer
    from latentoc.problem.toml_files import load_problem

    problem = load_problem("broad-jump")
    js = problem_setup(problem)
    s = settings_from_problem(problem, tube)
    robot, layer, ph = js.robot(s.mu), GPLayer(js.gpdm), js.phases
    full = Selection.every_node_row(s.n_stance + s.n_land, robot.unmirrored.size, tube_times(ph, layer))
    selection = full.with_samples(contact_sample_grid(s, ph), flight_sample_grid(s, ph))
    nlp = build_nlp(robot, layer, js.blocks(robot), ph, s, js.init["P"], "distance", selection)
    w = initial_point(robot, layer, nlp, ph, js.init["P"], js.init["x_L"])
    rows = []
    for f in nlp.nlp.families:
        if f.evaluator is None or not f.K:
            continue
        S = f.local_inputs(w)
        lam = np.ones((f.K, f.evaluator.n_out))
        times = []
        for call in (lambda: f.evaluator.values(S), lambda: f.evaluator.jacobian(S),
                     lambda: f.evaluator.hessian(S, lam)):
            ts = []
            for _ in range(repeat):
                if hasattr(f.evaluator, "_last"):
                    f.evaluator._last = None  # the GP layer's motion is part of each call
                t0 = time.perf_counter()
                call()
                ts.append(time.perf_counter() - t0)
            times.append(1e3 * float(np.median(ts)))
        rows.append((f.name, f.K, f.evaluator.n_in, *times))
    return rows


def _run_line(name: str, run) -> str:
    cb = " ".join(f"{1e3 * run.timings.get(n, 0.0) / max(run.calls.get(n, 0), 1):7.1f}x{run.calls.get(n, 0):<4d}"
                  for n in CALLBACKS)
    evals = sum(run.timings.values())
    return (f"  {name}: {run.iterations:4d} it {run.time_s:7.1f} s  evaluations {1e3 * evals / max(run.iterations, 1):6.0f} "
            f"ms/it  Ipopt itself {run.time_s - evals:6.1f} s  [{cb}]  {run.status}")


def main(argv: list[str] | None = None) -> int:
    """Print the first solve, the second GPDM's compilation, then each cold solve."""
    p = argparse.ArgumentParser(prog="jump_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tubes", nargs="*", type=float, default=[0.02])
    p.add_argument("--no-first", action="store_true", help="skip the first solve on an empty cache")
    p.add_argument("--no-second-gpdm", action="store_true")
    p.add_argument("--families", action="store_true", help="only each row family's evaluation times")
    a = p.parse_args(argv)
    if a.families:
        print("| family | nodes | local inputs | values ms | local Jacobians ms | local Hessians ms |")
        print("| --- | --- | --- | --- | --- | --- |")
        for name, K, n_in, tv, tj, th in family_times(a.tubes[0]):
            print(f"| {name} | {K} | {n_in} | {tv:.1f} | {tj:.1f} | {th:.1f} |")
        return 0
    print(f"machine: {os.cpu_count()} CPUs, python {sys.version.split()[0]}; per-callback columns: "
          f"ms per call x calls of {', '.join(CALLBACKS)}")
    with tempfile.TemporaryDirectory(prefix="latentoc-cache-") as cache:
        if not a.no_first:
            r = first_solve(a.tubes[0], cache)
            print(f"first solve, empty cache (target {TARGET_FIRST_S:.0f} s): {r['wall']:.1f} s wall, of it compiling "
                  f"the robot blocks {r['compile_time_s']:.1f} s; peak RSS {r['rss_mb']:.0f} MB; {r['status']}, "
                  f"{r['distance']:.4f} m")
        if not a.no_second_gpdm and not a.no_first:
            print(f"second GPDM (every 2nd frame) on that cache: {second_gpdm(cache)} libraries compiled")
    for tube in a.tubes:
        t0 = time.perf_counter()
        out = cold_solve(tube)
        sol = out["sol"]
        r = sol.result
        wall = time.perf_counter() - t0
        t = r["times"]
        print(f"cold solve, delta {tube:g} (target {TARGET_COLD_S:.0f} s, evaluations {TARGET_EVAL_MS:.0f} ms/it): "
              f"{wall:.1f} s wall = solve {t['solve_s']:.1f} s + build {t['build_s']:.1f} s + 1 kHz checks "
              f"{t['check_s']:.1f} s + blocks loaded {out['load']:.1f} s + set-up; {r['distance']:.4f} m; "
              f"{r['n_variables']} variables, {r['n_constraints']} rows; "
              f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
        if sol.phase1 is not None:
            print(_run_line("phase 1", sol.phase1))
        for k, rd in enumerate(r["phase2_rounds"]):
            print(f"  phase 2, round {k + 1}: {rd['iterations']:4d} it {rd['time_s']:6.1f} s, {rd['n_constraints']} rows, "
                  f"{rd['contact_samples']} contact / {rd['flight_samples']} flight samples, {rd['status']}")
        print(_run_line("phase 2, last round", sol.phase2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
