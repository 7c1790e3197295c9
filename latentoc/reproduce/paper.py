"""The paper's experiments, rerun: Tables 2, 3, 4 and 6 and Fig. 5, ours beside the paper's.

:func:`reproduce` runs the arm sweeps (latent d = 3 with the full configuration-space baseline,
Table 2; d = 2, Table 4), the end-effector distances of new start poses (Fig. 5, Eq. 31-32),
and unless ``quick`` the sampling-based baseline (Table 3, with OMPL) and the broad-jump sweep
(Table 6); :func:`report` writes them as markdown with the machine and the versions that made
them (``python -m latentoc reproduce`` writes docs/reproduction.md).
"""
from __future__ import annotations

import datetime
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from latentoc.runtime.environment import Environment
from latentoc.problem.toml_files import load_problem
from latentoc.results import Result

__all__ = ["PAPER", "Reproduction", "reproduce", "report", "environment"]

#: the paper's tables: rows of (tube or joint range or iteration, cost or distance, gain %, time s)
PAPER: dict[str, list[tuple[float, float, float, float]]] = {
    "table2_latent": [(1e-6, 341.89, 2.87, 7.55), (4e-6, 304.62, 13.46, 7.27), (6e-6, 294.27, 16.4, 7.57),
                      (8e-6, 286.88, 18.5, 7.92), (1e-5, 282.48, 19.75, 7.91), (2e-5, 265.44, 24.59, 8.36),
                      (4e-5, 253.12, 28.09, 8.48), (6e-5, 249.14, 29.22, 8.55), (8e-5, 246.36, 30.01, 8.32),
                      (1e-4, 241.82, 31.3, 8.57), (2e-4, 237.32, 32.58, 8.63), (4e-4, 230.45, 34.53, 8.66),
                      (5e-4, 226.41, 35.68, 8.5), (1e-2, 226.41, 35.68, 8.5)],
    "table2_full": [(5, 333.27, 5.32, 23.32), (10, 298.21, 15.28, 23.45), (15, 285.82, 18.8, 23.69),
                    (20, 269.10, 23.55, 23.92), (25, 250.91, 28.72, 24.22), (30, 240.63, 31.64, 24.52),
                    (35, 225.77, 35.86, 24.31), (40, 224.22, 36.3, 24.86), (45, 216.37, 38.53, 24.56),
                    (50, 206.66, 41.29, 24.47), (55, 199.02, 43.46, 24.3), (60, 191.14, 45.7, 24.12),
                    (62, 189.38, 46.2, 24.31), (90, 189.38, 46.2, 24.31)],
    "table3": [(3830, 355.38, -0.96, 5436), (4265, 315.73, 10.30, 8310), (5390, 275.06, 21.86, 15529),
               (7660, 252.74, 28.20, 24371), (9135, 225.59, 35.91, 46532)],
    "table4": [(1e-6, 339.87, 3.44, 5.23), (4e-6, 318.74, 8.16, 5.35), (6e-6, 309.04, 11.94, 5.54),
               (8e-6, 301.59, 14.32, 6.84), (1e-5, 293.01, 16.76, 6.74), (2e-5, 289.74, 17.69, 6.75),
               (4e-5, 268.25, 23.79, 6.5), (6e-5, 255.76, 27.34, 6.86), (8e-5, 251.57, 28.53, 6.68),
               (1e-4, 249.86, 29.02, 6.76), (1e-3, 249.86, 29.02, 6.75)],
    "table6": [(0.02, 1.47, 1.38, 18.72), (0.04, 1.64, 13.1, 18.85), (0.06, 1.7, 17.24, 18.97),
               (0.08, 1.77, 22.07, 18.97), (0.1, 1.81, 24.83, 18.93), (0.12, 1.88, 29.66, 19.01),
               (0.14, 1.92, 32.41, 19.35), (0.16, 1.92, 32.41, 19.35)],
}
PAPER_INITIAL = {"arm": 352.0, "jump": 1.45}

# why our numbers differ, per table (the paper's setting against ours)
NOTES = {
    "table2": ("The tubes are not comparable by value: delta is in units of sigma^2 (Eq. 19), which depend on the "
               "learned hyperparameters, so ours are multiples of the training motion's own tube (Eq. 30). The "
               "training trials differ (the paper's arm model and trial are not published; ours cost {initial:.1f} "
               "against 352), so the gains, not the costs, compare. Our tube holds on the 1 kHz grid and every "
               "row to 1e-8; the paper's times include its own code and machine."),
    "table3": ("The paper's kinodynamic RRT* ran 5,436-46,532 s; ours (OMPL's RRT* with a steering edge, "
               "latentoc.baselines.sampling) runs the wall-time budgets shown, and its costs are rechecked with "
               "numeric Pinocchio on the 1 kHz grid."),
    "table4": "As Table 2, with a two-dimensional latent space.",
    "table6_full": ("The full configuration-space jump (`solve broad-jump --method joint-range --joint-range K`, "
                    "minutes to more than half an hour per solve) is not rerun here: its distances, iterations and "
                    "times beside the latent solve are in docs/broad-jump.md, \"The full configuration-space broad "
                    "jump\"."),
    "fig5": ("The paper plots the distances against the tube; here they are listed. The relation is near linear "
             "in both when the tube is small."),
    "table6": ("The paper's jump was a penalty-contact forward simulation with soft torque and balance limits and "
               "a restitution of 0.5; ours holds the torque limits (Eq. 34), the friction cones, the centre of "
               "pressure, the ZMP and the COM (Eq. 35-36) as hard constraints, on the 1 kHz grid where they are "
               "sampled, with the planted feet still by construction and a landing at rest (no impact). The paper's "
               "distance (1.45 m initially) most likely counts both feet (Eq. 33 integrates the feet's speed): ours "
               "is one toe tip's{initial}. Ours is measured from the capture, which is not a physical jump under "
               "these contacts{physical} (docs/broad-jump.md, \"Contacts exact by construction\")."),
}


def environment() -> dict[str, str]:
    """The machine and the versions a reproduction ran with, and the day."""
    env = Environment.current()
    return {"date": datetime.date.today().isoformat(), "cpu": f"{env.cpu} ({env.cpu_count} CPUs)",
            "python": env.python, "latentoc": env.latentoc, "numpy": env.numpy, "scipy": env.scipy,
            "casadi": env.casadi, "pinocchio": env.pinocchio}


@dataclass
class Reproduction:
    """Our rows of each experiment (None: not run) and the environment."""

    table2: list[Result] = field(default_factory=list)
    table4: list[Result] = field(default_factory=list)
    table3: list[Any] | None = None
    table6: list[Result] | None = None
    fig5: list[dict[str, Any]] = field(default_factory=list)
    fig5_tubes: list[Any] = field(default_factory=list)
    skipped: dict[str, str] = field(default_factory=dict)
    environment: dict[str, str] = field(default_factory=environment)


def reproduce(quick: bool = False, arm: str = "arm-raise", jump: str = "broad-jump",
              budgets: Sequence[float] = (10.0, 60.0, 300.0), say: Callable[[str], None] = print) -> Reproduction:
    """Run the experiments (module doc); ``quick``: the arm's tables and Fig. 5 only."""
    from latentoc.min_torque.training import problem_gpdm
    from latentoc.robots import load_robot
    from latentoc.min_torque.start_poses import start_pose_distances
    from latentoc.sweeps import sweep
    from latentoc.latent.tube import resolve_tube

    out = Reproduction()
    problem = load_problem(arm)
    say("Table 2: latent d = 3 and the full configuration space")
    out.table2 = sweep(problem, baseline_ranges=problem.sweep_ranges, progress=say).results
    say("Table 4: latent d = 2")
    out.table4 = sweep(problem.replace(latent_dim=2), progress=say).results
    say("Fig. 5: end-effector distances of new start poses")
    gp, _ = problem_gpdm(problem)
    out.fig5_tubes = list(problem.start_pose_tubes)
    deltas = [resolve_tube(s, gp.tube_size()) for s in out.fig5_tubes]
    out.fig5 = start_pose_distances(gp, load_robot(problem.robot), problem.start_pose_frame, deltas)
    if quick:
        out.skipped = {"table3": "not run (quick)", "table6": "not run (quick)"}
        return out
    try:
        from latentoc.baselines.sampling import plan
        say("Table 3: the sampling-based baseline")
        out.table3 = plan(problem, seconds=list(budgets))
    except ImportError as exc:
        out.skipped["table3"] = f"not run: {exc}"
    say("Table 6: the broad jump")
    out.table6 = sweep(load_problem(jump), progress=say).results
    return out


def _table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _side_by_side(paper: list[list[str]], ours: list[list[str]], paper_head: list[str], our_head: list[str]) -> str:
    n = max(len(paper), len(ours))
    pad_p, pad_o = [""] * len(paper_head), [""] * len(our_head)
    rows = [(paper[i] if i < len(paper) else pad_p) + (ours[i] if i < len(ours) else pad_o) for i in range(n)]
    return _table([f"paper: {h}" for h in paper_head] + [f"ours: {h}" for h in our_head], rows)


def _latent_rows(results: list[Result]) -> list[list[str]]:
    return [[str(r.tube.spec), f"{r.tube.delta:.3g}", f"{r.cost:.2f}", f"{r.gain_pct:.2f}", f"{r.times.solve_s:.2f}",
             "ok" if r.success else r.status] for r in results if r.method == "latent" and r.tube is not None]


def _paper_rows(key: str, first: Callable[[float], str] = lambda v: f"{v:g}") -> list[list[str]]:
    return [[first(a), f"{b:g}", f"{c:g}", f"{d:g}"] for a, b, c, d in PAPER[key]]


def arm_gains(results: list[Result], method: str = "latent") -> list[float]:
    """The gains (%) of a sweep's rows of one method, in order: what the README's arm table shows."""
    return [r.gain_pct for r in results if r.method == method]


def report(rep: Reproduction) -> str:
    """docs/reproduction.md: each experiment, the paper's numbers and ours side by side."""
    env = rep.environment
    parts = ["# Reproduction of the paper's experiments", "",
             "Written by `python -m latentoc reproduce` (latentoc.reproduce.paper); every number below is that "
             "command's output on this machine:", "",
             _table(["", ""], [[k, v] for k, v in env.items()]), ""]
    lat = [r for r in rep.table2 if r.method == "latent"]
    full = [r for r in rep.table2 if r.method == "joint-range"]
    initial = lat[0].cost_initial if lat else float("nan")
    parts += ["## Table 2: arm raising, latent d = 3 and the full configuration space", "",
              f"Initial cost: paper 352, ours {initial:.2f}.", "",
              _side_by_side(_paper_rows("table2_latent"), _latent_rows(rep.table2),
                            ["delta", "cost", "gain %", "time s"], ["tube", "delta", "cost", "gain %", "time s", "status"]),
              "",
              _side_by_side(_paper_rows("table2_full", lambda v: f"+-{v:g} deg"),
                            [[f"+-{r.details['joint_range_deg']:g} deg", f"{r.cost:.2f}", f"{r.gain_pct:.2f}",
                              f"{r.times.solve_s:.2f}", "ok" if r.success else r.status] for r in full],
                            ["joint range", "cost", "gain %", "time s"], ["joint range", "cost", "gain %", "time s",
                                                                          "status"]),
              "", NOTES["table2"].format(initial=initial), ""]
    parts += ["## Table 3: kinodynamic RRT* (sampling-based)", ""]
    if rep.table3 is None:
        parts += [f"Ours: {rep.skipped.get('table3', 'not run')}.", "",
                  _table(["iteration", "cost", "gain %", "time s"], _paper_rows("table3"))]
    else:
        parts.append(_side_by_side(_paper_rows("table3"),
                                   [[str(r.iterations), f"{r.cost:.2f}",
                                     f"{100 * (initial - r.cost) / initial:.2f}" if r.solved else "-",
                                     f"{r.time_s:.0f}"] for r in rep.table3],
                                   ["iteration", "cost", "gain %", "time s"], ["iteration", "cost", "gain %",
                                                                                "time s"]))
    parts += ["", NOTES["table3"], ""]
    lat2 = [r for r in rep.table4 if r.method == "latent"]
    parts += ["## Table 4: arm raising, latent d = 2", "",
              _side_by_side(_paper_rows("table4"), _latent_rows(rep.table4), ["delta", "cost", "gain %", "time s"],
                            ["tube", "delta", "cost", "gain %", "time s", "status"]), "", NOTES["table4"], ""]
    if lat and lat2 and full:
        best = max(r.gain_pct for r in lat)
        parts += [_table(["quantity", "paper", "ours"], [
            ["max gain, latent d = 3 / full space", f"{35.68 / 46.2:.0%}", f"{best / max(r.gain_pct for r in full):.0%}"],
            ["max gain, latent d = 2 / d = 3", f"{29.02 / 35.68:.0%}", f"{max(r.gain_pct for r in lat2) / best:.0%}"],
            ["mean solve time, full space / latent d = 3", f"{np.mean([r[3] for r in PAPER['table2_full']]) / np.mean([r[3] for r in PAPER['table2_latent']]):.1f}",
             f"{np.mean([r.times.solve_s for r in full]) / np.mean([r.times.solve_s for r in lat]):.2f}"]]), ""]
    parts += ["## Fig. 5: end-effector distances of new start poses (Eq. 31-32)", "",
              _table(["tube", "delta", "latent distance", "translational distance m (Eq. 31)", "pose distance (Eq. 32)"],
                     [[str(s), f"{r['tube']:.3g}", f"{r['latent_distance']:.4f}", f"{r['translational_distance']:.4f}",
                       f"{r['pose_distance']:.4f}"] for s, r in zip(rep.fig5_tubes, rep.fig5)]),
              "", NOTES["fig5"], ""]
    parts += ["## Table 6: the broad jump", ""]
    if rep.table6 is None:
        parts += [f"Ours: {rep.skipped.get('table6', 'not run')}.", "",
                  _table(["delta", "distance m", "gain %", "time s"], _paper_rows("table6"))]
        jump_initial = float("nan")
    else:
        jump_initial = rep.table6[0].cost_initial if rep.table6 else float("nan")
        parts.append(_side_by_side(_paper_rows("table6"),
                                   [[f"{r.tube.delta:.3g}", f"{r.cost:.3f}", f"{r.gain_pct:.2f}", f"{r.times.solve_s:.1f}",
                                     "ok" if r.success else r.status] for r in rep.table6 if r.tube is not None],
                                   ["delta", "distance m", "gain %", "time s"],
                                   ["delta", "distance m", "gain %", "time s", "status"]))
    initial_text = f", {jump_initial:.3f} m initially" if np.isfinite(jump_initial) else ""
    # the physical motion nearest the capture's fit: phase 1's point of the smallest tube's solve
    phase1 = (rep.table6[0].details.get("phase1") or {}) if rep.table6 else {}
    physical = f"; its nearest physical motion, phase 1's point, jumps {phase1['distance']:.3f} m" if "distance" in phase1 else ""
    parts += ["", NOTES["table6"].format(initial=initial_text, physical=physical), "", NOTES["table6_full"], ""]
    return "\n".join(parts)
