"""The ``"latent-min-torque"`` problem kind: its problem schema, GPDM and solve.

:data:`SCHEMA` declares the keys of an arm problem file (``problems/arm-raise.toml``);
:func:`solve_latent_min_torque` learns the GPDM (once per settings, :func:`problem_gpdm`), builds
the NLP of :mod:`latentoc.kinds.min_torque`, runs Ipopt and rebuilds the motion on a 1 kHz grid.

Tube sizes (Eq. 29). delta is in units of sigma^2 (Eq. 19), which depend on the learned
hyperparameters, so the paper's values do not transfer. ``tube`` is either a positive number
(absolute) or a string ``"<k>x"``: k times ``tube_training``, Eq. 30 for the training sequence
(max sigma^2 along its latent path). ``tube_initial`` (max sigma^2 along the initial spline, the
least-squares fit of that path, on a 1 kHz grid) is reported too: for tubes below it the initial
guess is infeasible (Ipopt restores feasibility first). The smallest feasible delta is sigma^2 at
the fixed end points. ``tube_relative`` = delta / noise variance (1/beta_3) compares sweeps across
problems. The measured GPDM settings of arm-raise are in ``problems/arm-raise.toml`` and
docs/arm-raise.md.

``robot`` and ``training`` are registered names or the user's own files (:mod:`latentoc.problem_inputs`):
any fixed-base robot, its motion read from CSV, NPZ or ASF + AMC; the robot is reduced to the
joints the motion moves. ``[objective]`` chooses the running cost (:mod:`latentoc.kinds.objectives`),
``[transcription]`` switches the joint, velocity and torque limits (:mod:`latentoc.kinds.limits`)
and ``[goal]`` adds an end-effector goal (:mod:`latentoc.kinds.goal`).
"""
from __future__ import annotations

import time
from dataclasses import fields
from typing import Any

import numpy as np
import pinocchio as pin

from .dynamics import SymbolicModel
from .errors import ProblemError, SolveError
from .gpdm import GPDM, GPDMSettings, learned_gpdm
from .gpdm.cache import model_path
from .kinds.goal import goal_error
from .kinds.min_torque import (METHODS, MinTorqueNLP, MinTorqueSettings, ipopt_options, joint_range_nlp,
                               latent_nlp, sampled_motion, violated_times)
from .kinds.objectives import OBJECTIVES, Objective
from .latent import GPLayer
from .nlp import ipopt
from .nlp.ipopt import HESSIANS, IpoptResult
from .motions import TRAINING, TRAINING_MOTIONS, Demonstration, check_frames
from .problem import TUBE, Problem
from .motions.problem_inputs import check_problem_files, problem_demonstration, require_fixed_base
from .results import convergence_entry
from .robots import ROBOT, describe_robot
from .schema import Check, Schema, Setting, Table, boolean, choice, integer, list_of, number, optional, text
from .sizes import check_memory, spline_transcription_bytes
from .solve import SOLVERS, Solution, resolve_tube
from .spline_path import SplinePath, fixed_rows, trapezoid_cost

__all__ = ["SCHEMA", "TRAINING_MOTIONS", "training_motion", "problem_gpdm", "gpdm_settings", "tube_reference",
           "solve_latent_min_torque", "check_problem"]

TRAJECTORY_RATE_HZ = 1000.0


def _torque_limits(v: object) -> str | list[float]:
    if v == "urdf":
        return "urdf"
    return list_of(number(0, lo_open=True)).convert(v)


def _position(v: object) -> list[float]:
    if not isinstance(v, (list, tuple)) or len(v) != 3:
        raise ValueError
    return [number().convert(x) for x in v]


_GPDM_DEFAULTS = GPDMSettings()
_GPDM_CHECKS = {"balanced": boolean(), "ftol": number(0, lo_open=True), "max_iterations": integer(1),
                "seed": integer(), "init": choice("pca", "random"), "kappa_sq": number(0, lo_open=True),
                "log_hyper_bound": number(0, lo_open=True)}
_GPDM_DOCS = {"ftol": "convergence: the Newton decrement of Eq. 16 <= ftol |Eq. 16|",
              "max_iterations": "Newton iterations at most (a safety cap: then reported not converged)",
              "training_stride": "learn on every k-th training frame (the last one always kept)"}
_SPLINE = MinTorqueSettings(duration=1.0)  # the transcription's defaults

#: the keys of a latent-min-torque problem file
SCHEMA = Schema("latent-min-torque", (
    Setting("robot", "robot", ROBOT, doc="a latentoc.load_robot name or a table naming a URDF (or an ASF skeleton)"),
    Setting("training", "training", TRAINING, doc="a registered motion or a table naming a CSV, NPZ or AMC file"),
    Setting("duration", "duration", optional(number(0, lo_open=True)), None,
            "s (Table 1); none: the training motion's"),
    Setting("objective.cost", "objective", choice(*OBJECTIVES), "torque",
            '"torque": |tau|^2 (Eq. 22); "energy": sqrt((tau . qdot)^2 + eps^2) - eps; "acceleration": |qddot|^2'),
    Setting("objective.energy_epsilon", "energy_epsilon", number(0, lo_open=True), Objective.epsilon,
            "W: smoothing of |tau . qdot| in the energy cost"),
    Setting("latent.dim", "latent_dim", integer(1), 3, "latent dimension d"),
    Setting("latent.control_points", "control_points", integer(2), _SPLINE.control_points, "spline control points m"),
    Setting("latent.spline_degree", "spline_degree", integer(1), _SPLINE.spline_degree, "B-spline degree"),
    Setting("latent.boundary", "boundary", choice("rest", "pose"), _SPLINE.boundary,
            '"rest": fix p1, p2, p(m-1), pm (end poses and zero end velocity); "pose": fix p1, pm'),
    Setting("latent.tube", "tube", TUBE, "1.5x", 'delta (units of sigma^2) or "<k>x" times tube_training'),
    Setting("transcription.quadrature_points", "quadrature_points", integer(1, 20), _SPLINE.quadrature_points,
            "Gauss-Legendre nodes per knot interval (objective)"),
    Setting("transcription.constraint_points", "constraint_points", integer(1), _SPLINE.constraint_points,
            "tube and joint-limit nodes per knot interval"),
    Setting("transcription.joint_limits", "joint_limits", boolean(), _SPLINE.joint_limits,
            "the model's joint limits on the constraint grid"),
    Setting("transcription.torque_limits", "torque_limits",
            Check(_torque_limits, 'a list of positive numbers or "urdf"'), [],
            'N m: [] none, [s] every joint |tau| <= s, one per joint, or "urdf" (its effort limits)'),
    Setting("transcription.velocity_limits", "velocity_limits", boolean(), False,
            "|qdot| <= the model's velocity limits on the constraint grid"),
    Setting("goal.frame", "goal_frame", optional(text()), None,
            "end-effector goal: this frame's position at t = T (none: the demonstration's end pose)"),
    Setting("goal.position", "goal_position", optional(Check(_position, "3 numbers")), None, "m, world frame"),
    Setting("goal.tolerance", "goal_tolerance", number(0), 0.0, "m: 0 holds the position exactly"),
    Setting("solver.hessian", "hessian", choice(*HESSIANS), "exact", "Ipopt's Hessian"),
    Setting("solver.max_iter", "max_iter", integer(1), 300, "Ipopt iterations"),
    Setting("solver.tol", "tol", number(0, lo_open=True), 1e-8, "Ipopt tolerance"),
    Setting("baseline.joint_range_deg", "joint_range_deg", number(0, lo_open=True), 45.0,
            "full-space baseline: +-deg around the training fit (Sect. 4.1.1)"),
    Setting("sweep.tubes", "sweep_tubes", list_of(TUBE), ["1x", "2x", "5x"], "the sweep's tubes"),
    Setting("sweep.ranges", "sweep_ranges", list_of(number(0, lo_open=True)), [5.0, 10.0, 20.0],
            "the baseline sweep's joint ranges, deg"),
    Setting("start_poses.tubes", "start_pose_tubes", list_of(TUBE), ["1x", "2x", "5x"],
            "tubes of the new start poses (Sect. 4.1.4)"),
    Setting("start_poses.frame", "start_pose_frame", text(), "lhand_end", "the end-effector frame of Eq. 31"),
    Table("gpdm", "gpdm", tuple(
        [Setting(f.name, f.name, _GPDM_CHECKS[f.name], getattr(_GPDM_DEFAULTS, f.name),
                 _GPDM_DOCS.get(f.name, "")) for f in fields(GPDMSettings) if f.name in _GPDM_CHECKS]
        + [Setting("training_stride", "training_stride", integer(1), 1, _GPDM_DOCS["training_stride"])]),
        "GPDMSettings (latentoc.gpdm) and the training stride"),
), "the minimum-torque motion of a fixed-base robot (Sect. 4.1)")


def check_problem(problem: Problem, where: str) -> None:
    """Checks across settings: enough control points for the degree and the boundary, a goal's
    position with its frame, the files the robot and the training motion name, and sizes that
    fit in memory (:mod:`latentoc.sizes`)."""
    if (problem.goal_frame is None) != (problem.goal_position is None):
        raise ProblemError(f"{where}: [goal] needs both 'goal.frame' and 'goal.position'")
    check_problem_files(problem, where)
    m, k = problem.control_points, problem.spline_degree
    if m < k + 1:
        raise ProblemError(f"{where}: key 'latent.control_points' = {m} is fewer than spline_degree + 1 = {k + 1}")
    n_fixed = len(fixed_rows(max(m, 5), problem.boundary))
    if m <= n_fixed:
        raise ProblemError(f"{where}: key 'latent.control_points' = {m}: boundary \"{problem.boundary}\" fixes "
                           f"{n_fixed}, so at least {n_fixed + 1} are needed to leave one free")
    check_memory(spline_transcription_bytes(m, k, problem.quadrature_points, problem.constraint_points,
                                            problem.duration, problem.latent_dim),
                 {"latent.control_points": m, "transcription.constraint_points": problem.constraint_points,
                  "duration": problem.duration}, where)


def training_motion(problem: Problem, demo: Demonstration | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The problem's training motion (t, Q), subsampled by ``gpdm.training_stride``."""
    demo = problem_demonstration(problem) if demo is None else demo
    t, Q = demo.t, demo.Q
    idx = np.arange(0, len(t), problem.gpdm["training_stride"])
    if idx[-1] != len(t) - 1:
        idx = np.append(idx, len(t) - 1)  # keep the goal pose
    return np.asarray(t)[idx], np.asarray(Q)[idx]


def gpdm_settings(problem: Problem) -> GPDMSettings:
    """GPDMSettings from the problem's latent dimension and [gpdm] table."""
    kw = {k: v for k, v in problem.gpdm.items() if k != "training_stride"}
    return GPDMSettings(latent_dim=int(problem.latent_dim), **kw)


_GPDM_CACHE: dict[str, tuple[GPDM, float]] = {}  # learned once per process and settings


def problem_gpdm(problem: Problem) -> tuple[GPDM, float]:
    """The problem's GPDM and its learning time (s); learned once per training data + settings."""
    settings = gpdm_settings(problem)
    _, Q = training_motion(problem)
    key = model_path(Q, settings).name  # the disk cache's key: data and settings
    if key not in _GPDM_CACHE:
        t0 = time.perf_counter()
        model = learned_gpdm(Q, settings)
        _GPDM_CACHE[key] = (model, time.perf_counter() - t0)
    return _GPDM_CACHE[key]


def tube_reference(problem: Problem) -> float:
    """What a relative tube multiplies: tube_training of the problem's GPDM (Eq. 30)."""
    return problem_gpdm(problem)[0].tube_size()


def _time_grid(duration: float) -> np.ndarray:
    return np.linspace(0.0, duration, int(round(duration * TRAJECTORY_RATE_HZ)) + 1)


def _base_result(problem: Problem, method: str) -> dict[str, Any]:
    return {"problem": problem.name, "kind": problem.kind, "method": method,
            "quadrature": f"gauss-legendre, {problem.quadrature_points} nodes per knot interval"}


def _finish(result: dict[str, Any], nlp: MinTorqueNLP, res: IpoptResult, cost_initial: float,
            motion: dict[str, np.ndarray], motion_init_L: np.ndarray, t: np.ndarray) -> None:
    dt = float(t[1] - t[0])
    cost_fine = trapezoid_cost(motion["L"], dt)
    result.update({
        "status": res.status, "success": bool(res.success), "iterations": res.iterations,
        "cost_initial": cost_initial, "cost": res.f,
        "performance_gain_pct": 100.0 * (cost_initial - res.f) / cost_initial,
        "cost_meaning": nlp.objective.meaning,
        "cost_trapezoid_1ms": cost_fine, "cost_initial_trapezoid_1ms": trapezoid_cost(motion_init_L, dt),
        "quadrature_error": abs(res.f - cost_fine) / abs(cost_fine),
        "solve_time_s": res.time_s, "n_variables": int(nlp.w0.size), "n_constraints": int(nlp.lbg.size),
    })


def _limit_violations(settings: MinTorqueSettings, robot: pin.Model, motion: dict[str, np.ndarray]) -> dict[str, float]:
    """How far the 1 kHz motion leaves the joint (rad), velocity (rad/s) and torque limits (N m) and,
    with a goal, its position (m beyond the tolerance)."""
    out = settings.limits(robot).violations(motion)
    if settings.goal is not None:
        out["goal_m"] = max(0.0, goal_error(robot, settings.goal, motion["q"][-1]) - settings.goal.tolerance)
    return out


def _limit_arrays(nlp: MinTorqueNLP) -> dict[str, np.ndarray]:
    """The limits the NLP enforced, as trajectory arrays (q_min, q_max, v_max, tau_min, tau_max)."""
    lim, out = nlp.limits, dict[str, np.ndarray]()
    if lim.q_lo is not None and lim.q_hi is not None:
        out.update(q_min=lim.q_lo, q_max=lim.q_hi)
    if lim.v_max is not None:
        out["v_max"] = lim.v_max
    if lim.tau_max is not None:
        out.update(tau_min=-lim.tau_max, tau_max=lim.tau_max)
    return out


def _own_motion(problem: Problem, demo: Demonstration, settings: MinTorqueSettings, q: np.ndarray) -> dict:
    """The result's facts about the robot, the demonstration (and how far the motion's end poses q[0],
    q[-1] are from its first and last frames), the objective and the goal."""
    out = {"robot": describe_robot(problem.robot), "demonstration": demo.info(), "objective": settings.objective.name,
           "boundary_error_rad": {"start": float(np.max(np.abs(q[0] - demo.Q[0]))),
                                  "end": float(np.max(np.abs(q[-1] - demo.Q[-1])))}}
    if settings.goal is not None:
        out["goal"] = {"frame": settings.goal.frame, "position": list(settings.goal.position),
                       "tolerance": settings.goal.tolerance}
    return out


def _setup(problem: Problem, method: str) -> tuple[Demonstration, pin.Model, SymbolicModel, MinTorqueSettings]:
    """The demonstration, its (reduced) robot, the symbolic model and the transcription settings;
    a SolveError for a robot the kind cannot solve, an unknown goal frame or a bad limit list."""
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
    return demo, robot, SymbolicModel(robot), settings


def _run_ipopt(problem: Problem, nlp: MinTorqueNLP, x0: np.ndarray, verbose: bool) -> IpoptResult:
    options = ipopt_options(nlp, tol=problem.tol, max_iter=problem.max_iter, verbose=verbose)
    return ipopt.solve(nlp.nlp, x0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, options, hessian=problem.hessian,
                       desc=f"{problem.name} ({nlp.method})")


EXCHANGE_ROUNDS = 8


def _solve_exchanged(problem: Problem, nlp: MinTorqueNLP, rebuild, x0: np.ndarray, sym: SymbolicModel,
                     t: np.ndarray, verbose: bool) -> tuple[MinTorqueNLP, IpoptResult, list[dict], list[dict]]:
    """Solve, check the tube and the limits on the 1 kHz grid t, add the violated times to the NLP
    (``rebuild(extra)``) and resume from the point, until the grid holds (the exchange). Returns
    the last NLP and run, the rounds' summaries and each round's Ipopt history (``convergence``)."""
    rounds: list[dict] = []
    convergence: list[dict] = []
    while True:
        res = _run_ipopt(problem, nlp, x0, verbose)
        entry = {"iterations": res.iterations, "time_s": res.time_s, "status": res.status,
                 "grid_points": int(len(nlp.grid_t)), "torque_points": int(len(nlp.quad_t) + len(nlp.extra.torque))}
        rounds.append(entry)
        convergence.append(convergence_entry(nlp.method, len(rounds), res.history))
        if not res.success or len(rounds) >= EXCHANGE_ROUNDS:
            break
        P = nlp.control_points(res.x)
        motion = sampled_motion(nlp.layer, sym.model, nlp.path.spline, P, t, nlp.objective)
        layer = nlp.layer
        sigma2 = layer.variance(nlp.path.spline.evaluate(P, t))[0] \
            if isinstance(layer, GPLayer) and nlp.tube is not None else None
        add, worst = violated_times(nlp, motion, sigma2, t)
        entry["violation_1khz"] = worst
        if not add:
            break
        nlp, x0 = rebuild(nlp.extra.merged(add)), res.x
    return nlp, res, rounds, convergence


def solve_latent_min_torque(problem: Problem, *, method: str = "latent", joint_range_deg: float | None = None,
                            gpdm: GPDM | None = None, verbose: bool = False,
                            warm_start: Solution | None = None) -> Solution:
    """Minimum-torque motion (L = |tau|^2) in the GPDM latent space or, with
    ``method="joint-range"``, in the full configuration space (Sect. 4.1.1).

    ``warm_start``: a Solution whose latent control points (its ``warm["P"]``) Ipopt starts from
    instead of the training fit, used when it was solved at a tube no larger than this one;
    cost_initial and the gain still refer to the training fit."""
    if method not in METHODS:
        raise SolveError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    demo, robot, sym, settings = _setup(problem, method)
    if method == "joint-range":
        return _solve_joint_range(problem, demo, sym, settings, joint_range_deg, verbose)

    t_train, Q_train = training_motion(problem, demo)
    d = problem.latent_dim
    if not 1 <= d < Q_train.shape[1]:
        raise SolveError(f"latent dimension d = {d} must satisfy 1 <= d < D = {Q_train.shape[1]} "
                         "(the training data's dimension)")
    if gpdm is None:
        check_frames(demo, d, problem.gpdm["training_stride"])
    else:
        _check_given_gpdm(gpdm, problem, demo, Q_train)
    t0 = time.perf_counter()
    gp = problem_gpdm(problem)[0] if gpdm is None else gpdm
    gpdm_time = time.perf_counter() - t0

    t = _time_grid(settings.duration)
    spline = settings.spline()
    path = SplinePath.fit(spline, t_train, gp.latent_trajectories()[0], problem.boundary)
    P0 = path.P_init
    x0 = spline.evaluate(P0, t)
    tube_training = gp.tube_size()
    delta = resolve_tube(problem.tube, tube_training)
    end_s2 = max(float(gp.variance(P0[0])), float(gp.variance(P0[-1])))
    if delta < end_s2:
        raise SolveError(f"tube delta = {delta:.4g} is infeasible: the fixed start/end latent points already have "
                         f"sigma^2 = {end_s2:.4g}; the smallest feasible delta is {end_s2:.4g} "
                         f"({end_s2 / tube_training:.3g}x of tube_training = {tube_training:.4g})")
    warm = warm_start.warm if warm_start is not None and warm_start.warm else None
    initial_guess = warm["P"] if warm is not None and warm.get("tube", np.inf) <= delta else None
    if initial_guess is not None and np.shape(initial_guess) != P0.shape:
        raise SolveError(f"warm start has control points of shape {np.shape(initial_guess)}, this problem's "
                         f"are {P0.shape}")

    t1 = time.perf_counter()
    nlp = latent_nlp(gp, sym, settings, delta, path)
    cost_initial = nlp.cost(nlp.w0)
    build_time = time.perf_counter() - t1
    x_start = nlp.w0 if initial_guess is None else nlp.path.decision_vector(initial_guess)
    nlp, res, rounds, convergence = _solve_exchanged(problem, nlp, lambda extra: latent_nlp(gp, sym, settings, delta, path,
                                                                               extra=extra), x_start, sym, t, verbose)

    P = nlp.control_points(res.x)
    x = spline.evaluate(P, t)
    motion = sampled_motion(nlp.layer, robot, spline, P, t, settings.objective)
    init = sampled_motion(nlp.layer, robot, spline, P0, t, settings.objective)
    sigma2 = gp.variance(x)
    result = _base_result(problem, "latent")
    result.update({"latent_dim": int(d), "n_training_frames": int(len(t_train)),
                   "tube_spec": problem.tube, "tube": delta, "tube_relative": delta / gp.noise_variance,
                   "noise_variance": gp.noise_variance, "tube_training": tube_training,
                   "tube_initial": float(np.max(gp.variance(x0))), "max_sigma2": float(np.max(sigma2)),
                   "max_tube_violation": max(0.0, float(np.max(sigma2)) - delta),
                   "violations": {"tube": max(0.0, float(np.max(sigma2)) - delta),
                                  **_limit_violations(settings, robot, motion)},
                   "build_time_s": build_time, "gpdm_time_s": gpdm_time, "warm_start": initial_guess is not None,
                   **gp.learning_summary(),
                   "exchange_rounds": rounds, "convergence": convergence,
                   **_own_motion(problem, demo, settings, motion["q"])})
    _finish(result, nlp, res, cost_initial, motion, init["L"], t)
    result["iterations"] = sum(r["iterations"] for r in rounds)
    result["solve_time_s"] = sum(r["time_s"] for r in rounds)
    trajectory = {"t": t, "q": motion["q"], "v": motion["v"], "a": motion["a"], "tau": motion["tau"],
                  "x": x, "x_initial": x0, "P": P, "P_initial": P0, "q_initial": init["q"], "sigma2": sigma2,
                  "model": np.str_(robot.saveToString()), **_limit_arrays(nlp)}
    return Solution(result=result, trajectory=trajectory, warm={"P": P, "tube": delta} if res.success else None,
                    gpdm=gp)


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


def _solve_joint_range(problem: Problem, demo: Demonstration, sym: SymbolicModel, settings: MinTorqueSettings,
                       joint_range_deg: float | None, verbose: bool) -> Solution:
    k = problem.joint_range_deg if joint_range_deg is None else joint_range_deg
    if isinstance(k, bool) or not isinstance(k, (int, float, np.floating)) or not np.isfinite(k) or k <= 0:
        raise SolveError(f"joint range must be a positive number of degrees, got {k!r}")
    t_train, Q_train, robot = demo.t, demo.Q, demo.model  # all frames: no GPDM here
    t = _time_grid(settings.duration)
    t0 = time.perf_counter()
    nlp = joint_range_nlp(sym, settings, np.asarray(t_train), np.asarray(Q_train), float(k))
    cost_initial = nlp.cost(nlp.w0)
    build_time = time.perf_counter() - t0
    nlp, res, rounds, convergence = _solve_exchanged(problem, nlp, lambda extra: joint_range_nlp(
        sym, settings, np.asarray(t_train), np.asarray(Q_train), float(k), extra=extra), nlp.w0, sym, t, verbose)
    P, P0, spline = nlp.control_points(res.x), nlp.path.P_init, nlp.path.spline
    motion = sampled_motion(nlp.layer, robot, spline, P, t, settings.objective)
    init = sampled_motion(nlp.layer, robot, spline, P0, t, settings.objective)
    result = _base_result(problem, "joint-range")
    result.update({"joint_range_deg": float(k), "n_training_frames": int(len(t_train)),
                   "build_time_s": build_time, "gpdm_time_s": 0.0, "warm_start": False,
                   "violations": _limit_violations(settings, robot, motion), "exchange_rounds": rounds,
                   "convergence": convergence,
                   **_own_motion(problem, demo, settings, motion["q"])})
    _finish(result, nlp, res, cost_initial, motion, init["L"], t)
    result["iterations"] = sum(r["iterations"] for r in rounds)
    result["solve_time_s"] = sum(r["time_s"] for r in rounds)
    trajectory = {"t": t, "q": motion["q"], "v": motion["v"], "a": motion["a"], "tau": motion["tau"],
                  "P": P, "P_initial": P0, "q_initial": init["q"], "model": np.str_(robot.saveToString()),
                  **_limit_arrays(nlp)}
    return Solution(result=result, trajectory=trajectory)


SOLVERS["latent-min-torque"] = solve_latent_min_torque
