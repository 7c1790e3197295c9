"""Tube and joint-range sweeps: the paper's Table 2 (and Table 4 with d = 2).

:func:`sweep` solves the problem for each tube (latent) and, optionally, each joint
range of the full-space baseline, reusing one learned GPDM; :func:`format_table`
prints the rows like Table 2 (tube, cost, gain %, time | range, cost, gain %, time).

Warm start (``warm_start=True``, default): a smaller tube's optimum is feasible for a larger
one, so each tube starts from the Solution of the largest smaller tube solved before it (in the
given order), instead of the training fit (:func:`latentoc.solve.solve`'s ``warm_start``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable, Sequence

from .problem import Problem
from .results import atomic_write, write_json
from .solve import problem_gpdm, resolve_tube, solve

__all__ = ["sweep", "format_table", "write_sweep"]

_FIELDS = ("method", "tube_spec", "tube", "tube_relative", "joint_range_deg", "latent_dim", "status", "success",
           "iterations", "cost_initial", "cost", "performance_gain_pct", "solve_time_s", "build_time_s",
           "max_tube_violation", "quadrature_error", "warm_start")
# the 1 kHz verification of contact problems (latentoc.jump.verify), kept when a result has them
_CHECKS = ("max_dynamics_residual", "max_flight_residual", "min_normal_force", "max_friction_ratio", "cop_margin",
           "cop_margin_loaded", "zmp_margin", "com_margin", "max_torque_violation", "max_point_cone_violation",
           "max_sigma2", "toe_displacement", "toe_slip", "eq33_feet_distance")


# the other start of a tube solved from two (the broad jump's sweep_starts), kept when present
_STARTS = ("other_start",)


def _row(r: dict[str, Any]) -> dict[str, Any]:
    return {**{k: r.get(k) for k in _FIELDS}, **{k: r[k] for k in _CHECKS + _STARTS if k in r}}


def _print_now(line: str) -> None:
    print(line, flush=True)


def sweep(problem: Problem, tubes: Sequence[float | str], baseline_ranges: Sequence[float] | None = None,
          latent_dim: int | None = None, hessian: str | None = None,
          progress: Callable[[str], None] | None = _print_now, warm_start: bool = True) -> list[dict[str, Any]]:
    """One row per solve (latent for each tube, then joint-range for each range); see the
    module doc for ``warm_start``."""
    rows: list[dict[str, Any]] = []
    gp = problem_gpdm(problem, latent_dim)[0] if tubes else None
    total = len(tubes) + len(baseline_ranges or [])
    solved: list[tuple[float, Any]] = []  # (delta, Solution) of the successful latent solves
    for i, tube in enumerate(tubes):
        previous = None
        if warm_start and solved:
            delta = resolve_tube(tube, gp.tube_size())
            smaller = [s for s in solved if s[0] <= delta]
            previous = max(smaller, key=lambda s: s[0])[1] if smaller else None
        sol = solve(problem, tube=tube, latent_dim=latent_dim, gpdm=gp, hessian=hessian, warm_start=previous)
        r = sol.result
        if warm_start and r["success"] and sol.warm:
            solved.append((r["tube"], sol))
        rows.append(_row(r))
        if progress:
            progress(f"[{i + 1}/{total}] tube {tube}: delta {r['tube']:.4g}, cost {r['cost']:.2f}, "
                     f"gain {r['performance_gain_pct']:.2f}%, {r['solve_time_s']:.2f} s, {r['status']}")
    for j, k in enumerate(baseline_ranges or []):
        r = solve(problem, method="joint-range", joint_range_deg=float(k), hessian=hessian).result
        rows.append(_row(r))
        if progress:
            progress(f"[{len(tubes) + j + 1}/{total}] joint range +-{k} deg: cost {r['cost']:.2f}, "
                     f"gain {r['performance_gain_pct']:.2f}%, {r['solve_time_s']:.2f} s, {r['status']}")
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """Markdown table in the layout of Table 2: latent rows left, joint-range rows right."""
    lat = [r for r in rows if r["method"] == "latent"]
    jr = [r for r in rows if r["method"] == "joint-range"]
    head = ("| tube | delta | delta/noise | cost | gain % | time s | status "
            "| joint range | cost | gain % | time s | status |")
    lines = [head, "|" + "---|" * 12]
    for i in range(max(len(lat), len(jr))):
        left = ["", "", "", "", "", "", ""]
        right = ["", "", "", "", ""]
        if i < len(lat):
            r = lat[i]
            left = [str(r["tube_spec"]), f"{r['tube']:.4g}", f"{r['tube_relative']:.3g}", f"{r['cost']:.2f}",
                    f"{r['performance_gain_pct']:.2f}", f"{r['solve_time_s']:.2f}", _ok(r)]
        if i < len(jr):
            r = jr[i]
            right = [f"+-{r['joint_range_deg']:g} deg", f"{r['cost']:.2f}", f"{r['performance_gain_pct']:.2f}",
                     f"{r['solve_time_s']:.2f}", _ok(r)]
        lines.append("| " + " | ".join(left + right) + " |")
    if lat:
        lines.append(f"\nlatent: d = {lat[0]['latent_dim']}, initial cost {lat[0]['cost_initial']:.2f}")
    if jr:
        lines.append(f"joint range: initial cost {jr[0]['cost_initial']:.2f}")
    return "\n".join(lines)


def _ok(r: dict) -> str:
    return "ok" if r["success"] else str(r["status"])


def write_sweep(rows: list[dict[str, Any]], out_dir: str | Path, meta: dict | None = None) -> tuple[Path, Path]:
    """Atomically write ``sweep.json`` (rows + meta) and ``sweep.md`` (the table)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "sweep.json", {"meta": meta or {}, "rows": rows})
    atomic_write(out / "sweep.md", lambda f: f.write(format_table(rows) + "\n"))
    return out / "sweep.json", out / "sweep.md"
