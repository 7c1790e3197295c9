"""The public solve: a problem in, a :class:`~latentoc.results.Result` out (``latentoc.solve``)."""
from __future__ import annotations

from .gpdm import GPDM
from .interrupts import watching
from .problem import Problem
from .results import Result
from .solve import Solution, solver_for

__all__ = ["solve"]


def solve(problem: Problem, *, method: str = "latent", joint_range_deg: float | None = None,
          gpdm: GPDM | None = None, warm_start: Result | Solution | None = None, verbose: bool = False) -> Result:
    """Solve ``problem`` (its settings: :func:`latentoc.load_problem` and :meth:`Problem.replace`).

    ``method``: ``"latent"``, or ``"joint-range"`` for the arm's full configuration-space
    baseline (``joint_range_deg``, default the problem's). ``gpdm``: a learned GPDM to use
    instead of learning the problem's. ``warm_start``: the result of the same problem at a
    smaller tube, whose optimum the solve starts from. ``verbose``: Ipopt's own log.
    Input that cannot be solved raises :class:`~latentoc.errors.SolveError` before any work;
    Ctrl-C raises KeyboardInterrupt, also when the solver swallowed it (:mod:`latentoc.interrupts`)."""
    with watching():
        solution = solver_for(problem.kind)(problem, method=method, joint_range_deg=joint_range_deg, gpdm=gpdm,
                                            verbose=verbose, warm_start=warm_start)
    return Result.from_solution(solution, problem)
