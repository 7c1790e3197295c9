"""A stand-in for a kind's solver in tests of the plumbing around solves (CLI, sweeps, interrupts):
``install(monkeypatch, costs)`` makes ``latentoc.solve`` return hand-made results without Ipopt."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from result_factory import make_result

from latentoc.problem.kinds import Solution

COST_INITIAL = 1000.0


def solution(problem: Any, cost: float, *, success: bool = True, warm_start: bool = False,
             status: str | None = None, **extra: Any) -> Solution:
    """A Solution of ``problem`` (an absolute tube) with this cost (minimised, from COST_INITIAL)."""
    delta = float(problem.tube)
    result = {"problem": problem.name, "kind": problem.kind, "method": "latent",
              "status": status or ("Solve_Succeeded" if success else "Maximum_Iterations_Exceeded"),
              "success": success, "iterations": 3, "cost_initial": COST_INITIAL, "cost": cost,
              "performance_gain_pct": 100.0 * (COST_INITIAL - cost) / COST_INITIAL, "cost_meaning": "test cost",
              "solve_time_s": 0.01, "tube_spec": problem.tube, "tube": delta, "tube_relative": 10 * delta,
              "tube_training": 0.1, "max_sigma2": 0.9 * delta, "violations": {"tube": 0.0},
              "warm_start": warm_start, **extra}
    return Solution(result=result, trajectory=make_result().trajectory,
                    warm={"P": np.zeros((7, 3)), "tube": delta} if success else None)


def install(monkeypatch: Any, solver: Callable[..., Solution]) -> list[dict[str, Any]]:
    """Route every ``latentoc.solve`` to ``solver(problem, warm)``; returns the log of its calls
    (tube, whether warm)."""
    import dataclasses

    import latentoc.api as api
    from latentoc.problem.kinds import kind_of

    calls: list[dict[str, Any]] = []

    def kind_solver(problem: Any, *, method: str, joint_range_deg: Any, gpdm: Any, verbose: bool,
                    warm_start: Any) -> Solution:
        warm = warm_start.warm if warm_start is not None else None
        calls.append({"tube": problem.tube, "warm": warm is not None})
        return solver(problem, warm)

    monkeypatch.setattr(api, "kind_of", lambda name: dataclasses.replace(kind_of(name), solve=kind_solver))
    return calls
