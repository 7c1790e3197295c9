"""A solved minimum-torque NLP as a result: the motion on a 1 kHz grid, its cost, limits and facts.

The joint motion is rebuilt along the optimal path through the NLP's layer (the GP mean, or the
joint spline itself), the torques by Pinocchio's numeric RNEA; the cost is also integrated on that
grid (trapezoid) to report the quadrature's error. Both methods share :func:`motion_result`;
the latent solve adds its tube (:mod:`latentoc.latent.tube`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.latent import Layer
from latentoc.motions import Demonstration
from latentoc.nlp.ipopt import IpoptResult
from latentoc.problem.declaration import Problem
from latentoc.robots import describe_robot
from latentoc.latent.spline import BSpline
from latentoc.latent.spline_path import trapezoid_cost
from latentoc.min_torque.goal import goal_error
from latentoc.min_torque.nlp import MinTorqueNLP
from latentoc.min_torque.objectives import Objective
from latentoc.min_torque.settings import MinTorqueSettings

__all__ = ["TRAJECTORY_RATE_HZ", "Solved", "time_grid", "sampled_motion", "motion_result"]

TRAJECTORY_RATE_HZ = 1000.0


@dataclass
class Solved:
    """The exchange's outcome (:func:`.exchange.solve_exchanged`): the last NLP and Ipopt run, each
    round's summary and its Ipopt history (``convergence``)."""

    nlp: MinTorqueNLP
    run: IpoptResult
    rounds: list[dict[str, Any]] = field(default_factory=list)
    convergence: list[dict[str, Any]] = field(default_factory=list)


def time_grid(duration: float) -> np.ndarray:
    """The 1 kHz grid of a motion of ``duration`` s, both ends included."""
    return np.linspace(0.0, duration, int(round(duration * TRAJECTORY_RATE_HZ)) + 1)


def sampled_motion(layer: Layer, robot: pin.Model, spline: BSpline, P: np.ndarray,
                   t: np.ndarray, objective: Objective = Objective()) -> dict[str, np.ndarray]:
    """q, v, a (Eq. 26-28 through ``layer``) along the path P at times t, tau from Pinocchio's
    numeric RNEA and the objective's L (default |tau|^2): arrays len(t) x nv (L: len(t))."""
    Z = np.hstack([spline.evaluate(P, t, r) for r in range(3)])
    m = layer.motion(Z)
    data = robot.createData()
    tau = np.array([np.array(pin.rnea(robot, data, q, v, a)) for q, v, a in zip(m.y, m.yd, m.ydd)])
    q, v, a = np.asarray(m.y), np.asarray(m.yd), np.asarray(m.ydd)
    return {"q": q, "v": v, "a": a, "tau": tau, "L": objective.integrand(tau, v, a)}


def _limit_violations(settings: MinTorqueSettings, robot: pin.Model, motion: dict[str, np.ndarray]) -> dict[str, float]:
    """How far the 1 kHz motion leaves the joint (rad), velocity (rad/s) and torque limits (N m) and,
    with a goal, its position (m beyond the tolerance)."""
    out = settings.limits(robot).violations(motion)
    if settings.goal is not None:
        out["goal_m"] = max(0.0, goal_error(robot, settings.goal, motion["q"][-1]) - settings.goal.tolerance)
    return out


def _own_motion(problem: Problem, demo: Demonstration, settings: MinTorqueSettings, q: np.ndarray) -> dict[str, Any]:
    """The result's facts about the robot, the demonstration (and how far the motion's end poses q[0],
    q[-1] are from its first and last frames), the objective and the goal."""
    out = {"robot": describe_robot(problem.robot), "demonstration": demo.info(), "objective": settings.objective.name,
           "boundary_error_rad": {"start": float(np.max(np.abs(q[0] - demo.Q[0]))),
                                  "end": float(np.max(np.abs(q[-1] - demo.Q[-1])))}}
    if settings.goal is not None:
        out["goal"] = {"frame": settings.goal.frame, "position": list(settings.goal.position),
                       "tolerance": settings.goal.tolerance}
    return out


def motion_result(problem: Problem, solved: Solved, settings: MinTorqueSettings, demo: Demonstration,
                  robot: pin.Model, t: np.ndarray, cost_initial: float) -> tuple[dict[str, Any], dict[str, Any]]:
    """The result dict and the trajectory arrays of a solve on the grid ``t``, both methods' fields:
    status and cost (from ``cost_initial``, the training fit's), the cost on the grid, the limits'
    violations there, the Ipopt rounds and the motion's facts; q, v, a, tau, the control points,
    the training fit's motion and the enforced limits."""
    nlp, run = solved.nlp, solved.run
    spline, P0 = nlp.path.spline, nlp.path.P_init
    P = nlp.control_points(run.x)
    motion = sampled_motion(nlp.layer, robot, spline, P, t, settings.objective)
    initial = sampled_motion(nlp.layer, robot, spline, P0, t, settings.objective)
    dt = float(t[1] - t[0])
    cost_fine = trapezoid_cost(motion["L"], dt)
    result = {
        "problem": problem.name, "kind": problem.kind, "method": nlp.method,
        "quadrature": f"gauss-legendre, {problem.quadrature_points} nodes per knot interval",
        "status": run.status, "success": bool(run.success),
        "iterations": sum(r["iterations"] for r in solved.rounds), "cost_initial": cost_initial, "cost": run.f,
        "performance_gain_pct": 100.0 * (cost_initial - run.f) / cost_initial, "cost_meaning": nlp.objective.meaning,
        "cost_trapezoid_1ms": cost_fine, "cost_initial_trapezoid_1ms": trapezoid_cost(initial["L"], dt),
        "quadrature_error": abs(run.f - cost_fine) / abs(cost_fine),
        "solve_time_s": sum(r["time_s"] for r in solved.rounds), "n_variables": int(nlp.w0.size),
        "n_constraints": int(nlp.lbg.size), "violations": _limit_violations(settings, robot, motion),
        "exchange_rounds": solved.rounds, "convergence": solved.convergence,
        **_own_motion(problem, demo, settings, motion["q"])}
    trajectory = {"t": t, "q": motion["q"], "v": motion["v"], "a": motion["a"], "tau": motion["tau"], "P": P,
                  "P_initial": P0, "q_initial": initial["q"], "model": np.str_(robot.saveToString()),
                  **nlp.limits.arrays()}
    return result, trajectory
