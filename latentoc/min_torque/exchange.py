"""The exchange of a minimum-torque solve: constraint points added until the 1 kHz grid holds.

The NLP holds the tube and the joint and velocity limits on its constraint grid and the torque
limits at its quadrature nodes. After a successful Ipopt run the motion is sampled on the 1 kHz
grid (:func:`.export.sampled_motion`); the worst time of every stretch where it leaves the tube
(by more than :data:`~latentoc.nlp.exchange_rounds.TUBE_TOL` of delta) or a limit (by more than
:data:`LIMIT_TOL`) joins the NLP's nodes (:class:`.nlp.Samples`) and Ipopt resumes from the point
(the latent method warm, its multipliers carried to the same rows: :func:`carried_multipliers`),
for at most :data:`EXCHANGE_ROUNDS` runs (the loop: :func:`latentoc.nlp.exchange_rounds.exchange_rounds`).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin


from latentoc.nlp import ipopt
from latentoc.nlp.exchange_rounds import TUBE_TOL, Exchange, exchange_rounds
from latentoc.nlp.curvature import curvature
from latentoc.nlp.ipopt import IpoptResult
from latentoc.problem.declaration import Problem
from latentoc.results import convergence_entry
from latentoc.min_torque.export import Solved, sampled_motion
from latentoc.min_torque.nlp import MinTorqueNLP, Samples, ipopt_options

__all__ = ["LIMIT_TOL", "EXCHANGE_ROUNDS", "violated_times", "carried_multipliers", "solve_exchanged"]

LIMIT_TOL = 1e-6  # rad and N m a 1 kHz sample may leave the joint and torque limits by
EXCHANGE_ROUNDS = 8  # Ipopt runs at the most


def _worst_times(t: np.ndarray, slack: np.ndarray, tol: float) -> np.ndarray:
    """The worst times of each stretch of t where slack < -tol (its local minima)."""
    left = np.concatenate([[np.inf], slack[:-1]])
    right = np.concatenate([slack[1:], [np.inf]])
    return t[(slack < -tol) & (slack <= left) & (slack <= right)]


def violated_times(nlp: MinTorqueNLP, motion: dict[str, np.ndarray], sigma2: np.ndarray | None,
                   t: np.ndarray) -> tuple[Samples, dict[str, float]]:
    """Where the motion sampled at times t (:func:`.export.sampled_motion`) leaves the tube (by more
    than TUBE_TOL of delta), the joint, velocity or torque limits of ``nlp.limits`` (by more than
    LIMIT_TOL): each violated stretch's worst time, to add to the NLP, and the largest violations."""
    inside = (t > 0) & (t < t[-1])
    grid_slack = np.full(len(t), np.inf)
    worst = {}
    if sigma2 is not None and nlp.tube is not None:
        slack = (nlp.tube - sigma2) / nlp.tube
        worst["tube_rel"] = float(max(0.0, -slack.min()))
        grid_slack = np.minimum(grid_slack, slack / TUBE_TOL)
    slacks = nlp.limits.slacks(motion)
    for key in ("joint_limits_rad", "velocity_limits_rad_s"):  # rows on the constraint grid
        if key in slacks:
            worst[key] = float(max(0.0, -slacks[key].min()))
            grid_slack = np.minimum(grid_slack, slacks[key] / LIMIT_TOL)
    add = Samples(_worst_times(t[inside], grid_slack[inside], 1.0))
    if "torque_limits_nm" in slacks:
        slack = slacks["torque_limits_nm"]
        worst["torque_limits_nm"] = float(max(0.0, -slack.min()))
        add.torque = _worst_times(t, slack, LIMIT_TOL)
    known = nlp.extra.merged(Samples(nlp.grid_t, nlp.quad_t))
    add = Samples(add.grid[~np.isin(np.round(add.grid, 9), np.round(known.grid, 9))],
                  add.torque[~np.isin(np.round(add.torque, 9), np.round(known.torque, 9))])
    return add, worst


def _row_keys(nlp: MinTorqueNLP) -> list[tuple[str, float, int]]:
    """A key per constraint row, (family, time, component): the same row's in NLPs with more times."""
    times = {"tube": nlp.grid_t, "joint_limits": nlp.grid_t, "velocity_limits": nlp.grid_t,
             "torque": np.concatenate([nlp.quad_t, nlp.extra.torque])}
    keys = []
    for name, rows in nlp.rows.items():
        n, t = rows.stop - rows.start, times.get(name, np.zeros(1))
        per = n // len(t)
        keys += [(name, round(float(t[i // per]), 9), i % per) for i in range(n)]
    return keys


def carried_multipliers(old: MinTorqueNLP, new: MinTorqueNLP, lam_g: np.ndarray) -> np.ndarray:
    """``old``'s row multipliers in ``new``'s rows (zero for its new rows)."""
    where = {k: i for i, k in enumerate(_row_keys(old))}
    return np.array([lam_g[where[k]] if k in where else 0.0 for k in _row_keys(new)])


def _resume(old: MinTorqueNLP, new: MinTorqueNLP, run: IpoptResult) -> np.ndarray | dict[str, np.ndarray]:
    """The next round's start: the latent method's point with its multipliers carried (a warm start);
    the joint-range baseline's point alone (its table's optima were found so)."""
    if new.method == "joint-range":
        return run.x
    return {**run.multipliers(), "lam_g0": carried_multipliers(old, new, run.lam_g)}


def _run_ipopt(problem: Problem, nlp: MinTorqueNLP, start: np.ndarray | dict[str, np.ndarray],
               verbose: bool) -> IpoptResult:
    """Ipopt from ``start``: a point, or a warm start's point and multipliers."""
    options = ipopt_options(nlp, tol=problem.tol, max_iter=problem.max_iter, verbose=verbose)
    warm, x0 = (start, start["x0"]) if isinstance(start, dict) else (None, start)
    return ipopt.solve(nlp.nlp, x0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, options, warm=warm, hessian=problem.hessian,
                       desc=f"{problem.name} ({nlp.method})")


def solve_exchanged(problem: Problem, nlp: MinTorqueNLP, rebuild: Callable[[Samples], MinTorqueNLP], x0: np.ndarray,
                    robot: pin.Model, t: np.ndarray, verbose: bool) -> Solved:
    """Solve ``nlp`` from ``x0`` with the problem's Ipopt settings, check the tube and the limits on
    the 1 kHz grid t, add the violated times (``rebuild(extra)`` is the NLP with them) and resume
    from the point, until the grid holds (module doc)."""
    def record(nlp: MinTorqueNLP, run: IpoptResult) -> dict[str, Any]:
        # the second-order condition: the reduced Hessian's smallest eigenvalue (>= 0 at a minimum)
        c = curvature(nlp.nlp, run.x, run.lam_g, nlp.lbg, nlp.ubg, run.lam_x, nlp.lbx, nlp.ubx) \
            if run.success else None
        return {"iterations": run.iterations, "time_s": run.time_s, "status": run.status,
                "reduced_hessian_min": None if c is None else c.smallest,
                "grid_points": int(len(nlp.grid_t)), "torque_points": int(len(nlp.quad_t) + len(nlp.extra.torque)),
                "history": run.history}

    def check(nlp: MinTorqueNLP, run: IpoptResult) -> tuple[Samples | None, dict[str, float]]:
        P = nlp.control_points(run.x)
        motion = sampled_motion(nlp.layer, robot, nlp.path.spline, P, t, nlp.objective)
        sigma2 = nlp.layer.variance(nlp.path.spline.evaluate(P, t))[0] \
            if nlp.layer.has_tube and nlp.tube is not None else None
        add, worst = violated_times(nlp, motion, sigma2, t)
        return (add if add else None), worst

    kind = Exchange(solve=lambda nlp, x: _run_ipopt(problem, nlp, x, verbose), record=record, check=check,
                    grow=lambda nlp, add: rebuild(nlp.extra.merged(add)), resume=_resume)
    nlp, run, rounds = exchange_rounds(nlp, x0, kind, EXCHANGE_ROUNDS)
    convergence = [convergence_entry(nlp.method, k + 1, r.pop("history")) for k, r in enumerate(rounds)]
    return Solved(nlp, run, rounds, convergence)
