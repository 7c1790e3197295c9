"""GPDM learning benchmark (issues 28 and 52): each case in a fresh process, its learning time, peak memory,
Eq. 16, Newton iterations and convergence, with the machine it ran on.

* the motions of :mod:`latentoc.benchmarks.gpdm_motions`, each N = 350, D = 37, d = 3 (the synthetic set,
  the CMU jump, the panda reach, a noisy curve with loops, a slow random walk): <= 3 s, converged, and Eq. 16
  at the saddle-free learner's minimum to 1e-8 |L| (``same_minimum``; column "- today": L minus it);
* the panda example at stride 1 from the CLI (examples/panda-reach/reach.csv, 251 x 7): <= 2 s wall,
  ``/usr/bin/time -v python -m latentoc learn ... --robot panda --hold ...`` (the README's command);
* the broad jump's training set (157 x 37): <= 10 s, and the minimum of the shipped model;
* synthetic N = 1000, D = 37: <= 2 min and <= 2 GB peak (left out by ``--quick``).

``--scaling``: time and peak memory for N = 350, 1000, 2000 (D = 37), docs/gpdm.md's table.
``--split [MOTION]``: each motion's (or one's) learning time level by level (evaluations, Hessians,
eigendecompositions).
Run: ``python -m latentoc bench gpdm [--scaling | --split [MOTION]] [--quick]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from latentoc.benchmarks.gpdm_motions import MINIMA, MOTIONS, PANDA, benchmark_motion, same_minimum, synthetic_motion

__all__ = ["main", "synthetic_motion"]


def machine() -> str:
    """CPU model, cores, load average, numpy / scipy versions."""
    import scipy

    cpu = platform.processor() or "?"
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = ", ".join(f"{x:.2f}" for x in os.getloadavg())
    return (f"{cpu}, {os.cpu_count()} cores, load average {load}; numpy {np.__version__}, scipy {scipy.__version__}, "
            f"Python {platform.python_version()}")


def _data(case: str) -> np.ndarray:
    """A case's training data: a motion of gpdm_motions by name, the broad jump's training set ("jump157") or
    the synthetic set of N x D frames ("NxD")."""
    if case in MOTIONS:
        return benchmark_motion(case)
    if case == "jump157":
        from latentoc.jump.demonstration.training import training_jumps

        return training_jumps(0)[0].Y
    N, D = (int(x) for x in case.split("x"))
    return synthetic_motion(N, D)


def _child(case: str) -> dict:
    """One case, learned in this process: its data, learning time and model."""
    from latentoc.gpdm import GPDMSettings, learn_gpdm
    from latentoc.runtime.progress import set_quiet

    set_quiet(True)
    Y = _data(case)
    t0 = time.perf_counter()
    m = learn_gpdm(Y, GPDMSettings())
    out = {"case": case, "shape": list(Y.shape), "time_s": time.perf_counter() - t0,
           "objective": m.objective_value, "iterations": m.learning.iterations,
           "evaluations": m.learning.evaluations, "decrement": m.learning.newton_decrement,
           "converged": m.learning.converged}
    if case == "jump157":
        out.update(_against_shipped(Y, m))
    return out


def _split(case: str) -> list[dict]:
    """One learning run timed level by level (coarse to fine): L and its gradient, the Hessian's
    assembly, its eigendecomposition and the rest, from timers put around the Newton method's calls
    in this (child) process."""
    import latentoc.gpdm.learning as learning
    from latentoc.gpdm import GPDMSettings
    from latentoc.runtime.progress import set_quiet

    set_quiet(True)
    levels: list[dict] = []
    newton, eigh = learning.minimize_newton, np.linalg.eigh

    def timer(fn, key):  # type: ignore[no-untyped-def]
        def call(*a, **k):  # type: ignore[no-untyped-def]
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                if levels:
                    levels[-1][key] += time.perf_counter() - t0
        return call

    def level(evaluate, hessian, z0, *a, **k):  # type: ignore[no-untyped-def]
        levels.append({"variables": int(np.size(z0)), "evaluate_s": 0.0, "hessian_s": 0.0, "eigh_s": 0.0})
        t0 = time.perf_counter()
        r = newton(timer(evaluate, "evaluate_s"), timer(hessian, "hessian_s"), z0, *a, **k)
        levels[-1].update(wall_s=time.perf_counter() - t0, iterations=r.steps, evaluations=r.evaluations)
        return r

    learning.minimize_newton, np.linalg.eigh = level, timer(eigh, "eigh_s")  # type: ignore[assignment]
    learning.learn_gpdm(_data(case), GPDMSettings())
    return sorted(levels, key=lambda lv: lv["variables"])


def _against_shipped(Y: np.ndarray, m) -> dict:  # type: ignore[no-untyped-def]
    """Eq. 16 and the latent points (after the best rotation) against the shipped model of the same data."""
    from latentoc.gpdm import GPDM
    from latentoc.gpdm.cache import SHIPPED, model_path

    path = SHIPPED / model_path(Y, m.settings).name
    if not path.exists():
        return {"shipped": None}
    ref = GPDM.load(path)
    U, _, Vt = np.linalg.svd(m.X.T @ ref.X)
    return {"shipped": path.name, "shipped_objective": ref.objective_value,
            "objective_rel_diff": abs(m.objective_value - ref.objective_value) / abs(ref.objective_value),
            "aligned_dX": float(np.max(np.abs(m.X @ (U @ Vt) - ref.X)))}


def _run(args: list[str]) -> tuple[float, int, str]:
    """Wall time (s), peak RSS (bytes) and stdout of a child process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env={**os.environ, "LATENTOC_QUIET": "1"})
    out = proc.stdout.read() if proc.stdout is not None else ""
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} failed with exit code {proc.returncode}")
    return wall, int(usage.ru_maxrss) * 1024, out


def learn_case(case: str) -> dict:
    """A case learned in a fresh Python process, with that process's peak memory."""
    wall, rss, out = _run([sys.executable, "-m", "latentoc.benchmarks.gpdm_bench", "--child", case])
    return {**json.loads(out.strip().splitlines()[-1]), "wall_s": wall, "peak_rss": rss}


def panda_cli() -> dict:
    """``python -m latentoc learn`` on the panda example at stride 1, timed as a user sees it."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "latentoc", "learn", str(PANDA), "--robot", "panda", "--hold", "panda_finger_joint1=0.02",
               "--hold", "panda_finger_joint2=0.02", "--out", str(Path(tmp) / "o")]  # the README's command
        if shutil.which("time") and Path("/usr/bin/time").exists():
            wall, rss, out = _run(["/usr/bin/time", "-v", *cmd])
        else:
            wall, rss, out = _run(cmd)
        learn = json.loads((Path(tmp) / "o" / "learn.json").read_text())
    r = learn["learning"]
    return {"case": "panda", "shape": [learn["learned_frames"], len(learn["demonstration"]["joints"])],
            "time_s": learn["learning_time_s"], "wall_s": wall, "peak_rss": rss,
            "objective": learn["objective_value"], "iterations": r["iterations"], "evaluations": r["evaluations"],
            "decrement": r["newton_decrement"], "converged": r["converged"]}


def _row(label: str, r: dict, limit_s: float | None, limit_gb: float | None, wall: bool = False,
         reference: float | None = None) -> str:
    """One case's line; with a ``reference`` Eq. 16 (:data:`MINIMA`) the target needs that minimum too, and
    the line shows L minus it."""
    t = r["wall_s"] if wall else r["time_s"]
    ok = r["converged"] and (limit_s is None or t <= limit_s) and (limit_gb is None or r["peak_rss"] <= limit_gb * 1e9)
    same = "-"
    if reference is not None:
        ok = ok and same_minimum(r["objective"], reference)
        same = f"{r['objective'] - reference:+.1e}"
    target = " and ".join(x for x in (f"<= {limit_s:g} s" if limit_s else "", f"<= {limit_gb:g} GB" if limit_gb else "")
                          if x)
    load = os.getloadavg()[0]
    return (f"{label:<34} {r['shape'][0]:>5} x {r['shape'][1]:<3} {t:8.2f} {r['peak_rss'] / 1e9:7.2f} "
            f"{r['iterations']:>5} {r['objective']:>17.9f} {same:>8} {str(r['converged']):>6}  {target or '-':<18} "
            f"{'met' if ok else 'MISSED':<6} {load:5.2f}")


def _print_split(case: str) -> None:
    _, _, out = _run([sys.executable, "-m", "latentoc.benchmarks.gpdm_bench", "--child", f"split:{case}"])
    levels = json.loads(out.strip().splitlines()[-1])
    print(f"{case}: {sum(lv['wall_s'] for lv in levels):.2f} s in all (load average {os.getloadavg()[0]:.2f})")
    for lv in levels:
        rest = lv["wall_s"] - lv["evaluate_s"] - lv["hessian_s"] - lv["eigh_s"]
        print(f"  {lv['variables']:5d} variables: {lv['wall_s']:.2f} s, {lv['iterations']} iterations; "
              f"{lv['evaluations']} evaluations {lv['evaluate_s']:.2f} s, Hessians {lv['hessian_s']:.2f} s, "
              f"eigendecompositions {lv['eigh_s']:.2f} s, the rest {rest:.2f} s", flush=True)


def main(argv: list[str] | None = None) -> int:
    """Print the issue's targets (or the N-scaling table), each from a fresh process, with the machine."""
    p = argparse.ArgumentParser(prog="gpdm_bench", description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--scaling", action="store_true", help="time and memory for N = 350, 1000, 2000 (D = 37)")
    p.add_argument("--quick", action="store_true", help="leave out N = 1000")
    p.add_argument("--split", nargs="?", const="all", default=None, choices=["all", *MOTIONS],
                   help="where each motion's (or one motion's) learning time goes, level by level")
    p.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.child is not None:
        out = _split(args.child[6:]) if args.child.startswith("split:") else _child(args.child)
        print(json.dumps(out), flush=True)
        return 0
    if args.split:
        print(f"learning time by level, coarse to fine (machine: {machine()})")
        for case in (MOTIONS if args.split == "all" else [args.split]):
            _print_split(case)
        return 0
    print("GPDM learning benchmark (d = 3, balanced, converged to the Newton decrement <= 1e-10 |L|, 1 BLAS thread)")
    print(f"machine: {machine()}")
    print(f"{'case':<34} {'N x D':>11} {'time s':>8} {'peak GB':>7} {'its':>5} {'Eq. 16':>17} {'- today':>8} {'conv.':>6}  "
          f"{'target':<18} {'result':<6} {'load':>5}")
    if args.scaling:
        for N in (350, 1000, 2000):
            print(_row(f"synthetic N = {N}", learn_case(f"{N}x37"), None, None), flush=True)
    else:
        for name in MOTIONS:
            print(_row(f"{name} (learning time)", learn_case(name), 3, None, reference=MINIMA[name]), flush=True)
        print(_row("panda example, CLI (wall, time -v)", panda_cli(), 2, None, wall=True), flush=True)
        jump = learn_case("jump157")
        print(_row("broad jump's training set", jump, 10, None), flush=True)
        if jump.get("shipped"):
            print(f"  the shipped model {jump['shipped']}: Eq. 16 {jump['shipped_objective']:.9f}, relative "
                  f"difference {jump['objective_rel_diff']:.1e}, latent points {jump['aligned_dX']:.1e} apart after "
                  "the best rotation")
        if not args.quick:
            print(_row("synthetic (learning time)", learn_case("1000x37"), 120, 2), flush=True)
    print(f"load average after: {', '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
