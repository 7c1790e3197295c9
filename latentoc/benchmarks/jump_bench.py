"""Broad-jump benchmark (issue 6): setup, NLP build and Ipopt solve times per solve.

Target: 20 s or less per solve (paper: 19 s in C++ on a 2014 quad-core i7); the build
(casadi Functions of the 62-DOF model, GPDM mean derivatives, Ipopt set-up, and once per
machine the C compilation of the node Jacobians, :mod:`latentoc.jump.lifted`) is reported
separately, and the time per constraint Jacobian, constraint and gradient evaluation.  Run: ``python -m latentoc.benchmarks.jump_bench [--tubes 1.0 0.4] [--quick]``.

Measured (issue 6, delta 0.16, cold, 2 shared cores, Ipopt's ``print_timing_statistics``, an
L-BFGS memory of 20 pairs): of phase 1's 248 s, 116 s went to the back solves of the KKT system
(the limited-memory Hessian's low-rank update costs extra solves, more with more pairs), 56 s
to the constraint Jacobian and 13 s to the constraints.  That memory took 433 + 485 iterations
against 464 + 188 with Ipopt's default of 6, so the default stays.
"""
from __future__ import annotations

import argparse
import sys
import time


def main(argv: list[str] | None = None) -> int:
    """Print setup, build and solve time for each tube; returns 0."""
    from latentoc.jump.problem import settings_from_problem, setup, solve_broad_jump
    from latentoc.jump.transcription import JumpSettings
    from latentoc.problem import load_problem

    ap = argparse.ArgumentParser(prog="jump_bench", description=__doc__.splitlines()[0])
    ap.add_argument("--tubes", type=float, nargs="+", default=[1.0])
    ap.add_argument("--quick", action="store_true", help="small node count (6/6/8), no torque/polygon limits, no contact schedule")
    ap.add_argument("--max-iter", type=int, default=1500)
    ap.add_argument("--one-phase", action="store_true", help="skip the phase-1 feasibility solve")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    js = setup()
    print(f"setup (model, symmetric training, GPDM d=3, phases, torque limits): {time.perf_counter() - t0:.2f} s")
    for tube in args.tubes:
        if args.quick:
            s = JumpSettings(tube=tube, n_stance=6, n_flight=6, n_land=8, torque_limits=False, polygon=False,
                             contact_model="free", base_model="pinned", max_iter=args.max_iter,
                             two_phase=not args.one_phase)
        else:  # the packaged problem's settings (problems/broad-jump.toml), as `solve broad-jump`
            s = settings_from_problem(load_problem("broad-jump"), tube, None)
            s.max_iter, s.two_phase = args.max_iter, not args.one_phase
        c0 = time.process_time()
        out = solve_broad_jump(js, s)
        r, st = out["result"], out["nlp"].solver.stats()
        p1 = r.get("phase1") or {}
        ph1 = (f"phase 1 {p1['iterations']} it {p1['time_s']:.1f} s {p1['status']} viol {p1['max_constraint_violation']:.1e}; "
               if p1 else "")
        print(f"tube {tube:g}: build {r['build_time_s']:.2f} s, solve {r['solve_time_s']:.2f} s wall "
              f"({time.process_time() - c0:.1f} s CPU incl. build), {ph1}phase 2 {r['iterations']} it, {r['status']}, "
              f"distance {r['distance']:.3f} m (training {r['distance_initial']:.3f} m)", flush=True)
        for fn in ("nlp_jac_g", "nlp_g", "nlp_grad_f"):
            n = max(int(st.get(f"n_call_{fn}", 0)), 1)
            print(f"  {fn}: {1e3 * st.get(f't_proc_{fn}', 0.0) / n:.1f} ms x {n} calls (phase 2)")
        evals = sum(float(st.get(f"t_wall_{fn}", 0.0)) for fn in ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g"))
        print(f"  phase 2: {r['phase2_time_s']:.1f} s wall, of it {evals:.1f} s in function evaluations and "
              f"{r['phase2_time_s'] - evals:.1f} s in Ipopt itself (KKT solves of the limited-memory Hessian)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
