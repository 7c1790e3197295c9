"""Solving a minimum-torque problem: in the GPDM latent space, or in joint space (the baseline).

:func:`solve_latent_min_torque` is the kind's solve (:mod:`.kind`): it reads the demonstration and
its (reduced) robot, builds the NLP of :mod:`.nlp` (``"latent"``: over the latent spline, the
tube held; ``"joint-range"``: over the joint spline, within +-k degrees of the training fit,
Sect. 4.1.1), runs the exchange (:mod:`.exchange`) and exports the motion on a 1 kHz grid
(:mod:`.export`). Input that cannot be solved is a :class:`~latentoc.errors.SolveError` before
any work: an unknown method, a robot that is not fixed-base, an unknown goal frame, a GPDM of
other data, a tube below sigma^2 at the fixed end points.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.errors import SolveError
from latentoc.gpdm import GPDM
from latentoc.problem.kinds import Solution, joint_range
from latentoc.motions import Demonstration, check_frames
from latentoc.nlp.blocks import compile_seconds
from latentoc.motions.problem_inputs import problem_demonstration, require_fixed_base
from latentoc.problem.declaration import Problem
from latentoc.robots import describe_robot
from latentoc.latent.spline_path import SplinePath
from latentoc.latent.tube import relative_tube, tube_delta
from latentoc.min_torque.exchange import solve_exchanged
from latentoc.min_torque.export import Solved, motion_result, time_grid
from latentoc.min_torque.nlp import MinTorqueNLP, Samples, joint_range_nlp, latent_nlp
from latentoc.min_torque.settings import MinTorqueSettings
from latentoc.min_torque.training import problem_gpdm, training_frames

__all__ = ["METHODS", "solve_latent_min_torque"]

METHODS = ("latent", "joint-range")


def solve_latent_min_torque(problem: Problem, *, method: str = "latent", joint_range_deg: float | None = None,
                            gpdm: GPDM | None = None, verbose: bool = False,
                            warm_start: Solution | None = None) -> Solution:
    """Minimum-torque motion (L = |tau|^2, or the problem's objective) in the GPDM latent space or,
    with ``method="joint-range"``, in the full configuration space (Sect. 4.1.1).

    ``gpdm``: a learned GPDM of the problem's training frames to use instead of learning it.
    ``warm_start``: a Solution whose latent control points (its ``warm["P"]``) Ipopt starts from
    instead of the training fit, used when it was solved at a tube no larger than this one;
    cost_initial and the gain still refer to the training fit."""
    if method not in METHODS:
        raise SolveError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    t0 = time.perf_counter()
    demo, robot, settings = _setup(problem)
    if method == "joint-range":
        solution = _solve_joint_range(problem, demo, robot, settings, joint_range_deg, verbose)
    else:
        solution = _solve_latent(problem, demo, robot, settings, gpdm, warm_start, verbose)
    solution.result["total_time_s"] = time.perf_counter() - t0  # the wall of this call: the parts add up to it
    return solution


def _solve_and_export(problem: Problem, nlp: MinTorqueNLP, rebuild: Callable[[Samples], MinTorqueNLP],
                      x0: np.ndarray, robot: pin.Model, settings: MinTorqueSettings, demo: Demonstration,
                      cost_initial: float, verbose: bool) -> tuple[Solved, dict, dict]:
    """The exchange's rounds (:func:`.exchange.solve_exchanged`) and the 1 kHz export; the result's
    ``solve_time_s`` is the rounds' wall (Ipopt and the checks between rounds), ``check_time_s``
    the export's."""
    t = time_grid(settings.duration)
    t0, c0 = time.perf_counter(), compile_seconds()
    solved = solve_exchanged(problem, nlp, rebuild, x0, robot, t, verbose)
    t1, compiled = time.perf_counter(), compile_seconds() - c0  # a rebuilt NLP's new blocks
    result, trajectory = motion_result(problem, solved, settings, demo, robot, t, cost_initial)
    result.update(solve_time_s=t1 - t0 - compiled, check_time_s=time.perf_counter() - t1, compile_time_s=compiled)
    return solved, result, trajectory


def _setup(problem: Problem) -> tuple[Demonstration, pin.Model, MinTorqueSettings]:
    """The demonstration, its (reduced) robot and the transcription settings; a SolveError for a
    robot the kind cannot solve, an unknown goal frame or a bad limit list."""
    demo = problem_demonstration(problem)
    robot = demo.model
    require_fixed_base(robot, problem.robot, "latent-min-torque")
    settings = MinTorqueSettings.from_problem(problem, duration=demo.duration)
    if settings.goal is not None and not robot.existFrame(settings.goal.frame):
        raise SolveError(f"goal frame {settings.goal.frame!r} is not a frame of {describe_robot(problem.robot)}; "
                         f"its frames: {', '.join(f.name for f in robot.frames)}")
    try:
        settings.limits(robot)
    except ValueError as exc:
        raise SolveError(str(exc)) from None
    return demo, robot, settings


def _latent_gpdm(problem: Problem, demo: Demonstration, gpdm: GPDM | None) -> tuple[GPDM, np.ndarray, float]:
    """The GPDM to solve in (the given one, checked, or the problem's), its training times and the
    time it took (s)."""
    t_train, Q_train = training_frames(problem, demo)
    d = problem.latent_dim
    if not 1 <= d < Q_train.shape[1]:
        raise SolveError(f"latent dimension d = {d} must satisfy 1 <= d < D = {Q_train.shape[1]} "
                         "(the training data's dimension)")
    if gpdm is not None:
        _check_given_gpdm(gpdm, problem, demo, Q_train)
        return gpdm, t_train, 0.0
    check_frames(demo, d, problem.gpdm["training_stride"])
    t0 = time.perf_counter()
    gp = problem_gpdm(problem)[0]
    return gp, t_train, time.perf_counter() - t0


def _check_given_gpdm(gpdm: GPDM, problem: Problem, demo: Demonstration, Q_train: np.ndarray) -> None:
    """A SolveError unless the given GPDM is one of this problem's training motion: its joints,
    latent dimension and training frames (the data it was learned from)."""
    D = gpdm.Y.shape[1] if np.ndim(gpdm.Y) == 2 else -1
    if D != Q_train.shape[1]:
        raise SolveError(f"the given GPDM models {D} joints; problem {problem.name!r} moves {Q_train.shape[1]} "
                         f"({', '.join(demo.joint_names)}): a GPDM of another robot or motion")
    if gpdm.latent_dim != problem.latent_dim:
        raise SolveError(f"the given GPDM has latent dimension {gpdm.latent_dim}; problem {problem.name!r} has "
                         f"latent.dim = {problem.latent_dim} (set it to {gpdm.latent_dim}: --latent-dim)")
    if gpdm.Y.shape[0] != len(Q_train):
        raise SolveError(f"the given GPDM has {gpdm.Y.shape[0]} latent points, the problem's training motion "
                         f"has {len(Q_train)} frames (gpdm.training_stride = {problem.gpdm['training_stride']})")
    if not np.allclose(gpdm.Y, Q_train, rtol=0.0, atol=1e-9):
        worst = float(np.max(np.abs(gpdm.Y - Q_train)))
        raise SolveError(f"the given GPDM was learned from other data than problem {problem.name!r}'s training "
                         f"motion (its frames differ by up to {worst:.3g} rad or m)")


def _feasible_delta(problem: Problem, gp: GPDM, P0: np.ndarray) -> float:
    """delta of the problem's tube; a SolveError below sigma^2 at the fixed end points."""
    tube_training = gp.tube_size()
    delta = tube_delta(problem.tube, gp)
    end_s2 = max(float(gp.variance(P0[0])), float(gp.variance(P0[-1])))
    if delta < end_s2:
        raise SolveError(f"tube delta = {delta:.4g} is infeasible: the fixed start/end latent points already have "
                         f"sigma^2 = {end_s2:.4g}; the smallest feasible delta is {end_s2:.4g} "
                         f"({end_s2 / tube_training:.3g}x of tube_training = {tube_training:.4g})")
    return delta


def _warm_points(warm_start: Solution | None, delta: float, P0: np.ndarray) -> np.ndarray | None:
    """The control points a warm start offers at tube ``delta`` (solved at a tube no larger), else None."""
    warm = warm_start.warm if warm_start is not None and warm_start.warm else None
    P = warm["P"] if warm is not None and warm.get("tube", np.inf) <= delta else None
    if P is not None and np.shape(P) != P0.shape:
        raise SolveError(f"warm start has control points of shape {np.shape(P)}, this problem's are {P0.shape}")
    return P


def _solve_latent(problem: Problem, demo: Demonstration, robot: pin.Model, settings: MinTorqueSettings,
                  gpdm: GPDM | None, warm_start: Solution | None, verbose: bool) -> Solution:
    gp, t_train, gpdm_time = _latent_gpdm(problem, demo, gpdm)
    t, sym = time_grid(settings.duration), SymbolicModel(robot)
    path = SplinePath.fit(settings.spline(), t_train, gp.latent_trajectories()[0], problem.boundary)
    delta = _feasible_delta(problem, gp, path.P_init)
    warm_P = _warm_points(warm_start, delta, path.P_init)
    t1, c1 = time.perf_counter(), compile_seconds()
    nlp = latent_nlp(gp, sym, settings, delta, path)
    cost_initial = nlp.cost(nlp.w0)
    compiled = compile_seconds() - c1
    build_time = time.perf_counter() - t1 - compiled
    x_start = nlp.w0 if warm_P is None else nlp.path.decision_vector(warm_P)
    solved, result, trajectory = _solve_and_export(
        problem, nlp, lambda extra: latent_nlp(gp, sym, settings, delta, path, extra=extra), x_start, robot, settings,
        demo, cost_initial, verbose)
    x, x0 = (path.spline.evaluate(P, t) for P in (trajectory["P"], path.P_init))
    sigma2 = gp.variance(x)
    tube_violation = max(0.0, float(np.max(sigma2)) - delta)
    result.update({
        "latent_dim": int(problem.latent_dim), "n_training_frames": int(len(t_train)), "tube_spec": problem.tube,
        "tube": delta, "tube_relative": relative_tube(delta, gp), "noise_variance": gp.noise_variance,
        "tube_training": gp.tube_size(), "tube_initial": float(np.max(gp.variance(x0))),
        "max_sigma2": float(np.max(sigma2)), "max_tube_violation": tube_violation,
        "violations": {"tube": tube_violation, **result["violations"]}, "build_time_s": build_time,
        "compile_time_s": result["compile_time_s"] + compiled,
        "gpdm_time_s": gpdm_time, "warm_start": warm_P is not None, **gp.learning_summary()})
    trajectory.update(x=x, x_initial=x0, sigma2=sigma2)
    warm: dict[str, Any] | None = {"P": trajectory["P"], "tube": delta} if solved.run.success else None
    return Solution(result=result, trajectory=trajectory, warm=warm, gpdm=gp)


def _solve_joint_range(problem: Problem, demo: Demonstration, robot: pin.Model, settings: MinTorqueSettings,
                       joint_range_deg: float | None, verbose: bool) -> Solution:
    k = joint_range(problem, joint_range_deg)
    t_train, Q_train = np.asarray(demo.t), np.asarray(demo.Q)  # all frames: no GPDM here
    sym = SymbolicModel(robot)
    t0, c0 = time.perf_counter(), compile_seconds()
    nlp = joint_range_nlp(sym, settings, t_train, Q_train, k)
    cost_initial = nlp.cost(nlp.w0)
    compiled = compile_seconds() - c0
    build_time = time.perf_counter() - t0 - compiled
    _, result, trajectory = _solve_and_export(
        problem, nlp, lambda extra: joint_range_nlp(sym, settings, t_train, Q_train, k, extra=extra), nlp.w0,
        robot, settings, demo, cost_initial, verbose)
    result.update({"joint_range_deg": k, "n_training_frames": int(len(t_train)), "build_time_s": build_time,
                   "compile_time_s": result["compile_time_s"] + compiled, "gpdm_time_s": 0.0, "warm_start": False})
    return Solution(result=result, trajectory=trajectory)
