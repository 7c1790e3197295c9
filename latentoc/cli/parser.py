"""Command line: ``python -m latentoc {list,show,learn,solve,plot,view,sweep,start-poses,reproduce,bench,simulate} ...``.

Input errors (:class:`latentoc.LatentocError`: bad problem, infeasible tube, an ``--out`` that
cannot be written, ...) print ``latentoc: error: <message>`` and exit with code 2 without
writing anything; any other exception is a bug and ends with its traceback (exit code 1). A
solve that Ipopt does not finish successfully exits with code 1 and writes nothing unless
``--keep-failed``; a sweep with failed or unsuccessful tasks writes the others and exits with
code 1. Ctrl-C prints ``latentoc: interrupted`` and exits with code 130, writing no result of the
interrupted solve; a closed stdout (``latentoc list | head``) ends quietly with code 141.
This module parses the command line; each command is :mod:`latentoc.cli.commands`' ``cmd_<name>``
(``simulate``: :func:`latentoc.simulate.command.cmd_simulate`), imported when it runs, so that
``--help`` and an arm solve load only what they use.
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import sys
from pathlib import Path
from typing import Any, Callable

from latentoc.errors import LatentocError
from latentoc.runtime.interrupts import CommandLine

__all__ = ["main"]


def _held_joint(text: str) -> tuple[str, float | None]:
    """``--hold JOINT[=VALUE]``: the joint's name and its value (None: the model's neutral)."""
    name, sep, value = text.partition("=")
    if not name.strip():
        raise argparse.ArgumentTypeError(f"{text!r}: give a joint name, JOINT or JOINT=VALUE")
    if not sep:
        return name.strip(), None
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: VALUE {value!r} is not a number") from None
    if not math.isfinite(number):
        raise argparse.ArgumentTypeError(f"{text!r}: VALUE must be finite")
    return name.strip(), number


def _positive(text: str) -> float:
    """An argparse type: a positive, finite number (rates, gains, ranges, budgets)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not a number") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"{text[:40]!r}: must be a positive, finite number")
    return value


def _solve_arguments(sub: Any) -> None:
    """The ``solve`` command's arguments."""
    s = sub.add_parser("solve", help="solve a problem and write result.json, trajectory.npz, gpdm.npz")
    s.add_argument("problem", help="problem name (see `list`) or path to a .toml file")
    s.add_argument("--tube", type=str, default=None, help='"<k>x": k times the training motion\'s own tube (Eq. 30); a bare number: the absolute bound delta on '
                        'sigma^2 (Eq. 29), printed with its multiple of the noise in the summary (default: the problem\'s)')
    s.add_argument("--latent-dim", type=int, default=None, help="the GPDM's latent dimension d (default: the problem's)")
    s.add_argument("--control-points", type=int, default=None,
                   help="the latent B-spline's control points m (default: the problem's)")
    s.add_argument("--hessian", choices=["exact", "lbfgs"], default=None,
                   help="Ipopt's Hessian: exact (CasADi) or its L-BFGS approximation (default: the problem's)")
    s.add_argument("--method", default="latent",
                   help="a method of the problem's kind: latent (default) or joint-range (latentoc.problem.kinds)")
    s.add_argument("--joint-range", type=float, default=None, help="baseline joint range, +-deg")
    s.add_argument("--out", type=Path, default=None, help="output folder (default: out/<problem>-<method>)")
    s.add_argument("--quiet", action="store_true", help="no progress display")
    s.add_argument("--verbose", action="store_true", help="Ipopt's own iteration log")
    s.add_argument("--keep-failed", action="store_true", help="write files even if Ipopt did not succeed")
    s.add_argument("--plots", action="store_true", help="also write PNG figures (and motion.gif) to OUT/plots")
    s.add_argument("--gpdm", type=Path, default=None,
                   help="a GPDM written by `learn` (its gpdm.npz) instead of learning the problem's")


def _learn_arguments(sub: Any) -> None:
    """The ``learn`` command's arguments."""
    ln = sub.add_parser("learn", help="learn a GPDM from a motion file: gpdm.npz, learn.json (and figures)")
    ln.add_argument("file", type=Path, help="the motion: .csv (t and joint columns), .npz (t, q, joint_names) or .amc")
    ln.add_argument("--robot", required=True, help="a robot name (latentoc.robots) or the path of a URDF file")
    ln.add_argument("--latent-dim", type=int, default=3, help="latent dimension d (default 3)")
    ln.add_argument("--out", type=Path, required=True, help="output folder")
    ln.add_argument("--plots", action="store_true", help="also write latent_tube.png, reconstruction.png, variance.png")
    ln.add_argument("--stride", type=int, default=1, help="learn on every k-th frame (the last one always kept)")
    ln.add_argument("--clip", action="store_true", help="clip a motion that leaves the joint limits to them")
    ln.add_argument("--rate", type=_positive, default=None, help="resample to this rate, Hz (default: the file's median)")
    ln.add_argument("--asf", type=Path, default=None, help="the ASF skeleton of an .amc motion")
    ln.add_argument("--start", type=int, default=None, help="first frame (0-based)")
    ln.add_argument("--stop", type=int, default=None, help="one past the last frame")
    ln.add_argument("--fps", type=_positive, default=120.0, help="frame rate of an .amc motion (default 120)")
    ln.add_argument("--hold", action="append", default=[], metavar="JOINT[=VALUE]", type=_held_joint,
                    help="a joint the file does not move, held at VALUE (rad or m) or at the model's neutral "
                         "(repeat for each; every joint without a column must be named)")


def _plot_arguments(sub: Any) -> None:
    """The ``plot`` command's arguments."""
    pl = sub.add_parser("plot", help="every figure of a result folder, from its files alone")
    pl.add_argument("result", type=Path, help="a result folder (result.json, trajectory.npz, gpdm.npz)")
    pl.add_argument("--format", choices=["png", "pdf", "svg"], default="png", help="the figures' file format (default png)")
    pl.add_argument("--out", type=Path, default=None, help="output folder (default: RESULT/plots)")
    pl.add_argument("--no-gif", action="store_true", help="no motion.gif")


def _view_arguments(sub: Any) -> None:
    """The ``view`` command's arguments."""
    vw = sub.add_parser("view", help="the 3-D view of a result: one self-contained HTML page with the animation")
    vw.add_argument("result", type=Path, help="a result folder (result.json, trajectory.npz), or a retargeted "
                                              "motion (`retarget`'s .npz: the robot beside the source)")
    vw.add_argument("--html", type=Path, default=None,
                    help="the page to write (default: RESULT/view.html; for an .npz, its name with .html)")
    vw.add_argument("--rate", type=_positive, default=50.0, help="animation frames per second of motion time (default 50)")


def _notebooks_arguments(sub: Any) -> None:
    """The ``notebooks`` command's arguments."""
    nbk = sub.add_parser("notebooks", help="run the notebooks in place: their committed outputs, and what made them")
    nbk.add_argument("names", nargs="*", help="notebooks by name or number (default: all)")
    nbk.add_argument("--stale", action="store_true", help="only those whose code or inputs changed since their run")


def _list_arguments(sub: Any) -> None:
    """The ``list`` command's arguments (and ``show``'s)."""
    ls = sub.add_parser("list", help="list the packaged problems (or, with --robots, the robot names)")
    ls.add_argument("--verbose", action="store_true", help="every problem's resolved settings")
    ls.add_argument("--robots", action="store_true", help="the robot names a problem's `robot` or `learn --robot` takes")
    sh = sub.add_parser("show", help="a problem's resolved settings, one key per line")
    sh.add_argument("problem", help="a packaged problem's name (python -m latentoc list) or a .toml file")


def _sweep_arguments(sub: Any) -> None:
    """The ``sweep`` command's arguments."""
    w = sub.add_parser("sweep", help="tube sweep (and joint-range baseline), a table like the paper's Table 2")
    w.add_argument("problem", help="a packaged problem's name (python -m latentoc list) or a .toml file")
    w.add_argument("--tubes", nargs="*", default=None, help="tubes (numbers or <k>x); default: the problem's")
    w.add_argument("--baseline", choices=["joint-range"], default=None,
                   help="also solve the full configuration-space baseline at each of --ranges")
    w.add_argument("--ranges", nargs="*", type=_positive, default=None,
                   help="the baseline's joint ranges around the training motion, +-deg (default: the problem's)")
    w.add_argument("--latent-dim", type=int, default=None, help="the GPDM's latent dimension d (default: the problem's)")
    w.add_argument("--hessian", choices=["exact", "lbfgs"], default=None,
                   help="Ipopt's Hessian: exact (CasADi) or its L-BFGS approximation (default: the problem's)")
    w.add_argument("--out", type=Path, default=None, help="folder of the sweep: OUT/<task>/ per solve, sweep.json")
    w.add_argument("--workers", type=int, default=None, help="solve on a Dask LocalCluster of N worker processes")
    w.add_argument("--scheduler", default=None, help="solve on an existing Dask cluster, tcp://HOST:PORT")
    w.add_argument("--resume", action="store_true", help="skip the tasks whose folder in OUT is complete")
    w.add_argument("--cold", action="store_true", help="serial: start every tube from the training fit (as workers do)")
    w.add_argument("--plots", action="store_true", help="also write OUT/gain_vs_tube.png")
    w.add_argument("--quiet", action="store_true", help="no progress display")


def _start_poses_arguments(sub: Any) -> None:
    """The ``start-poses`` command's arguments."""
    sp = sub.add_parser("start-poses", help="end-effector distances of new start poses vs tube (Sect. 4.1.4)")
    sp.add_argument("problem", help="a packaged problem's name (python -m latentoc list) or a .toml file")
    sp.add_argument("--tubes", nargs="*", default=None, help="tubes (numbers or <k>x); default: the problem's")
    sp.add_argument("--latent-dim", type=int, default=None, help="the GPDM's latent dimension d (default: the problem's)")
    sp.add_argument("--out", type=Path, default=None, help="output folder")


def _reproduce_arguments(sub: Any) -> None:
    """The ``reproduce`` command's arguments."""
    r = sub.add_parser("reproduce", help="the paper's Tables 2, 3, 4, 6 and Fig. 5, ours beside the paper's")
    r.add_argument("--quick", action="store_true", help="the arm's tables and Fig. 5 only (no OMPL, no jump)")
    r.add_argument("--figures", action="store_true",
                   help="instead of the tables: the README's figures in docs/images (latentoc/reproduce/figures.py)")
    r.add_argument("--budgets", nargs="*", type=_positive, default=[10.0, 60.0, 300.0],
                   help="the sampling baseline's cumulative wall budgets, s")
    r.add_argument("--out", type=Path, default=Path("docs") / "reproduction.md",
                   help="the Markdown file of the tables (default docs/reproduction.md)")
    r.add_argument("--quiet", action="store_true", help="no progress display")


def _bench_arguments(sub: Any) -> None:
    """The ``bench`` command's arguments."""
    b = sub.add_parser("bench", help="run latentoc.benchmarks.<NAME>_bench")
    b.add_argument("name", help="dynamics, gpdm, blocks, arm, jump or sampling")
    b.add_argument("rest", nargs=argparse.REMAINDER, help="the benchmark's own arguments (bench NAME --help)")


def _simulate_arguments(sub: Any) -> None:
    """The ``simulate`` command's arguments."""
    sm = sub.add_parser("simulate", help="replay a result's torques in MuJoCo: simulation.json, simulation.npz")
    sm.add_argument("result", type=Path, help="a result folder with foot contacts (result.json, trajectory.npz)")
    sm.add_argument("--kp", type=float, default=None,
                    help="joint stiffness tracking the plan, N m/rad, every joint (default: latentoc.simulate's "
                         "DEFAULT_KP)")
    sm.add_argument("--kd", type=float, default=None,
                    help="joint damping, N m s/rad, every joint (default: critical, 2 sqrt(kp I) per joint)")
    sm.add_argument("--out", type=Path, default=None, help="output folder (default: RESULT)")
    sm.add_argument("--sweep-gains", type=float, nargs="+", default=None, metavar="KP",
                    help="also replay at each of these kp and report which stay upright")
    sm.add_argument("--quiet", action="store_true", help="no progress display")


def _retarget_arguments(sub: Any) -> None:
    """The ``retarget`` command's arguments."""
    rt = sub.add_parser("retarget", help="a motion of one model followed by another robot (keypoint IK): an .npz")
    rt.add_argument("map", type=Path, help="the keypoint map, a TOML file (e.g. robots/g1/cmu-retarget.toml)")
    rt.add_argument("--motion", type=Path, required=True,
                    help="the source motion: .amc (with --asf) or .npz (t, q: the source model's configurations)")
    rt.add_argument("--asf", type=Path, default=None, help="the ASF skeleton of an .amc motion")
    rt.add_argument("--fps", type=_positive, default=120.0, help="frame rate of an .amc motion (default 120)")
    rt.add_argument("--start", type=int, default=None, help="first frame (0-based)")
    rt.add_argument("--stop", type=int, default=None, help="one past the last frame")
    rt.add_argument("--out", type=Path, required=True, help="the target's motion, an .npz (t, q, retarget)")


_ARGUMENTS = (_solve_arguments, _learn_arguments, _plot_arguments, _view_arguments, _notebooks_arguments,
              _list_arguments, _sweep_arguments, _start_poses_arguments, _reproduce_arguments, _bench_arguments,
              _simulate_arguments, _retarget_arguments)

#: command name -> its implementation, "module:function" (:mod:`latentoc.cli.commands`)
COMMANDS = {name: f"latentoc.cli.commands:cmd_{name.replace('-', '_')}"
            for name in ("plot", "view", "notebooks", "list", "show", "solve", "sweep", "reproduce",
                         "start-poses", "bench", "retarget")} | {"learn": "latentoc.cli.learn:cmd_learn",
                                                                 "simulate": "latentoc.simulate.command:cmd_simulate"}


def _command(args: argparse.Namespace) -> Callable[[argparse.Namespace], int]:
    """The implementation of ``args.command``, imported now (and the defaults its module holds)."""
    module, name = COMMANDS[args.command].split(":")
    imported = importlib.import_module(module)
    if args.command == "simulate" and args.kp is None:
        args.kp = imported.DEFAULT_KP
    return getattr(imported, name)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="latentoc", description="Motion optimisation in a GPDM latent space "
                                                            "(Kang & Park 2015).")
    sub = p.add_subparsers(dest="command", required=True)
    for add in _ARGUMENTS:
        add(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code."""
    from latentoc.runtime.progress import quiet, set_quiet

    session = CommandLine()
    was_quiet = quiet()
    try:
        session.start()
        args = _parser().parse_args(argv)
        set_quiet(was_quiet or getattr(args, "quiet", False))
        code = _command(args)(args)
        session.raise_swallowed()
        return code
    except BaseException as exc:
        if session.interrupted(exc):  # also an error that a SIGINT caused inside C code or an import
            print("latentoc: interrupted", file=sys.stderr)
            return 130
        if isinstance(exc, LatentocError):
            print(f"latentoc: error: {exc}", file=sys.stderr)
            return 2
        if isinstance(exc, BrokenPipeError):  # the reader of stdout has gone (| head): stop quietly, as Unix tools do
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())  # Python's flush at exit would fail again
            return 141
        raise
    finally:
        session.end()
        set_quiet(was_quiet)
