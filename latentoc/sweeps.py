"""Tube and joint-range sweeps (the paper's Tables 2, 4, 6), serial or on an executor (Dask).

A sweep is a list of :class:`SweepTask`: a latent solve per tube, then, for the arm, a
full-space baseline solve per joint range. Each task carries its problem as data
(:meth:`~latentoc.problem.declaration.Problem.to_dict`, :func:`~latentoc.problem.toml_files.problem_from_dict`) and :func:`run_task` returns the content of its result
files (:meth:`~latentoc.results.Result.files`), so a worker needs only the installed package.

* Serial (``executor=None``): the tasks run in this process, in order; with ``warm_start`` each
  tube starts from the result of the largest smaller tube solved before it (a smaller tube's
  optimum is feasible for a larger one).
* On an executor (a ``dask.distributed.Client`` or any ``concurrent.futures.Executor``): the
  tasks run at once and start cold, from the training fit: a warm start needs the previous
  tube's optimum, which makes a sweep serial. A failed task is reported with its tube and error
  (:class:`SweepFailure`); the others still finish and are written.

A warm-started tube's result is never worse than the optimum it started from, which is feasible
for the larger tube: when the warm solve fails or ends worse than its start, the tube is solved
cold (from the training fit) and the better kept (:func:`no_worse_than_start`; a kind that solved
both starts itself, the jump, is not solved again). If even that is worse than the start, the
result is marked not successful (``details["rejected"]``). The row says which start was kept.

With ``out``, each task's folder ``out/<label>/`` is written as its result arrives, and
``resume=True`` skips the tasks whose folder holds a successful result; a folder that does not
load or holds a failed solve is solved again. Ctrl-C stops the sweep at once (KeyboardInterrupt).
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from latentoc.api import solve
from latentoc.arguments import expect
from latentoc.errors import ArgumentError, LatentocError, SweepError
from latentoc.problem.kinds import kind_of
from latentoc.problem.declaration import Problem
from latentoc.problem.toml_files import problem_from_dict
from latentoc.errors import ResultFileError
from latentoc.results import RESULT_NAME, Result, load_result, write_files
from latentoc.runtime.files import atomic_write, write_json
from latentoc.latent.tube import parse_tube, resolve_tube

__all__ = ["SweepTask", "SweepFailure", "SweepResult", "sweep", "sweep_tasks", "run_task", "format_table",
           "write_sweep", "summary_row", "no_worse_than_start"]

#: a tube's cost may be worse than its warm start's by this fraction of the start's cost (rounding)
START_RTOL = 1e-6


@dataclass(frozen=True)
class SweepTask:
    """One solve of a sweep: the problem as data, and a tube (latent) or a joint range (baseline)."""

    problem: dict[str, Any]
    method: str = "latent"
    tube: float | str | None = None
    joint_range_deg: float | None = None

    @property
    def label(self) -> str:
        """The task's folder name: ``tube-5x``, ``tube-0.02``, ``joint-range-10``."""
        if self.method == "latent":
            return f"tube-{self.tube}"
        return f"joint-range-{self.joint_range_deg:g}"


@dataclass(frozen=True)
class SweepFailure:
    """A task that raised: its label, the error type, message and traceback."""

    label: str
    error: str
    message: str
    traceback: str = ""
    input_error: bool = False  # a LatentocError (bad input), not a bug


@dataclass
class SweepResult:
    """The results in task order (the failed tasks left out) and the failures."""

    results: list[Result] = field(default_factory=list)
    failures: list[SweepFailure] = field(default_factory=list)

    @property
    def unsuccessful(self) -> list[Result]:
        """The results whose solve did not succeed (a solver status, or worse than their start)."""
        return [r for r in self.results if not r.success]


def sweep_tasks(problem: Problem, tubes: Sequence[float | str],
                baseline_ranges: Sequence[float] = ()) -> list[SweepTask]:
    """The tasks of a sweep: a latent solve per tube, then a joint-range solve per range."""
    if not tubes and not baseline_ranges:
        raise SweepError("a sweep needs at least one tube or joint range, none were given")
    for t in tubes:
        parse_tube(t)
    if any(not k > 0 for k in baseline_ranges):
        raise SweepError(f"joint ranges must be positive degrees, got {list(baseline_ranges)}")
    data = problem.to_dict()
    return ([SweepTask(data, "latent", tube=t) for t in tubes]
            + [SweepTask(data, "joint-range", joint_range_deg=float(k)) for k in baseline_ranges])


def run_task(task: SweepTask) -> dict[str, bytes]:
    """Solve one task (in any process: the problem comes as data); its result files' content."""
    problem = problem_from_dict(task.problem)
    if task.method == "latent":
        problem = problem.replace(tube=task.tube)
    return solve(problem, method=task.method, joint_range_deg=task.joint_range_deg).files()


def _line(i: int, n: int, task: SweepTask, r: Result) -> str:
    what = f"tube {task.tube}: delta {r.tube.delta:.4g}" if r.tube is not None else \
        f"joint range +-{task.joint_range_deg:g} deg"
    return (f"[{i}/{n}] {what}, cost {r.cost:.2f}, gain {r.gain_pct:.2f}%, {r.times.solve_s:.2f} s, {r.status}")


def sweep(problem: Problem, tubes: Sequence[float | str] | None = None, executor: Executor | Any | None = None, *,
          baseline_ranges: Sequence[float] = (), out: str | Path | None = None, resume: bool = False,
          warm_start: bool = True, progress: Callable[[str], None] | None = print) -> SweepResult:
    """Solve ``problem`` at each tube (default: its ``sweep_tubes``) and each baseline joint range
    (module doc): serially, or on ``executor`` (a Dask Client or a concurrent.futures Executor)."""
    expect("sweep", "problem", problem, Problem, "a Problem (latentoc.load_problem(NAME or PATH))")
    if tubes is not None:
        expect("sweep", "tubes", tubes, (list, tuple), 'a list of tubes (["2x", "5x"] or numbers), not one tube')
    expect("sweep", "baseline_ranges", baseline_ranges, (list, tuple), "a list of joint ranges, degrees")
    if executor is not None and not (hasattr(executor, "submit") and callable(executor.submit)):
        raise ArgumentError(f"sweep(): argument 'executor' must be a dask.distributed Client, a "
                            f"concurrent.futures Executor or None, got {type(executor).__name__}")
    tasks = sweep_tasks(problem, problem.sweep_tubes if tubes is None else tubes, baseline_ranges)
    if resume and out is None:
        raise SweepError("resume needs the output folder the earlier run wrote")
    say = progress or (lambda line: None)
    done: dict[str, Result] = {}
    if resume and out is not None:
        for t in tasks:
            kept = _resumed(t, Path(out) / t.label, say)
            if kept is not None:
                done[t.label] = kept
    todo = [t for t in tasks if t.label not in done]
    if executor is None:
        outcome = _serial(problem, todo, out, warm_start, say, len(tasks), len(done))
    else:
        outcome = _distributed(executor, todo, out, say, len(tasks), len(done))
    by_label = {**done, **outcome}
    failures = [f for f in outcome.values() if isinstance(f, SweepFailure)]
    results = [r for t in tasks if isinstance(r := by_label.get(t.label), Result)]
    return SweepResult(results=results, failures=failures)


def _resumed(task: SweepTask, folder: Path, say: Callable[[str], None]) -> Result | None:
    """The result a resumed sweep keeps: a successful one, solved with this task's settings; None
    (solve it again) for no folder, one that does not load or a solve that did not succeed."""
    if not (folder / RESULT_NAME).is_file():
        return None
    try:
        r = load_result(folder)
    except ResultFileError as exc:
        say(f"{task.label}: solving again: {exc}")
        return None
    settings = dict(task.problem["settings"], **({"tube": task.tube} if task.method == "latent" else {}))
    differ = sorted(k for k in settings if r.settings.get(k) != settings[k])
    if differ or r.method != task.method:
        raise SweepError(f"{folder} was written for other settings ({', '.join(differ) or 'method'}); "
                         "resume in the folder of the same sweep, or write to another")
    if not r.success:
        say(f"{task.label}: solving again: the earlier solve ended {r.status}")
        return None
    return r


def _write(out: str | Path | None, label: str, files: dict[str, bytes]) -> None:
    if out is not None:
        write_files(files, Path(out) / label)


def _serial(problem: Problem, tasks: list[SweepTask], out: str | Path | None, warm_start: bool,
            say: Callable[[str], None], total: int, skipped: int) -> dict[str, Any]:
    outcome: dict[str, Any] = {}
    solved: list[tuple[float, Result]] = []  # (delta, result) of the successful latent solves
    for i, task in enumerate(tasks):
        try:
            p = problem
            previous = None
            if task.method == "latent":
                p = problem.replace(tube=task.tube)
                if warm_start and solved:
                    delta = resolve_tube(task.tube, lambda: kind_of(p.kind).tube_reference(p))  # type: ignore[arg-type]
                    smaller = [s for s in solved if s[0] <= delta]
                    previous = max(smaller, key=lambda s: s[0])[1] if smaller else None
            r = solve(p, method=task.method, joint_range_deg=task.joint_range_deg, warm_start=previous)
            if previous is not None:
                r = no_worse_than_start(r, previous, lambda: solve(p, method=task.method,
                                                                   joint_range_deg=task.joint_range_deg))
        except LatentocError as exc:
            outcome[task.label] = SweepFailure(task.label, type(exc).__name__, str(exc), input_error=True)
            say(f"[{skipped + i + 1}/{total}] {task.label}: failed: {exc}")
            continue
        if warm_start and r.success and r.warm and r.tube is not None:
            solved.append((r.tube.delta, r))
        _write(out, task.label, r.files())
        outcome[task.label] = r
        say(_line(skipped + i + 1, total, task, r))
        if "sweep_start" in r.details:
            say("  " + _start_note(r))
    return outcome


def _improvement(a: Result, b: Result) -> float:
    """How much better ``a`` is than ``b``, in cost units (both of one problem: one cost_initial;
    gain_pct grows with a better result, whether the cost is minimised or maximised)."""
    return (a.gain_pct - b.gain_pct) / 100.0 * abs(a.cost_initial)


def _worse(r: Result, start: Result) -> bool:
    return _improvement(start, r) > START_RTOL * max(abs(start.cost), 1e-12)


def no_worse_than_start(r: Result, start: Result, solve_cold: Callable[[], Result]) -> Result:
    """``r``, a tube's result warm-started from ``start`` (the optimum of a smaller tube, feasible
    here), or, if it failed or is worse than ``start``, the better of it and ``solve_cold()``;
    marked not successful if even that is worse than ``start`` (module doc)."""
    if not r.details.get("warm_start") or (r.success and not _worse(r, start)):
        return r
    warm = r
    if "other_start" not in r.details:  # the kind did not solve from both starts itself
        cold = solve_cold()
        r = cold if (cold.success, cold.gain_pct) > (warm.success, warm.gain_pct) else warm
        r.details["sweep_start"] = {
            "start": str(start.tube.spec if start.tube is not None else start.problem), "start_cost": start.cost,
            "warm_cost": warm.cost, "warm_status": warm.status, "warm_success": warm.success,
            "cold_cost": cold.cost, "cold_status": cold.status, "kept": "cold" if r is cold else "warm"}
    if r.success and _worse(r, start):
        r.success = False
        r.details["rejected"] = (f"cost {r.cost:.6g} is worse than {start.cost:.6g}, the optimum of the smaller "
                                 f"tube {start.tube.spec if start.tube is not None else '?'} it started from, "
                                 "which is feasible here")
    return r


def _start_note(r: Result) -> str:
    s = r.details["sweep_start"]
    why = f"worse than its start's {s['start_cost']:.6g}" if s.get("warm_success", True) else "not a success"
    return (f"the warm start from {s['start']} ended {s['warm_status']} at cost {s['warm_cost']:.6g}, {why}: "
            f"solved cold ({s['cold_status']}, cost {s['cold_cost']:.6g}), kept the {s['kept']} solve")


def _distributed(executor: Any, tasks: list[SweepTask], out: str | Path | None, say: Callable[[str], None],
                 total: int, skipped: int) -> dict[str, Any]:
    futures = {executor.submit(run_task, t): t for t in tasks}
    outcome: dict[str, Any] = {}
    for k, future in enumerate(_as_completed(executor, list(futures))):
        task = futures[future]
        exc = future.exception()
        if exc is not None:
            tb = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
            outcome[task.label] = SweepFailure(task.label, type(exc).__name__, str(exc), tb,
                                               isinstance(exc, LatentocError))
            say(f"[{skipped + k + 1}/{total}] {task.label}: failed: {type(exc).__name__}: {exc}")
            continue
        files = future.result()
        _write(out, task.label, files)
        r = Result.from_files(files, task.label)
        outcome[task.label] = r
        say(_line(skipped + k + 1, total, task, r))
    return outcome


def _as_completed(executor: Any, futures: list[Any]) -> Any:
    """Futures as they finish: Dask's own iterator for a Dask client, else concurrent.futures'."""
    if type(executor).__module__.startswith("distributed"):
        from distributed import as_completed
        return as_completed(futures)
    from concurrent.futures import as_completed as cf_as_completed
    return cf_as_completed(futures)


# ------------------------------------------------------------------ tables and files
def summary_row(r: Result) -> dict[str, Any]:
    """A result's line in sweep.json: the core fields and the tube or joint range."""
    return {"problem": r.problem, "method": r.method, "status": r.status, "success": r.success,
            "iterations": r.iterations, "cost_initial": r.cost_initial, "cost": r.cost, "gain_pct": r.gain_pct,
            "tube_spec": None if r.tube is None else r.tube.spec, "tube": None if r.tube is None else r.tube.delta,
            "tube_relative": None if r.tube is None else r.tube.relative,
            "joint_range_deg": r.details.get("joint_range_deg"), "solve_s": r.times.solve_s,
            "warm_start": r.details.get("warm_start", False), "start": _start(r),
            "rejected": r.details.get("rejected"), "violations": r.violations}


def _start(r: Result) -> str:
    """Where the kept solve started: "cold", "warm", or which of both (sweep_start)."""
    s = r.details.get("sweep_start")
    if s is not None:
        return f"{s['kept']} (warm and cold solved: the warm start ended worse than its start or failed)"
    return "warm" if r.details.get("warm_start") else "cold"


def format_table(results: Sequence[Result]) -> str:
    """Markdown table in the layout of Table 2: latent rows left, joint-range rows right."""
    lat = [r for r in results if r.method == "latent"]
    jr = [r for r in results if r.method == "joint-range"]
    head = ("| tube | delta | delta/noise | cost | gain % | time s | status "
            "| joint range | cost | gain % | time s | status |")
    lines = [head, "|" + "---|" * 12]
    for i in range(max(len(lat), len(jr))):
        left = [""] * 7
        right = [""] * 5
        tube = lat[i].tube if i < len(lat) else None
        if tube is not None:
            r = lat[i]
            left = [str(tube.spec), f"{tube.delta:.4g}", f"{tube.relative:.3g}", f"{r.cost:.2f}",
                    f"{r.gain_pct:.2f}", f"{r.times.solve_s:.2f}", _ok(r)]
        if i < len(jr):
            r = jr[i]
            right = [f"+-{r.details['joint_range_deg']:g} deg", f"{r.cost:.2f}", f"{r.gain_pct:.2f}",
                     f"{r.times.solve_s:.2f}", _ok(r)]
        lines.append("| " + " | ".join(left + right) + " |")
    if lat:
        lines.append(f"\nlatent: d = {lat[0].settings['latent_dim']}, initial cost {lat[0].cost_initial:.2f}")
    if jr:
        lines.append(f"joint range: initial cost {jr[0].cost_initial:.2f}")
    lines += [f"{r.tube.spec if r.tube is not None else r.problem}: {_start_note(r)}" for r in lat
              if "sweep_start" in r.details]
    lines += [f"{r.tube.spec if r.tube is not None else r.problem}: not successful: {r.details['rejected']}"
              for r in lat if r.details.get("rejected")]
    return "\n".join(lines)


def _ok(r: Result) -> str:
    if r.details.get("rejected"):
        return "worse than its start"
    status = "ok" if r.success else r.status
    return status + (f", {r.details['sweep_start']['kept']} kept" if "sweep_start" in r.details else "")


def write_sweep(outcome: SweepResult, out_dir: str | Path, meta: dict[str, Any] | None = None) -> tuple[Path, Path]:
    """Atomically write ``sweep.json`` (meta, a summary row per result, the failures) and
    ``sweep.md`` (the table) beside the tasks' folders."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "sweep.json", {"meta": meta or {}, "rows": [summary_row(r) for r in outcome.results],
                                    "failures": [vars(f) for f in outcome.failures]})
    atomic_write(out / "sweep.md", lambda f: f.write(format_table(outcome.results) + "\n"))
    return out / "sweep.json", out / "sweep.md"
