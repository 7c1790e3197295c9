"""Broad-jump benchmark: the first solve on an empty cache, the solve on a warm one, where its time goes.

Run: ``python -m latentoc bench jump [--tubes DELTA ...] [--no-first] [--no-second-gpdm] [--families]``;
``--profile [PROBLEM]``: only the warm solve of PROBLEM (default broad-jump) and where it goes.
Targets: the first solve <= 3 min with all compilation; a second GPDM on a warm cache compiles
nothing; the warm solve <= 60 s; a phase-2 Ipopt iteration <= 0.15 s.

* first solve: ``python -m latentoc solve broad-jump`` in a subprocess with a new, empty
  ``$LATENTOC_CACHE``: wall time from process start to exit, the robot blocks' compile time,
  the peak resident memory of the process;
* second GPDM: with that cache, the blocks of a jump learned on every 2nd frame (another GPDM):
  how many libraries are compiled (none: the blocks are the robot's);
* warm solves: the problem solved as ``solve`` does it, each Ipopt run's iterations and its
  milliseconds per iteration in the robot blocks, the latent layer, the chain rule and assembly,
  MUMPS and the rest of Ipopt (:mod:`.jump_profile`), then the builds, 1 kHz checks and set-up.
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

TARGET_FIRST_S, TARGET_WARM_S, TARGET_PHASE2_ITERATION_S = 180.0, 60.0, 0.15


def first_solve(tube: float | None, cache: str) -> dict:
    """``latentoc solve broad-jump`` in a subprocess on the (empty) block cache ``cache``."""
    with tempfile.TemporaryDirectory(prefix="latentoc-bench-") as tmp:
        env = {**os.environ, "LATENTOC_CACHE": cache, "LATENTOC_QUIET": "1"}
        cmd = [sys.executable, "-m", "latentoc", "solve", "broad-jump", "--quiet", "--keep-failed",
               "--out", os.path.join(tmp, "out")] + (["--tube", str(tube)] if tube is not None else [])
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


def family_times(tube: float | None, repeat: int = 5) -> list[tuple]:
    """Median ms of each row family's values, local Jacobians and local Hessians at the training
    start of phase 2's first NLP (every node row, samples on the packaged grids) on the packaged
    path (the leg residual's layer)."""
    import numpy as np

    from latentoc.jump.schedule.phases import contact_sample_grid, flight_sample_grid
    from latentoc.jump.transcription.nlp import build_nlp, tube_times
    from latentoc.jump.problem import jump_path, problem_setup, settings_from_problem
    from latentoc.jump.transcription.selection import Selection
    from latentoc.jump.solve.initial_point import initial_point
    from latentoc.latent.tube import tube_delta
    from latentoc.problem.toml_files import load_problem

    problem = load_problem("broad-jump")
    js = problem_setup(problem)
    s = settings_from_problem(problem, tube_delta(problem.tube, js.gpdm) if tube is None else tube)
    path = jump_path(js, problem.options["leg_residual"])
    robot, layer, ph = js.robot(s.mu), path.layer, js.phases
    full = Selection.every_node_row(s.n_stance + s.n_land, robot.unmirrored.size, tube_times(ph, layer))
    selection = full.with_samples(contact_sample_grid(s, ph), flight_sample_grid(s, ph))
    nlp = build_nlp(robot, layer, js.blocks(robot, layer), ph, s, path.P, "distance", selection, path.P_range)
    w = initial_point(robot, layer, nlp, ph, path.P, js.init["x_L"])
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


def main(argv: list[str] | None = None) -> int:
    """Print the first solve, the second GPDM's compilation, then each cold solve."""
    p = argparse.ArgumentParser(prog="jump_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--tubes", nargs="*", type=float, default=None, help="the tubes' deltas (default: the problem's)")
    p.add_argument("--no-first", action="store_true", help="skip the first solve on an empty cache")
    p.add_argument("--no-second-gpdm", action="store_true")
    p.add_argument("--families", action="store_true", help="only each row family's evaluation times")
    p.add_argument("--profile", nargs="?", const="broad-jump", metavar="PROBLEM",
                   help="only the warm solve of PROBLEM and where its iterations go")
    a = p.parse_args(argv)
    tubes = a.tubes or [None]
    if a.families:
        print("| family | nodes | local inputs | values ms | local Jacobians ms | local Hessians ms |")
        print("| --- | --- | --- | --- | --- | --- |")
        for name, K, n_in, tv, tj, th in family_times(tubes[0]):
            print(f"| {name} | {K} | {n_in} | {tv:.1f} | {tj:.1f} | {th:.1f} |")
        return 0
    print(f"machine: {os.cpu_count()} CPUs, python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.2f}")
    if not a.profile:
        with tempfile.TemporaryDirectory(prefix="latentoc-cache-") as cache:
            if not a.no_first:
                r = first_solve(tubes[0], cache)
                print(f"first solve, empty cache (target {TARGET_FIRST_S:.0f} s): {r['wall']:.1f} s wall, of it "
                      f"compiling the robot blocks {r['compile_time_s']:.1f} s; peak RSS {r['rss_mb']:.0f} MB; "
                      f"{r['status']}, {r['distance']:.4f} m")
            if not a.no_second_gpdm and not a.no_first:
                print(f"second GPDM (every 2nd frame) on that cache: {second_gpdm(cache)} libraries compiled")
    for tube in tubes:
        warm_solve(a.profile or "broad-jump", tube)
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


def warm_solve(name: str, tube: float | None) -> None:
    """Solve ``name`` (at ``tube``; None: the problem's) as ``solve`` does, on the warm cache, under the
    profile's timers, and print its times and each Ipopt run's split."""
    from latentoc.benchmarks.jump_profile import block_table, profile_table, profiled
    from latentoc.errors import LatentocError
    from latentoc.jump.problem import solve_jump_problem
    from latentoc.problem.toml_files import load_problem

    t0 = time.perf_counter()
    with profiled() as profile:
        runs = profile.runs
        try:
            sol = solve_jump_problem(load_problem(name), **({} if tube is None else {"tube": tube}))
        except LatentocError as exc:  # a solve that fails still shows where its iterations went
            print(f"{name}: {exc} ({time.perf_counter() - t0:.1f} s)")
            print("\n".join(profile_table(runs)))
            return
    wall = time.perf_counter() - t0
    r = sol.result
    ipopt_s = sum(x.time_s for x in runs)
    rest = wall - ipopt_s - r["build_time_s"] - r["check_time_s"] - r["compile_time_s"] - r["gpdm_time_s"]
    print(f"{name}, delta {r['tube']:g}, warm cache (target {TARGET_WARM_S:.0f} s): {wall:.1f} s = Ipopt "
          f"{ipopt_s:.1f} s + NLP builds {r['build_time_s']:.1f} s (of them the consistent start "
          f"{profile.seconds['consistent start']:.1f} s) + 1 kHz checks {r['check_time_s']:.1f} s + blocks "
          f"{r['compile_time_s']:.1f} s + GPDM {r['gpdm_time_s']:.1f} s + set-up {rest:.1f} s; {r['status']}, "
          f"{r['distance']:.4f} m, {r['iterations']} iterations; peak RSS "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MB")
    start = dict(r.get("start_violation") or {})
    if start:
        worst = sorted(((v, k) for k, v in start.items() if k != "max"), reverse=True)[:3]
        print(f"  phase 1's start: largest row violation {start['max']:.3g} (" +
              ", ".join(f"{k} {v:.3g}" for v, k in worst) + ")")
    phase2 = [x for x in runs if "phase 2" in x.desc]
    if phase2:
        per_it = sum(x.time_s for x in phase2) / max(sum(x.iterations for x in phase2), 1)
        print(f"  a phase-2 Ipopt iteration: {per_it:.3f} s (target {TARGET_PHASE2_ITERATION_S:g} s)")
    print("\n".join(profile_table(runs)))
    print("\n".join(block_table(runs)))


if __name__ == "__main__":
    raise SystemExit(main())
