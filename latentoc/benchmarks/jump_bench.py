"""Broad-jump benchmark (issue 6): setup, NLP build and Ipopt solve times per solve.

Target: 20 s or less per solve (paper: 19 s in C++ on a 2014 quad-core i7); the build
(casadi Functions of the 62-DOF model, GPDM mean derivatives, the symbolic node Hessians, Ipopt
set-up, and once per machine the C compilation of the node rows, Jacobians and Hessians,
:mod:`latentoc.jump.lifted`) is reported separately, and the wall time per constraint Jacobian,
constraint, gradient and Hessian evaluation.  Run: ``python -m latentoc.benchmarks.jump_bench
[--tubes 0.005 0.01] [--warm] [--hessian exact|lbfgs] [--quick]``.

Measured (2 shared cores, compiled blocks on 2 threads, the packaged problem: fixed phase
durations, exact Hessian):

* ``--tubes 0.005``: build 8.7 s (the compiled blocks found from their rows, :func:`latentoc.jump.lifted.compile_node_rows`;
  94 s when a process builds the symbolic Jacobians and Hessians), then 88 s cold (phase 1 38
  iterations in 14 s, phase 2 128 in 74 s).  Per iteration: constraint Jacobian 102 ms, Hessian
  265 ms, the rest of Ipopt (KKT factorisations, with inertia corrections, and solves) about
  0.19 s.  Before Ipopt's OpenBLAS ran on one thread (:func:`latentoc.solver.load_ipopt`): 114 s
  (Jacobian 147 ms, Hessian 324 ms, 45 s of system time in phase 2).  The flight block's
  Jacobian alone takes about 50 ms (80 nodes, 425k instructions each), its Hessian 110 ms (1.15M).
  Warm (``sweep broad-jump``, each tube from the previous optimum): 36-53 s per solve, 63-102
  iterations.
* Without the right joints' torque rows (mirror copies of the left's; 8912 rows instead of 13706)
  and with the node rows computed about the base's translation (this version): cold solves at
  delta 0.005, 0.02, 0.08 of 104, 80 and 85 s (phase 1 37-38 iterations in 11-12 s, phase 2 186,
  141, 156); per iteration the Hessian 0.25 s, the Jacobian 0.10 s, the linear solves 0.12 s.
  The sweep (``sweep_starts = "warm+cold"``): warm solves 14-24 s (35-59 iterations) but 52 s at
  delta 0.01, cold ones 52-97 s.
* Another 2-core machine (AMD EPYC, 2026-12-02), the same version: the first ``solve broad-jump
  --tube 0.02`` on the machine 22 min (21 min of it building and compiling the blocks), then
  46 s (phase 1 36 iterations in 6.7 s, phase 2 141 in 39 s); ``sweep broad-jump`` 6 min 26 s,
  the same iterations and distances as above, cold solves 34-62 s, warm ones 7-22 s.
* Tried and not kept, phase 2 from the same phase-1 point at delta 0.005 (140 iterations, 82 s):
  ``mu_init`` 1e-3 to 1e-5 with small bound pushes, 140-143 iterations; MUMPS without scaling, or
  with scaling 8, 141 and 132 iterations in 80 s; SPRAL as the linear solver, 135 iterations in
  182 s (127 s in the linear solver); phase 1 with the wrench samples (one NLP), 79 + 123
  iterations in 137 s against 38 + 140 in 127 s; gcc ``-O2``/``-O3`` for the tube Hessian (timed
  beside another solve): 244/154 us per node against 144 with ``-O1``, and 6.5x/4.8x its compile time.
* Warm starts with the previous optimum's multipliers too (``warm_start_init_point``, mu_init
  1e-6 or 1e-3 monotone): 86 and 91 iterations from delta 0.005 to 0.01, against 99 from the
  point alone, so the point alone is used.
* Exact Hessian against L-BFGS (free time scale, delta 0.16, cold): phase 1 39 iterations and
  22 s against 433 iterations and 248 s (L-BFGS memory 20; of it 116 s in the back solves of the
  low-rank update, 56 s in the Jacobian); phase 2 177 iterations and 179 s against 188 (memory 6).
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
    ap.add_argument("--warm", action="store_true",
                    help="start each tube from the previous tube's optimum, as `sweep` does (tubes ascending)")
    ap.add_argument("--hessian", choices=["exact", "lbfgs"], default=None, help="default: the problem file's")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    js = setup()
    print(f"setup (model, symmetric training, GPDM d=3, phases, torque limits): {time.perf_counter() - t0:.2f} s")
    prev = None
    for tube in args.tubes:
        if args.quick:
            s = JumpSettings(tube=tube, n_stance=6, n_flight=6, n_land=8, torque_limits=False, polygon=False,
                             contact_model="free", base_model="pinned", max_iter=args.max_iter,
                             two_phase=not args.one_phase)
        else:  # the packaged problem's settings (problems/broad-jump.toml), as `solve broad-jump`
            s = settings_from_problem(load_problem("broad-jump"), tube, args.hessian)
            s.max_iter, s.two_phase = args.max_iter, not args.one_phase
        c0 = time.process_time()
        out = solve_broad_jump(js, s, x0=prev if args.warm else None)
        r, st = out["result"], out["nlp"].solver.stats()
        prev = out["w"] if r["success"] else prev
        p1 = r.get("phase1") or {}
        ph1 = (f"phase 1 {p1['iterations']} it {p1['time_s']:.1f} s {p1['status']} viol {p1['max_constraint_violation']:.1e}; "
               if p1 else "")
        print(f"tube {tube:g}: build {r['build_time_s']:.2f} s, solve {r['solve_time_s']:.2f} s wall "
              f"({time.process_time() - c0:.1f} s CPU incl. build), {ph1}phase 2 {r['iterations']} it, {r['status']}, "
              f"distance {r['distance']:.3f} m (training {r['distance_initial']:.3f} m)", flush=True)
        print(f"  {s.hessian} Hessian{', warm start' if r['warm_start'] else ''}")
        for fn in ("nlp_jac_g", "nlp_g", "nlp_grad_f", "nlp_hess_l"):
            n = max(int(st.get(f"n_call_{fn}", 0)), 1)
            print(f"  {fn}: {1e3 * st.get(f't_wall_{fn}', 0.0) / n:.1f} ms x {n} calls (phase 2, wall)")
        evals = sum(float(st.get(f"t_wall_{fn}", 0.0)) for fn in ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g",
                                                                  "nlp_hess_l"))
        print(f"  phase 2: {r['phase2_time_s']:.1f} s wall, of it {evals:.1f} s in function evaluations and "
              f"{r['phase2_time_s'] - evals:.1f} s in Ipopt itself (the KKT solves)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
