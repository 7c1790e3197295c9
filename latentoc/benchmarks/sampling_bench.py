"""Sampling-based baseline (paper Table 3): kinodynamic RRT* on OMPL next to the latent and
joint-range solves.

Run: ``python -m latentoc bench sampling [--problem arm-raise] [--budgets 10 60 300] [--seed 0]
[--iterations N ...] [--ranges 45 90] [--no-solves] [--json PATH]``. Needs ``pip install latentoc[sampling]``.

One RRT* tree (:mod:`latentoc.baselines.sampling`) grows through the budgets (cumulative wall
seconds, or ``--iterations``: cumulative RRT* iterations, reproducible for a seed in a fresh
process); at each one its best motion is re-checked on the 1 kHz grid with numeric Pinocchio.
Per checkpoint: the wall time in OMPL, iterations, states in the tree, whether the goal was
reached, J by the planner and re-checked, the performance gain against the initial cost of the
latent solve (the paper's "P. gain"), when the first and the current solution were found, the
joint-limit excess and the largest boundary error. Then the latent solve and the joint-range
solves: J, Ipopt's time and the whole solve's wall time (GPDM learning and building included).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time

from latentoc.baselines.sampling import SamplingSettings, plan, require_ompl
from latentoc.problem.toml_files import load_problem
from latentoc.runtime.progress import set_quiet

PAPER_TABLE3 = ((3830, 355.38, -0.96, 5436), (4265, 315.73, 10.30, 8310), (5390, 275.06, 21.86, 15529),
                (7660, 252.74, 28.20, 24371), (9135, 225.59, 35.91, 46532))  # iteration, cost, gain %, s


def _cpu() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            names = [line.split(":", 1)[1].strip() for line in f if line.startswith("model name")]
        return f"{names[0]} x {len(names)}" if names else platform.processor()
    except OSError:
        return platform.processor()


def _solves(problem, ranges: list[float]) -> list[dict]:
    from latentoc import solve
    rows = []
    for method, k in [("latent", None)] + [("joint-range", r) for r in ranges]:
        t0 = time.perf_counter()
        r = solve(problem, method=method, joint_range_deg=k)
        rows.append({"method": method, "param": str(problem.tube) if k is None else f"+-{k:g} deg",
                     "cost": r.cost, "cost_initial": r.cost_initial, "solve_s": r.times.solve_s,
                     "wall_s": time.perf_counter() - t0, "status": r.status})
    return rows


def main(argv: list[str] | None = None) -> int:
    """Print the RRT* checkpoints, then the latent and joint-range solves."""
    p = argparse.ArgumentParser(prog="sampling_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--problem", default="arm-raise")
    p.add_argument("--budgets", nargs="*", type=float, default=[10.0, 60.0, 300.0], help="cumulative wall s")
    p.add_argument("--iterations", nargs="*", type=int, default=None, help="cumulative iterations instead")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--ranges", nargs="*", type=float, default=None,
                   help="joint-range baselines, +-deg (default: the problem's and 90)")
    p.add_argument("--no-solves", action="store_true", help="only the sampling planner")
    p.add_argument("--json", default=None, help="also write the rows to this JSON file")
    args = p.parse_args(argv)
    require_ompl()  # before any work: a clear error naming the extra
    from importlib.metadata import version

    problem = load_problem(args.problem)
    settings = SamplingSettings(seed=args.seed)
    print(f"{args.problem}: kinodynamic RRT* (OMPL {version('ompl')} geometric RRTstar, "
          f"Hermite steering over (q, qdot, t)), seed {args.seed}; {_cpu()}, {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.2f}", flush=True)
    budgets = dict(iterations=args.iterations) if args.iterations else dict(seconds=args.budgets)
    results = plan(problem, settings=settings, **budgets)
    set_quiet(True)  # no progress bars between the table's lines
    solves = [] if args.no_solves else _solves(problem, args.ranges if args.ranges is not None else
                                               sorted({float(problem.joint_range_deg), 90.0}))
    J0 = solves[0]["cost_initial"] if solves else None
    print(f"{'budget':>8s} {'time s':>8s} {'iter':>7s} {'states':>7s} {'goal':>5s} {'J planner':>10s} "
          f"{'J 1 kHz':>10s} {'gain %':>7s} {'first s':>8s} {'best s':>8s} {'joint exc':>9s} {'bound err':>9s}")
    rows = []
    marks = args.iterations if args.iterations else args.budgets
    for mark, r in zip(sorted(marks), results):
        gain = 100 * (1 - r.cost / J0) if J0 and r.solved else float("nan")
        bound = max((v for k, v in r.checks.items() if k.endswith("_error")), default=float("nan"))
        print(f"{mark:8g} {r.time_s:8.1f} {r.iterations:7d} {r.vertices:7d} {'yes' if r.solved else 'no':>5s} "
              f"{r.cost_planner:10.3f} {r.cost:10.3f} {gain:7.2f} {r.first_solution_s:8.2f} {r.best_found_s:8.2f} "
              f"{r.checks.get('max_joint_violation', float('nan')):9.2g} {bound:9.2g}", flush=True)
        rows.append({"budget": mark, "time_s": r.time_s, "iterations": r.iterations, "states": r.vertices,
                     "solved": r.solved, "cost_planner": r.cost_planner, "cost": r.cost, "gain_pct": gain,
                     "first_solution_s": r.first_solution_s, "best_found_s": r.best_found_s, "knots": len(r.knots),
                     "seeded": r.seeded, **r.checks})
    if not results[-1].seeded:
        print("note: OMPL was seeded earlier in this process, so this run is not reproducible")
    if solves:
        print(f"{'method':12s} {'param':>10s} {'J':>10s} {'gain %':>7s} {'Ipopt s':>8s} {'wall s':>8s}  status")
        for s in solves:
            print(f"{s['method']:12s} {s['param']:>10s} {s['cost']:10.3f} {100 * (1 - s['cost'] / J0):7.2f} "
                  f"{s['solve_s']:8.2f} {s['wall_s']:8.2f}  {s['status']}")
    print("paper Table 3 (kinodynamic RRT*, initial cost 352): "
          + "; ".join(f"it {i}: {c:.2f} ({g:+.2f} %) {s} s" for i, c, g, s in PAPER_TABLE3))
    print(f"load average {os.getloadavg()[0]:.2f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"problem": args.problem, "seed": args.seed, "cpu": _cpu(), "sampling": rows,
                       "solves": solves}, f, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
