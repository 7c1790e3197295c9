"""Arm benchmark: build and solve times per arm solve, latent vs joint-range.

Run: ``python -m latentoc bench arm [--problem arm-raise] [--tubes 1x 5x] [--ranges 20 60]``.
Targets (issue 5): solve <= 1 s once built, build < 5 s.
"""

from __future__ import annotations

import argparse

from latentoc.problem import load_problem
from latentoc.solve import problem_gpdm, solve


def main(argv: list[str] | None = None) -> int:
    """Print one line per solve: method, parameter, build s, solve s, iterations, gain."""
    p = argparse.ArgumentParser(prog="arm_bench", description=__doc__)
    p.add_argument("--problem", default="arm-raise")
    p.add_argument("--tubes", nargs="*", default=["1x", "5x", "50x"])
    p.add_argument("--ranges", nargs="*", type=float, default=[20.0, 60.0])
    p.add_argument("--hessian", choices=["exact", "lbfgs"], default=None)
    args = p.parse_args(argv)
    problem = load_problem(args.problem)
    gp, gpdm_time = problem_gpdm(problem)
    print(f"{problem.name}: GPDM learned in {gpdm_time:.2f} s ({gp.X.shape[0]} frames)")
    print(f"{'method':12s} {'param':>8s} {'build s':>8s} {'solve s':>8s} {'iter':>5s} {'gain %':>7s}  status")
    for tube in args.tubes:
        r = solve(problem, tube=tube, gpdm=gp, hessian=args.hessian).result
        print(f"{'latent':12s} {tube:>8s} {r['build_time_s']:8.2f} {r['solve_time_s']:8.2f} {r['iterations']:5d} "
              f"{r['performance_gain_pct']:7.2f}  {r['status']}")
    for k in args.ranges:
        r = solve(problem, method="joint-range", joint_range_deg=k, hessian=args.hessian).result
        print(f"{'joint-range':12s} {k:>8g} {r['build_time_s']:8.2f} {r['solve_time_s']:8.2f} {r['iterations']:5d} "
              f"{r['performance_gain_pct']:7.2f}  {r['status']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
