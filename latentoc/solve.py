"""Solving a problem: dispatch on ``problem.kind`` to the kind's solver (:data:`SOLVERS`).

Contract for a problem kind (``latentoc.min_torque_problem``, ``latentoc.jump.problem``)::

    from latentoc.solve import SOLVERS, Solution
    def solve_my_kind(problem, *, method, joint_range_deg, gpdm, verbose, warm_start) -> Solution: ...
    SOLVERS["my-kind"] = solve_my_kind

The solver reads every setting from the :class:`~latentoc.problem.Problem` (already checked
against the kind's schema), raises :class:`~latentoc.errors.SolveError` for what only solving
can find wrong (an infeasible tube, an unknown method) BEFORE any work is written, and returns a
:class:`Solution`: a JSON-ready ``result`` dict (at least problem, kind, method, status, success,
iterations, cost_initial, cost, performance_gain_pct, cost_meaning, solve_time_s and violations;
for a latent solve tube_spec, tube, tube_relative, tube_training, max_sigma2; the rest becomes
the result's details), the ``trajectory`` arrays (keys from :data:`latentoc.results.TRAJECTORY_KEYS`),
the GPDM it used and what a neighbouring tube may start from (``warm``, with its ``tube``).
:class:`latentoc.results.Result` turns a Solution into the versioned result schema; this
module's :func:`solve` returns the Solution, the public ``latentoc.solve`` the Result.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import import_module
from typing import Any

from .errors import ProblemError, SolveError
from .gpdm import GPDM
from .problem import KIND_MODULES, Problem, parse_tube

__all__ = ["solve", "Solution", "SolveError", "SOLVERS", "solver_for", "apply_overrides", "resolve_tube", "tube_delta"]


@dataclass
class Solution:
    """What a kind's solver returns: ``result`` (JSON-ready dict), ``trajectory`` (numpy arrays),
    the ``gpdm`` it solved in, and ``warm``, what a neighbouring solve of the same problem may
    start from (a kind's own data, with the ``tube`` it was solved at)."""

    result: dict[str, Any]
    trajectory: dict[str, Any] = field(default_factory=dict)
    warm: dict[str, Any] | None = None
    gpdm: GPDM | None = None

    @property
    def success(self) -> bool:
        return bool(self.result.get("success", False))


#: problem kind -> solver function ``(problem, **options) -> Solution`` (module doc).
SOLVERS: dict[str, Callable[..., Solution]] = {}


def _kind_module(kind: str) -> Any:
    if kind not in KIND_MODULES:
        raise SolveError(f"no solver for problem kind {kind!r}; known kinds: {', '.join(sorted(KIND_MODULES))}")
    return import_module(KIND_MODULES[kind])


def solver_for(kind: str) -> Callable[..., Solution]:
    """The registered solver of a problem kind (importing its module if needed)."""
    if kind not in SOLVERS:
        _kind_module(kind)
    if kind not in SOLVERS:
        raise SolveError(f"no solver for problem kind {kind!r}; known kinds: {', '.join(sorted(SOLVERS))}")
    return SOLVERS[kind]


def solve(problem: Problem, *, tube: float | str | None = None, latent_dim: int | None = None,
          control_points: int | None = None, hessian: str | None = None, method: str = "latent",
          joint_range_deg: float | None = None, gpdm: GPDM | None = None, verbose: bool = False,
          warm_start: Solution | None = None) -> Solution:
    """Solve ``problem``; ``tube``, ``latent_dim``, ``control_points`` and ``hessian`` override its
    settings (checked like the file's, a :class:`SolveError` if wrong). ``warm_start``: the
    Solution of the same problem at a smaller tube, whose optimum is feasible here; each kind takes
    what it needs from its ``warm`` (the arm: the control points; the jump: the point and
    multipliers)."""
    problem = apply_overrides(problem, {"tube": tube, "latent_dim": latent_dim, "control_points": control_points,
                                        "hessian": hessian})
    return solver_for(problem.kind)(problem, method=method, joint_range_deg=joint_range_deg, gpdm=gpdm,
                                    verbose=verbose, warm_start=warm_start)


def apply_overrides(problem: Problem, overrides: dict[str, Any]) -> Problem:
    """``problem`` with the settings in ``overrides`` that are not None; a SolveError if wrong."""
    given = {k: v for k, v in overrides.items() if v is not None}
    if not given:
        return problem
    try:
        return problem.replace(**given)
    except ProblemError as exc:
        raise SolveError(str(exc)) from None


def resolve_tube(spec: float | str, reference: float) -> float:
    """Absolute delta from a tube spec (number or "<k>x" times ``reference``)."""
    try:
        value, relative = parse_tube(spec)
    except ProblemError as exc:
        raise SolveError(str(exc)) from None
    return value * reference if relative else value


def tube_delta(problem: Problem, spec: float | str) -> float:
    """The absolute delta of a tube spec for ``problem``: a relative spec times the kind's
    ``tube_reference(problem)`` (tube_training of its GPDM, learned if needed)."""
    value, relative = parse_tube(spec)
    return value * float(_kind_module(problem.kind).tube_reference(problem)) if relative else value
