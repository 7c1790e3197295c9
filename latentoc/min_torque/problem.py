"""The problem file of the ``"latent-min-torque"`` kind: its keys (:data:`SCHEMA`) and their checks.

An arm problem file (``problems/arm-raise.toml``) names the robot and the training motion
(registered names or the user's own files, :mod:`latentoc.motions.problem_inputs`: any
fixed-base robot, its motion read from CSV, NPZ or ASF + AMC, the robot reduced to the joints
the motion moves), the duration, ``[objective]`` (the running cost, :mod:`.objectives`),
``[latent]`` (d, the spline and the tube, :mod:`latentoc.latent.tube`), ``[transcription]`` (node
densities; the joint, velocity and torque limits, :mod:`.limits`), ``[goal]`` (an end-effector
goal, :mod:`.goal`), ``[solver]``, the baseline's joint range, the sweep's tubes, the start
poses of Sect. 4.1.4 and ``[gpdm]`` (:class:`~latentoc.gpdm.GPDMSettings`). The measured GPDM
settings of arm-raise are in docs/arm-raise.md.
"""
from __future__ import annotations

from dataclasses import fields

from latentoc.errors import ProblemError
from latentoc.gpdm import GPDMSettings
from latentoc.motions import TRAINING
from latentoc.motions.problem_inputs import check_problem_files
from latentoc.nlp.ipopt import HESSIANS
from latentoc.problem.declaration import Problem
from latentoc.robots import ROBOT
from latentoc.problem.schema import Check, Schema, Setting, Table, boolean, choice, integer, list_of, number, optional, text
from latentoc.problem.sizes import check_memory, spline_transcription_bytes
from latentoc.latent.spline_path import fixed_rows
from latentoc.latent.tube import TUBE
from latentoc.min_torque.objectives import RUNNING_COSTS, Objective
from latentoc.min_torque.settings import MinTorqueSettings

__all__ = ["SCHEMA", "check_problem"]


def _torque_limits(v: object) -> str | list[float]:
    if v == "urdf":
        return "urdf"
    return list_of(number(0, lo_open=True)).convert(v)


def _position(v: object) -> list[float]:
    if not isinstance(v, (list, tuple)) or len(v) != 3:
        raise ValueError
    return [number().convert(x) for x in v]


def check_problem(problem: Problem, where: str) -> None:
    """Checks across settings: enough control points for the degree and the boundary, a goal's
    position with its frame, the files the robot and the training motion name, and sizes that
    fit in memory (:mod:`latentoc.problem.sizes`)."""
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


_GPDM_DEFAULTS = GPDMSettings()
_GPDM_CHECKS = {"balanced": boolean(), "ftol": number(0, lo_open=True), "max_iterations": integer(1),
                "seed": integer(), "init": choice("pca", "random"), "kappa_sq": number(0, lo_open=True),
                "log_hyper_bound": number(0, lo_open=True)}
_GPDM_DOCS = {"balanced": "balanced GPDM: the dynamics term of Eq. 16 times D/d (Urtasun et al. 2006)",
              "ftol": "convergence: the Newton decrement of Eq. 16 <= ftol |Eq. 16|",
              "max_iterations": "Newton iterations at most (a safety cap: then reported not converged)",
              "seed": 'random start\'s seed (init = "random" only)',
              "init": 'latent start: "pca" (scores of the principal components) or "random"',
              "kappa_sq": "variance of the N(0, kappa^2) prior on the per-dimension scales W",
              "log_hyper_bound": "|ln alpha_i|, |ln beta_i| at most this (a hyperparameter there: not converged)",
              "training_stride": "learn on every k-th training frame (the last one always kept)"}
_SPLINE = MinTorqueSettings(duration=1.0)  # the transcription's defaults

#: the keys of a latent-min-torque problem file
SCHEMA = Schema("latent-min-torque", (
    Setting("robot", "robot", ROBOT, doc="a latentoc.load_robot name or a table naming a URDF (or an ASF skeleton)"),
    Setting("training", "training", TRAINING, doc="a registered motion or a table naming a CSV, NPZ or AMC file"),
    Setting("duration", "duration", optional(number(0, lo_open=True)), None,
            "s (Table 1); none: the training motion's"),
    Setting("objective.cost", "objective", choice(*RUNNING_COSTS), "torque",
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
), "the minimum-torque motion of a fixed-base robot (Sect. 4.1)", check=check_problem)
