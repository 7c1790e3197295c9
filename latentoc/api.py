"""The public solve: a problem in, a :class:`~latentoc.results.Result` out (``latentoc.solve``)."""
from __future__ import annotations

from latentoc.arguments import expect
from latentoc.gpdm import GPDM
from latentoc.runtime.interrupts import watching
from latentoc.problem.kinds import Solution
from latentoc.problem.kinds import kind_of
from latentoc.problem.declaration import Problem
from latentoc.results import Result

__all__ = ["solve"]


def solve(problem: Problem, *, method: str = "latent", joint_range_deg: float | None = None,
          gpdm: GPDM | None = None, warm_start: Result | Solution | None = None, verbose: bool = False) -> Result:
    """Solve ``problem`` (its settings: :func:`latentoc.load_problem` and :meth:`Problem.replace`).

    ``method``: ``"latent"``, or ``"joint-range"`` for the full configuration-space baseline of
    the arm or the broad jump (``joint_range_deg``, default the problem's). ``gpdm``: a learned GPDM to use
    instead of learning the problem's. ``warm_start``: the result of the same problem at a
    smaller tube, whose optimum the solve starts from. ``verbose``: Ipopt's own log.
    Input that cannot be solved raises :class:`~latentoc.errors.SolveError` before any work;
    Ctrl-C raises KeyboardInterrupt, also when the solver swallowed it (:mod:`latentoc.runtime.interrupts`)."""
    expect("solve", "problem", problem, Problem, "a Problem (latentoc.load_problem(NAME or PATH))")
    expect("solve", "method", method, str, "'latent' or 'joint-range'")
    if joint_range_deg is not None:
        expect("solve", "joint_range_deg", joint_range_deg, (int, float), "a number of degrees or None")
    if gpdm is not None:
        expect("solve", "gpdm", gpdm, GPDM, "a learned GPDM or None")
    if warm_start is not None:
        expect("solve", "warm_start", warm_start, (Result, Solution), "the Result of the same problem or None")
    problem = problem.validate()  # settings changed in place since loading are checked again
    kind = kind_of(problem.kind)
    with watching():
        solution = kind.solve(problem, method=method, joint_range_deg=joint_range_deg, gpdm=gpdm, verbose=verbose,
                              warm_start=warm_start)  # type: ignore[arg-type]  # a Result carries .warm as a Solution does
    return Result.from_solution(solution, problem)
