"""Command line: ``python -m latentoc {solve,list,sweep,start-poses,bench} ...``.

Input errors (bad problem, infeasible tube, ...) print ``latentoc: error: <message>``
and exit with code 2 without writing anything. A solve that Ipopt does not finish
successfully exits with code 1 and writes nothing unless ``--keep-failed``.
"""

from __future__ import annotations

import argparse
import sys
from importlib import import_module
from pathlib import Path

__all__ = ["main"]


def _input_errors() -> tuple[type[BaseException], ...]:
    from .gpdm import GPDMInputError
    from .problem import ProblemError
    from .solve import SolveError
    errors: list[type[BaseException]] = [ProblemError, SolveError, GPDMInputError, FileNotFoundError, ValueError]
    try:
        from .mocap import MocapFormatError  # type: ignore[attr-defined]
        errors.append(MocapFormatError)
    except ImportError:
        pass
    return tuple(errors)


def _tube_arg(text: str) -> float | str:
    from .problem import parse_tube
    value, relative = parse_tube(text)  # ValueError -> argparse message
    return text if relative else value


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="latentoc", description="Motion optimisation in a GPDM latent space "
                                                            "(Kang & Park 2015).")
    sub = p.add_subparsers(dest="command", required=True)

    s = sub.add_parser("solve", help="solve a problem and write result.json + trajectory.npz")
    s.add_argument("problem", help="problem name (see `list`) or path to a .toml file")
    s.add_argument("--tube", type=str, default=None, help='delta: a number, or "<k>x" relative (default: the problem\'s)')
    s.add_argument("--latent-dim", type=int, default=None)
    s.add_argument("--control-points", type=int, default=None)
    s.add_argument("--hessian", choices=["exact", "lbfgs"], default=None)
    s.add_argument("--method", choices=["latent", "joint-range"], default="latent")
    s.add_argument("--joint-range", type=float, default=None, help="baseline joint range, +-deg")
    s.add_argument("--out", type=Path, default=None, help="output folder (default: out/<problem>)")
    s.add_argument("--quiet", action="store_true", help="no progress display")
    s.add_argument("--verbose", action="store_true", help="Ipopt's own iteration log")
    s.add_argument("--keep-failed", action="store_true", help="write files even if Ipopt did not succeed")
    s.add_argument("--plots", action="store_true", help="also write PNG figures (and motion.gif) to OUT/plots")

    sub.add_parser("list", help="list the packaged problems")

    w = sub.add_parser("sweep", help="tube sweep (and joint-range baseline), a table like the paper's Table 2")
    w.add_argument("problem")
    w.add_argument("--tubes", nargs="*", default=None, help="tubes (numbers or <k>x); default: the problem's")
    w.add_argument("--baseline", choices=["joint-range"], default=None)
    w.add_argument("--ranges", nargs="*", type=float, default=None, help="joint ranges, deg")
    w.add_argument("--latent-dim", type=int, default=None)
    w.add_argument("--hessian", choices=["exact", "lbfgs"], default=None)
    w.add_argument("--out", type=Path, default=None)
    w.add_argument("--plots", action="store_true", help="also write OUT/gain_vs_tube.png")
    w.add_argument("--quiet", action="store_true", help="no progress display")

    sp = sub.add_parser("start-poses", help="end-effector distances of new start poses vs tube (Sect. 4.1.4)")
    sp.add_argument("problem")
    sp.add_argument("--tubes", nargs="*", default=None)
    sp.add_argument("--latent-dim", type=int, default=None)
    sp.add_argument("--out", type=Path, default=None)

    b = sub.add_parser("bench", help="run latentoc.benchmarks.<NAME>_bench")
    b.add_argument("name")
    b.add_argument("rest", nargs=argparse.REMAINDER)
    return p


def _cmd_list() -> int:
    from .problem import load_problem, problem_names
    for name in problem_names():
        print(f"{name:24s} {load_problem(name).description}")
    return 0


def _cmd_solve(args: argparse.Namespace) -> int:
    from .problem import load_problem
    from .results import write_solution
    from .solve import solve

    problem = load_problem(args.problem)
    tube = _tube_arg(args.tube) if args.tube is not None else None
    sol = solve(problem, tube=tube, latent_dim=args.latent_dim, control_points=args.control_points,
                hessian=args.hessian, method=args.method, joint_range_deg=args.joint_range, verbose=args.verbose)
    r = sol.result
    print(f"{r['problem']} ({r['method']}): {r['status']} after {r['iterations']} iterations")
    print(f"  cost {r['cost_initial']:.3f} -> {r['cost']:.3f}  (gain {r['performance_gain_pct']:.2f} %)")
    if r.get("tube") is not None:
        print(f"  tube delta {r['tube']:.4g} ({r['tube_spec']}; {r['tube_relative']:.3g} x noise), "
              f"max violation on 1 kHz grid {r['max_tube_violation']:.3g}")
    if r.get("joint_range_deg") is not None:
        print(f"  joint range +-{r['joint_range_deg']:g} deg")
    if r.get("max_dynamics_residual") is not None:  # contact problems: the exported motion's 1 kHz checks
        print(f"  1 kHz checks: base residual {r['max_dynamics_residual']:.2g} body weights, min normal force "
              f"{r['min_normal_force']:.1f} N, friction ratio {r['max_friction_ratio']:.3f} (mu {r['friction']:g}), "
              f"centre-of-pressure margin {r.get('cop_margin_loaded', r['cop_margin']):.3f} m, "
              f"ZMP margin {r['zmp_margin']:.3f} m, COM margin {r['com_margin']:.3f} m, "
              f"torque-limit excess {r['max_torque_violation']:.2g} N m")
        if r.get("toe_slip") is not None:
            print(f"  toe tip: forward travel {r['toe_displacement']:.3f} m; in contact slip {100 * r['toe_slip']:.2f} cm, "
                  f"height up to {100 * r['max_toe_height']:.2f} cm")
        if r.get("eq33_feet_distance") is not None:
            print(f"  Eq. 33 feet distance (both toe tips) {r['eq33_feet_distance']:.3f} m")
    print(f"  times: gpdm {r['gpdm_time_s']:.2f} s, build {r['build_time_s']:.2f} s, solve {r['solve_time_s']:.2f} s;"
          f" quadrature error {r['quadrature_error']:.2e}")
    if not sol.success and not args.keep_failed:
        print("latentoc: solve did not succeed; nothing written (use --keep-failed to write anyway)", file=sys.stderr)
        return 1
    out = args.out if args.out is not None else Path("out") / f"{r['problem']}-{r['method']}"
    paths = write_solution(sol, out)
    print("  wrote " + ", ".join(str(p) for p in paths))
    if args.plots:
        from .plots import plot_solution

        figures = plot_solution(out, gif=True)
        print(f"  plots: {len(figures)} figures in {out / 'plots'}")
    return 0 if sol.success else 1


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .problem import load_problem, parse_tube
    from .sweep import format_table, sweep, write_sweep

    problem = load_problem(args.problem)
    tubes = problem.sweep_tubes if args.tubes is None else [_tube_arg(t) for t in args.tubes]
    for t in tubes:
        parse_tube(t)
    ranges = None
    if args.baseline == "joint-range":
        ranges = problem.sweep_ranges if args.ranges is None else args.ranges
        if any(k <= 0 for k in ranges):
            raise ValueError("joint ranges must be positive degrees")
    rows = sweep(problem, tubes, ranges, latent_dim=args.latent_dim, hessian=args.hessian)
    print(format_table(rows))
    if args.out is not None:
        meta = {"problem": problem.name, "tubes": tubes, "ranges": ranges, "latent_dim": args.latent_dim}
        paths = write_sweep(rows, args.out, meta)
        print("wrote " + ", ".join(str(p) for p in paths))
    if args.plots:
        from .plots import plot_gain_vs_tube

        out = args.out if args.out is not None else Path("out") / f"{problem.name}-sweep"
        print("wrote " + str(plot_gain_vs_tube(rows, out / "gain_vs_tube.png", title=f"{problem.name}: gain vs tube")))
    return 0


def _cmd_start_poses(args: argparse.Namespace) -> int:
    from .problem import load_problem
    from .results import write_json
    from .robots import load_robot
    from .solve import problem_gpdm, resolve_tube
    from .start_poses import start_pose_distances

    problem = load_problem(args.problem)
    gp, _ = problem_gpdm(problem, args.latent_dim)
    specs = problem.start_pose_tubes if args.tubes is None else [_tube_arg(t) for t in args.tubes]
    ref = gp.tube_size()
    deltas = [resolve_tube(s, ref) for s in specs]
    rows = start_pose_distances(gp, load_robot(problem.robot), problem.start_pose_frame, deltas)
    print(f"start poses of {problem.name} (relative tubes x tube_training = {ref:.4g}), frame {problem.start_pose_frame}")
    print("| tube | delta | latent dist | translational dist (m), Eq. 31 | pose dist, Eq. 32 |")
    print("|---|---|---|---|---|")
    for s, r in zip(specs, rows):
        print(f"| {s} | {r['tube']:.4g} | {r['latent_distance']:.4f} | {r['translational_distance']:.4f} "
              f"| {r['pose_distance']:.4f} |")
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        write_json(args.out / "start_poses.json", {"problem": problem.name, "tube_training": ref,
                                                    "specs": [str(s) for s in specs], "rows": rows})
        print(f"wrote {args.out / 'start_poses.json'}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    name = args.name.replace("-", "_")
    try:
        module = import_module(f"latentoc.benchmarks.{name}_bench")
    except ModuleNotFoundError:
        raise ValueError(f"unknown benchmark {args.name!r}") from None
    return int(module.main(args.rest) or 0)


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    from .progress import quiet, set_quiet

    was_quiet = quiet()
    set_quiet(was_quiet or getattr(args, "quiet", False))
    commands = {"list": lambda a: _cmd_list(), "solve": _cmd_solve, "sweep": _cmd_sweep,
                "start-poses": _cmd_start_poses, "bench": _cmd_bench}
    try:
        return commands[args.command](args)
    except _input_errors() as exc:
        print(f"latentoc: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("latentoc: interrupted", file=sys.stderr)
        return 130
    finally:
        set_quiet(was_quiet)
