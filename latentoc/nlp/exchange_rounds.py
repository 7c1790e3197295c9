"""The exchange: an NLP's sampled rows grow where the exported 1 kHz motion breaks a hard constraint.

A solve checks every hard constraint on the 1 kHz grid of its exported motion, adds rows at the
worst time of each stretch that breaks (or comes near) one, and resumes warm, until the grid holds
(the Remez-style exchange of semi-infinite programming). The loop and the choice of times are
here, one for every kind; what is checked, added and carried is the kind's
(:mod:`latentoc.min_torque.exchange`, :mod:`latentoc.jump.solve.exchange`).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any, Generic, TypeVar

import numpy as np

from latentoc.intervals import runs
from latentoc.nlp.ipopt import IpoptResult

__all__ = ["TUBE_TOL", "Exchange", "worst_times", "exchange_rounds"]

TUBE_TOL = 1e-6  # sigma^2 on the 1 kHz grid may exceed delta by this fraction of it

N = TypeVar("N")  # a kind's NLP
A = TypeVar("A")  # what a check adds to it


def worst_times(slack: np.ndarray, below: np.ndarray, spacing: int = 0, neighbours: int = 0) -> np.ndarray:
    """Indices of samples in each run of ``below``: its least ``slack`` and, with ``spacing``, every
    ``spacing``-th sample of the grid in the run (a bound that holds along a stretch is held along
    it); a run shorter than ``spacing`` also its ``neighbours``-th neighbours either side (the bound
    moves a little when the solve resumes)."""
    out = []
    for a, b in runs(below):
        k = a + int(np.nanargmin(slack[a:b]))
        out.append(np.array([k]))
        if spacing:
            grid = np.arange(a, b)
            out.append(grid[grid % spacing == 0])
            if b - a < spacing and neighbours:
                out.append(np.array([k - neighbours, k + neighbours]))
    return np.unique(np.clip(np.concatenate(out), 0, len(slack) - 1)) if out else np.zeros(0, np.int64)


class Exchange(Generic[N, A]):
    """The kind's side of the loop: ``solve(nlp, start)`` runs Ipopt; ``record(nlp, run)`` is the
    round's summary; ``check(nlp, run)`` gives what to add (None: the grid holds, or nothing new
    to add) and the worst violations; ``grow(nlp, add)`` is the NLP with it; ``resume(old, new,
    run)`` the start of the next run (point, multipliers)."""

    def __init__(self, solve: Callable[[N, Any], IpoptResult], record: Callable[[N, IpoptResult], dict],
                 check: Callable[[N, IpoptResult], tuple[A | None, dict[str, float]]], grow: Callable[[N, A], N],
                 resume: Callable[[N, N, IpoptResult], Any]):
        self.solve, self.record, self.check, self.grow, self.resume = solve, record, check, grow, resume


def exchange_rounds(nlp: N, start: Any, kind: Exchange[N, A], max_rounds: int) -> tuple[N, IpoptResult, list[dict]]:
    """Solve ``nlp`` from ``start``, then check, grow and resume until the 1 kHz grid holds, a run
    fails, or ``max_rounds`` runs (module doc): the last NLP and run and each round's summary with
    its ``violation_1khz``."""
    run = kind.solve(nlp, start)
    rounds: list[dict] = []
    while True:
        entry = kind.record(nlp, run)
        rounds.append(entry)
        if not run.success:
            break
        add, entry["violation_1khz"] = kind.check(nlp, run)
        if add is None or len(rounds) >= max_rounds:
            break
        grown = kind.grow(nlp, add)
        start = kind.resume(nlp, grown, run)
        nlp = grown
        run = kind.solve(nlp, start)
    return nlp, run, rounds
