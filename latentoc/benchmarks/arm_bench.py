"""Arm benchmark: build and solve times per arm solve, latent vs joint-range.

Run: ``python -m latentoc bench arm [--problem arm-raise] [--tubes 1x 5x] [--ranges 20 60]``.
Targets (issue 5): solve <= 1 s once built, build < 5 s.
"""

from __future__ import annotations

import argparse
import time

from latentoc.problem import load_problem
from latentoc.solve import problem_gpdm, solve


def main(argv: list[str] | None = None) -> int:
    """Print one line per solve: method, parameter, build s, solve s (wall), CPU s of the
    whole call (process time: build, solve and the 1 kHz evaluation), iterations, gain."""
    p = argparse.ArgumentParser(prog="arm_bench", description=__doc__)
    p.add_argument("--problem", default="arm-raise")
    p.add_argument("--tubes", nargs="*", default=["1x", "5x", "50x"])
    p.add_argument("--ranges", nargs="*", type=float, default=[20.0, 60.0])
    p.add_argument("--hessian", choices=["exact", "lbfgs"], default=None)
    args = p.parse_args(argv)
    problem = load_problem(args.problem)
    gp, gpdm_time = problem_gpdm(problem)
    print(f"{problem.name}: GPDM learned in {gpdm_time:.2f} s ({gp.X.shape[0]} frames)")
    print(f"{'method':12s} {'param':>8s} {'build s':>8s} {'solve s':>8s} {'cpu s':>6s} {'iter':>5s} "
          f"{'gain %':>7s} {'viol rel':>8s}  status")
    for tube in args.tubes:
        c0 = time.process_time()
        r = solve(problem, tube=tube, gpdm=gp, hessian=args.hessian).result
        cpu = time.process_time() - c0
        print(f"{'latent':12s} {tube:>8s} {r['build_time_s']:8.2f} {r['solve_time_s']:8.2f} {cpu:6.2f} "
              f"{r['iterations']:5d} {r['performance_gain_pct']:7.2f} {r['max_tube_violation_rel']:8.1e}  {r['status']}")
    for k in args.ranges:
        c0 = time.process_time()
        r = solve(problem, method="joint-range", joint_range_deg=k, hessian=args.hessian).result
        cpu = time.process_time() - c0
        print(f"{'joint-range':12s} {k:>8g} {r['build_time_s']:8.2f} {r['solve_time_s']:8.2f} {cpu:6.2f} "
              f"{r['iterations']:5d} {r['performance_gain_pct']:7.2f} {'-':>8s}  {r['status']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
