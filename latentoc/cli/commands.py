"""The commands of ``python -m latentoc`` (:mod:`latentoc.cli.parser` parses the command line and calls one).

Each ``cmd_<name>(args)`` takes the parsed arguments and returns the exit code; an input error is
a :class:`~latentoc.errors.LatentocError`, which the CLI prints (exit code 2). :func:`summary`
formats a solved result from its schema alone (:class:`~latentoc.results.Result`).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from latentoc.errors import LatentocError, SweepError
from latentoc.runtime.files import check_out_dir
from latentoc.runtime.interrupts import finish
from latentoc.results import Result

__all__ = ["summary", "tube_arg", "overrides", "cmd_plot", "cmd_view", "cmd_notebooks", "cmd_list",
           "cmd_show", "cmd_solve", "cmd_sweep", "cmd_start_poses", "cmd_reproduce", "cmd_bench", "cmd_retarget"]


def tube_arg(text: str) -> float | str:
    """A tube given on the command line: a number (delta) or "<k>x" (module :mod:`latentoc.latent.tube`)."""
    from latentoc.latent.tube import parse_tube

    value, relative = parse_tube(text)  # ProblemError (a ValueError) -> argparse message
    return text if relative else value


def overrides(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The problem settings given on the command line (those not None)."""
    values = {"tube": tube_arg(args.tube) if getattr(args, "tube", None) is not None else None,
              "latent_dim": getattr(args, "latent_dim", None), "control_points": getattr(args, "control_points", None),
              "hessian": getattr(args, "hessian", None)}
    return {k: values[k] for k in names if values[k] is not None}


def cmd_plot(args: argparse.Namespace) -> int:
    from latentoc.plots import plot_solution

    paths = plot_solution(args.result, gif=not args.no_gif, out_dir=args.out, format=args.format)
    print(f"wrote {len(paths)} figures to {paths[0].parent}: " + ", ".join(p.name for p in paths))
    return 0


def cmd_view(args: argparse.Namespace) -> int:
    from latentoc.viewer import write_html

    if not args.rate > 0:
        raise LatentocError(f"--rate must be positive, got {args.rate}")
    path = write_html(args.result, args.html, rate_hz=args.rate)  # a result folder, or a retargeted .npz
    print(f"wrote {path} (open it in a browser; no server needed)")
    return 0


def cmd_notebooks(args: argparse.Namespace) -> int:
    import time

    try:
        from latentoc.reproduce.notebooks import check, notebook_paths, run_notebook
        import nbclient  # noqa: F401  (the dev extra's, with nbmake)
    except ImportError:
        raise LatentocError("running the notebooks needs nbclient: pip install -e '.[dev]'") from None

    for path in notebook_paths(args.names):
        if args.stale and not check(path):
            continue
        t0 = time.perf_counter()
        meta = run_notebook(path)
        print(f"ran {path} in {time.perf_counter() - t0:.0f} s ({len(meta['inputs'])} inputs recorded)", flush=True)
        _warn_uncommitted(meta["inputs"])
    return 0


def _warn_uncommitted(inputs: dict[str, str]) -> None:
    from latentoc.reproduce.provenance import uncommitted

    dirty = uncommitted(inputs)
    if dirty:
        print(f"latentoc: warning: made from uncommitted changes to {', '.join(dirty)}: on a clean clone the "
              "outputs are stale until those are committed as they are", file=sys.stderr)


def cmd_list(args: argparse.Namespace) -> int:
    from latentoc.problem.declaration import describe_problem
    from latentoc.problem.toml_files import load_problem, problem_names
    if args.robots:
        from latentoc.robots import robot_names
        print("\n".join(robot_names()))
        return 0
    for name in problem_names():
        problem = load_problem(name)
        print(describe_problem(problem) + "\n" if args.verbose else f"{name:24s} {problem.description}")
    return 0


def cmd_show(args: argparse.Namespace) -> int:
    from latentoc.problem.declaration import describe_problem
    from latentoc.problem.toml_files import load_problem
    print(describe_problem(load_problem(args.problem)))
    return 0


def _mm(x: float) -> str:
    """A margin in mm to 0.01 mm (a margin that rounds to zero prints as 0.00, not -0.00)."""
    return f"{round(1e3 * x, 2) + 0.0:.2f}"


def summary(r: Result) -> str:
    """The lines ``solve`` prints about a :class:`~latentoc.results.Result`."""
    d = r.details
    lines = [f"{r.problem} ({r.method}): {r.status} after {r.iterations} iterations",
             f"  cost {r.cost_initial:.3f} -> {r.cost:.3f}  (gain {r.gain_pct:.2f} %)"]
    if r.tube is not None:
        lines.append(f"  tube delta {r.tube.delta:.4g} ({r.tube.spec}; {r.tube.relative:.3g} x noise), "
                     f"max violation on 1 kHz grid {r.violations['tube']:.3g}")
    if d.get("joint_range_deg") is not None:
        lines.append(f"  joint range +-{d['joint_range_deg']:g} deg")
    if d.get("max_dynamics_residual") is not None:  # contact problems: the exported motion's 1 kHz checks
        lines.append(f"  1 kHz checks: base residual {d['max_dynamics_residual']:.2g} body weights, min normal force "
                     f"{d['min_normal_force']:.1f} N, friction ratio {d['max_friction_ratio']:.3f} "
                     f"(mu {d['friction']:g}), centre-of-pressure margin {_mm(d.get('cop_margin_loaded', d['cop_margin']))}"
                     f" mm, ZMP margin {_mm(d['zmp_margin'])} mm, COM margin {_mm(d['com_margin'])} mm, "
                     f"torque-limit excess {d['max_torque_violation']:.2g} N m")
        if d.get("max_loaded_travel") is not None:
            lines.append(f"  contact: loaded points travel {_mm(d['max_loaded_travel'])} mm, height up to "
                         f"{_mm(d['max_loaded_height'])} mm, unloaded points down to {_mm(d['min_unloaded_height'])} mm; "
                         f"the ground's work {d['ground_work_positive']:.3g} J positive, {d['ground_work']:.3g} J net")
        if d.get("toe_displacement") is not None:
            lines.append(f"  toe tip: forward travel {d['toe_displacement']:.3f} m")
        if d.get("eq33_feet_distance") is not None:
            lines.append(f"  Eq. 33 feet distance (both toe tips) {d['eq33_feet_distance']:.3f} m")
    t = r.times
    checks = f", 1 kHz checks {t.check_s:.2f} s" if t.check_s else ""
    total = f"; in all {t.total_s:.2f} s" if t.total_s else ""
    lines.append(f"  times: gpdm {t.gpdm_s:.2f} s, compile {t.compile_s:.2f} s, build {t.build_s:.2f} s, solve {t.solve_s:.2f} s"
                 f"{checks}{total}; quadrature error {d.get('quadrature_error', 0.0):.2e}")
    return "\n".join(lines)


def cmd_solve(args: argparse.Namespace) -> int:
    from latentoc.api import solve
    from latentoc.problem.toml_files import load_problem

    problem = load_problem(args.problem, **overrides(args, "tube", "latent_dim", "control_points", "hessian"))
    out = check_out_dir(args.out if args.out is not None else Path("out") / f"{problem.name}-{args.method}")
    gpdm = None
    if args.gpdm is not None:
        from latentoc.cli.learn import load_gpdm_file
        gpdm = load_gpdm_file(args.gpdm)
    r = solve(problem, method=args.method, joint_range_deg=args.joint_range, verbose=args.verbose, gpdm=gpdm)
    print(summary(r))
    if not r.success and not args.keep_failed:
        print("latentoc: solve did not succeed; nothing written (use --keep-failed to write anyway)", file=sys.stderr)
        return 1
    if not args.plots:
        finish()  # the result is written whole, or (Ctrl-C before this line) not at all
    paths = r.save(out)
    print("  wrote " + ", ".join(str(p) for p in paths))
    if args.plots:
        from latentoc.plots import plot_solution

        figures = plot_solution(out, gif=True)
        print(f"  plots: {len(figures)} figures in {out / 'plots'}")
    return 0 if r.success else 1


def _executor(args: argparse.Namespace) -> Any:
    """A Dask client for --workers / --scheduler, else None (serial)."""
    if args.workers is None and args.scheduler is None:
        return None
    if args.workers is not None and args.scheduler is not None:
        raise SweepError("give --workers (a local cluster) or --scheduler (an existing one), not both")
    if args.workers is not None and args.workers < 1:
        raise SweepError(f"--workers must be a positive number of processes, got {args.workers}")
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise SweepError("--workers and --scheduler need Dask: pip install 'latentoc[distributed]'") from None
    if args.scheduler is not None:
        try:
            return Client(args.scheduler, timeout=10)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SweepError(f"no Dask scheduler at {args.scheduler}: {exc}") from None
    return Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None))


def cmd_sweep(args: argparse.Namespace) -> int:
    from latentoc.problem.toml_files import load_problem
    from latentoc.sweeps import format_table, sweep, write_sweep

    problem = load_problem(args.problem, **overrides(args, "latent_dim", "hessian"))
    if args.tubes == [] or args.ranges == []:
        raise SweepError(f"--{'tubes' if args.tubes == [] else 'ranges'} needs at least one value (leave it out "
                         "for the problem's own)")
    tubes = problem.sweep_tubes if args.tubes is None else [tube_arg(t) for t in args.tubes]
    ranges: list[float] = []
    if args.baseline == "joint-range":
        ranges = problem.sweep_ranges if args.ranges is None else args.ranges
    out = args.out
    check_out_dir(out if out is not None else Path("out") / f"{problem.name}-sweep")
    client = _executor(args)
    try:
        outcome = sweep(problem, tubes, client, baseline_ranges=ranges, out=out, resume=args.resume,
                        warm_start=not args.cold, progress=None if args.quiet else lambda line: print(line, flush=True))
    finally:
        if client is not None:
            cluster = getattr(client, "cluster", None)
            client.close()
            if cluster is not None and args.workers is not None:
                cluster.close()
    print(format_table(outcome.results))
    if out is not None:
        if not args.plots:
            finish()  # sweep.json is written whole, or (Ctrl-C before this line) not at all
        meta = {"problem": problem.name, "tubes": tubes, "ranges": ranges, "workers": args.workers,
                "scheduler": args.scheduler, "warm_start": client is None and not args.cold}
        print("wrote " + ", ".join(str(p) for p in write_sweep(outcome, out, meta)))
    if args.plots and outcome.results:
        from latentoc.plots import plot_gain_vs_tube, save

        folder = out if out is not None else Path("out") / f"{problem.name}-sweep"
        print("wrote " + str(save(plot_gain_vs_tube(outcome.results, title=f"{problem.name}: gain vs tube"),
                                  folder / "gain_vs_tube.png")))
    for f in outcome.failures:
        print(f"latentoc: task {f.label} failed: {f.error}: {f.message}", file=sys.stderr)
        if f.traceback and not f.input_error:
            print(f.traceback, file=sys.stderr)
    for r in outcome.unsuccessful:
        what = f"tube {r.tube.spec}" if r.tube is not None else f"joint range {r.details.get('joint_range_deg')}"
        print(f"latentoc: {what} did not succeed: {r.details.get('rejected') or r.status} (--resume solves it "
              "again)", file=sys.stderr)
    return 1 if outcome.failures or outcome.unsuccessful else 0


def cmd_start_poses(args: argparse.Namespace) -> int:
    from latentoc.problem.toml_files import load_problem
    from latentoc.runtime.files import write_json
    from latentoc.robots import load_robot
    from latentoc.latent.tube import tube_delta
    from latentoc.min_torque.start_poses import start_pose_distances

    problem = load_problem(args.problem, **overrides(args, "latent_dim"))
    if args.out is not None:
        check_out_dir(args.out)
    if problem.kind != "latent-min-torque":
        raise LatentocError(f"start-poses is for latent-min-torque problems (Sect. 4.1.4), {problem.name!r} is "
                            f"a {problem.kind} problem")
    from latentoc.min_torque.training import problem_gpdm

    gp, _ = problem_gpdm(problem)
    specs = problem.start_pose_tubes if args.tubes is None else [tube_arg(t) for t in args.tubes]
    ref = gp.tube_size()
    deltas = [tube_delta(s, gp) for s in specs]
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


def cmd_reproduce(args: argparse.Namespace) -> int:
    from latentoc.reproduce.paper import report, reproduce
    from latentoc.runtime.files import atomic_write

    if args.figures:
        from latentoc.reproduce.figures import make_figures

        written = make_figures()
        print("wrote " + ", ".join(str(p) for p in written))
        _warn_uncommitted(json.loads(written[-1].read_text())["inputs"])
        return 0

    if args.out.is_dir():
        raise LatentocError(f"--out {args.out} is a folder; reproduce writes a Markdown file")
    check_out_dir(args.out.parent, "--out's folder")
    text = report(reproduce(quick=args.quick, budgets=args.budgets))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(args.out, lambda f: f.write(text))
    print(f"wrote {args.out}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from latentoc.benchmarks import arm_bench, blocks_bench, dynamics_bench, gpdm_bench, jump_bench, sampling_bench

    benchmarks = {"arm": arm_bench.main, "blocks": blocks_bench.main, "dynamics": dynamics_bench.main,
                  "gpdm": gpdm_bench.main, "jump": jump_bench.main, "sampling": sampling_bench.main}
    name = args.name.replace("-", "_")
    if name not in benchmarks:
        raise LatentocError(f"unknown benchmark {args.name!r}; known: {', '.join(benchmarks)}")
    return int(benchmarks[name](args.rest) or 0)


def _source_motion(args: argparse.Namespace, model: Any) -> tuple[Any, Any]:
    """Times and full configurations of the source model from ``--motion`` (an AMC with its ASF, or an
    NPZ whose q is the model's configuration), cut to ``--start``/``--stop``."""
    import numpy as np

    from latentoc.mocap import motion_to_q, read_amc, read_asf
    from latentoc.motions.readers import MotionFileError, read_npz

    path = Path(args.motion)
    if not path.is_file():
        raise MotionFileError(f"--motion: {path} does not exist")
    if path.suffix.lower() == ".amc":
        if args.asf is None or not Path(args.asf).is_file():
            raise MotionFileError(f"--asf: an AMC motion needs its ASF skeleton (got {args.asf})")
        skeleton = read_asf(args.asf)
        Q = motion_to_q(model, skeleton, read_amc(path, skeleton, args.fps))
        t = np.arange(len(Q)) / args.fps
    else:
        raw = read_npz(path)
        if raw.names is not None or raw.values.shape[1] != model.nq:
            raise MotionFileError(f"--motion: {path}'s q must be the source model's configuration "
                                  f"({model.nq} columns, no joint_names), got {raw.values.shape[1]} columns")
        t, Q = raw.t, raw.values
    stop = len(Q) if args.stop is None else args.stop
    if not (0 <= (args.start or 0) < stop <= len(Q)) or stop - (args.start or 0) < 2:
        raise MotionFileError(f"--start/--stop: {args.start}:{args.stop} is not a window of two or more of the "
                              f"motion's {len(Q)} frames")
    sl = slice(args.start or 0, stop)
    return t[sl] - t[sl][0], Q[sl]


def cmd_retarget(args: argparse.Namespace) -> int:
    """Retarget ``--motion`` with the keypoint map MAP; write the target's motion as an NPZ
    (``t``, ``q``: the target's configurations, ``q_source``: the source's it followed, ``retarget``:
    the report as JSON)."""
    import numpy as np
    import pinocchio as pin

    from latentoc.runtime.files import atomic_write, dumps_json
    from latentoc.motions.retarget_map import load_retarget_map
    from latentoc.motions.retargeting import chain_scale, retarget
    from latentoc.robots.catalog import load_robot

    if Path(args.out).suffix != ".npz":
        raise LatentocError(f"--out: the retargeted motion is an .npz file, got {args.out}")
    check_out_dir(Path(args.out).parent or Path("."))
    spec = load_retarget_map(args.map)
    source, target = load_robot(spec.source), load_robot(spec.target)
    t, Q = _source_motion(args, source)
    chain = [k for n in spec.scale_chain for k in spec.keypoints if k.name == n]
    scale = spec.scale if spec.scale is not None else chain_scale(source, Q[0], target, pin.neutral(target), chain)
    r = retarget(source, Q, t, target, spec.keypoints, scale=scale, rise=spec.rise, speed=spec.speed)
    info = {"map": str(args.map), "motion": str(args.motion), "start": args.start, "stop": args.stop,
            "source": spec.source, "target": spec.target, **r.info()}
    atomic_write(Path(args.out), lambda f: np.savez(f, t=r.t, q=r.Q, q_source=Q,
                                                          retarget=np.array(dumps_json(info))), binary=True)
    print(f"{spec.source} -> {spec.target}: {len(r.t)} frames, scale {r.scale:.3f}")
    print(f"  {'keypoint':16s} {'RMS mm':>8s} {'max mm':>8s}  planted frames")
    for name, (rms, mx) in r.residual_mm.items():
        print(f"  {name:16s} {rms:8.1f} {mx:8.1f}  {int(r.planted[name].sum()) if name in r.planted else ''}")
    for name, (rms, mx) in r.residual_deg.items():
        print(f"  {name:16s} {rms:8.2f} {mx:8.2f}  (orientation, deg)")
    if r.too_fast:
        print("  faster than the URDF allows (x its limit): " + ", ".join(
            f"{j} {f:.2f}" for j, f in sorted(r.too_fast.items(), key=lambda x: -x[1])))
    if r.at_limit:
        print("  at a joint limit: " + ", ".join(f"{j} {100 * f:.0f} %" for j, f in sorted(r.at_limit.items(), key=lambda x: -x[1])))
    print(f"wrote {args.out}")
    return 0
