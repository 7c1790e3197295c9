"""The ``"broad-jump"`` problem kind: its problem schema, set-up from the training data, solve, result.

:data:`SCHEMA` declares the keys of a broad-jump problem file: the ``[options]`` table is
:class:`~.settings.JumpSettings` (its fields, types and defaults; ``mu`` is the file's
``friction``; :data:`RANGES` adds the ranges) and the set-up's own keys (:data:`SETUP_OPTIONS`).
:func:`setup` learns the GPDM on the symmetric training jump (37 learned DOF; or every jump of
the take), estimates the phases, the heel point and the torque limits, and fits the training
start. :func:`solve_jump_problem` is the broad jump's solve (:mod:`.kind`).
"""
from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from dataclasses import asdict, dataclass, field, fields
from functools import cached_property
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.mocap.symmetry import SymmetryMap
from latentoc.errors import ProblemError, SolveError
from latentoc.gpdm import GPDM, GPDMSettings, cached_gpdm
from latentoc.latent.gp_layer import GPLayer, IdentityLayer, Layer
from latentoc.nlp.blocks import RobotBlock, compile_blocks
from latentoc.problem.kinds import Solution, joint_range
from latentoc.motions.problem_inputs import problem_dir
from latentoc.problem.declaration import Problem, apply_overrides
from latentoc.problem.schema import Check, Schema, Setting, Table, boolean, choice, integer, list_of, number, optional
from latentoc.latent.tube import TUBE, relative_tube, tube_delta
from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.closure.planted_legs import LegClosure
from latentoc.jump.demonstration.planted import PlantedTraining, learned_leg, plantable, planted_training
from latentoc.jump.robot.feet import POINTS, FootGeometry
from latentoc.jump.schedule.path import (METHODS, PATH_SMOOTHING, JumpPath, initial_latent_path, joint_range_path,
                                         latent_path, leg_residual_path)
from latentoc.jump.schedule.phases import SCHEDULE_ORDER, Phases, toe_path, training_phases
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.rows import row_blocks
from latentoc.jump.settings import FIELD_DOCS, JumpSettings
from latentoc.jump.solve.solve import JumpSolution, solve_jump
from latentoc.jump.robot.torque_limits import TorqueLimits, TrainingDynamics, estimate_training_dynamics, urdf_torque_limits
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID, ROBOT_KEYS, RobotDeclaration, declaration, robot_model
from latentoc.jump.demonstration.training import JumpTraining, antisymmetric_centre, motion_training, training_jumps

__all__ = ["JumpSetup", "setup", "solve_jump_problem", "solve_from_starts", "usable_warm_start",
           "settings_from_problem", "SCHEMA", "OPTIONS", "RANGES", "SETUP_OPTIONS", "tube_reference"]



@dataclass(eq=False)
class JumpSetup:
    """Everything the NLP needs from the training data."""

    model: pin.Model
    smap: SymmetryMap
    training: JumpTraining
    gpdm: GPDM
    phases: Phases
    geom: FootGeometry
    limits: TrainingDynamics | TorqueLimits
    init: dict
    distance_training: float
    sym: SymbolicModel
    planted: PlantedTraining | None = None  # what planting the feet changed in the captured jump
    joint_limits: bool = False  # the model's joint position and velocity limits held (``limits = "urdf"``)
    _blocks: dict = field(default_factory=dict, repr=False)

    @cached_property
    def closure(self) -> LegClosure:
        """The planted foot of the training's standing pose (:mod:`.closure.planted_legs`)."""
        return LegClosure.of(self.sym, self.smap, self.geom, self.training.Q[0])

    def robot(self, mu: float) -> JumpRobot:
        return JumpRobot(self.sym, self.smap, self.geom, self.limits, mu, float(sum(i.mass for i in self.model.inertias)),
                         joint_limits=self.joint_limits, closure=self.closure)

    def blocks(self, robot: JumpRobot, layer: Layer | None = None) -> dict[str, RobotBlock]:
        """The row families' blocks for ``layer`` (default: the GP layer's latent dimension),
        compiled (or found in the disk cache) once per set-up, mu and layer kind."""
        joint_space = isinstance(layer, IdentityLayer)
        d = self.gpdm.latent_dim if layer is None else layer.latent_dim
        key = (robot.mu, d, joint_space)
        if key not in self._blocks:
            blocks = row_blocks(robot, d, joint_space)
            compile_blocks(list(blocks.values()))
            self._blocks[key] = blocks
        return self._blocks[key]


def setup(training: str | int = 0, latent_dim: int = 3, n_control: int = 27, torque_margin: float = 0.1,
          gpdm_settings: GPDMSettings | None = None, path_smoothing: float = PATH_SMOOTHING,
          torque_floor: float = 5.0, stride: int = 1, plant: bool = False,
          robot: RobotDeclaration = CMU_HUMANOID, base_dir: Path = Path("."),
          schedule: dict[str, float] | None = None) -> JumpSetup:
    """Model, GPDM, phases, feet, torque limits and training start. ``stride``: the GPDM learns
    every ``stride``-th captured frame (120 Hz) of each jump; ``plant``: the jumps' feet planted
    first (:mod:`.demonstration.planted`; of "all", the jumps whose contact schedule is whole); ``robot``: the
    problem's ``[robot]`` (:mod:`.robot.robot_declaration`), its motion relative to ``base_dir``; ``schedule``:
    contact times that replace the detected ones (:func:`.schedule.phases.training_phases`)."""
    model, smap = robot_model(robot)
    if robot.motion:
        if training == "all":
            raise ProblemError("[options] training_jumps = \"all\" chooses every jump of the CMU humanoid's take 01_01; "
                               "with key 'robot.motion' that motion is the training")
        trs = [motion_training(base_dir / robot.motion, model, smap, robot)]
    elif robot.model == CMU_HUMANOID.model:
        trs = training_jumps(training, robot)
    else:
        raise ProblemError(f"key 'robot.motion': {robot.model!r} needs its own demonstration of the jump, an NPZ "
                           "of t and q such as `python -m latentoc retarget` writes (docs/retargeting.md)")
    planted = None
    if plant:
        geom0 = robot.geometry(model, trs[0].Q[0])
        schedules = [training_phases(model, c, geom0, declared=schedule) for c in trs]
        if not plantable(schedules[0]):
            raise ProblemError("[options] plant_training: the training jump's contact schedule is not whole "
                               "(heel, ball, takeoff, touchdown)")
        cleaned = [planted_training(model, smap, c, ph, geom0) for c, ph in zip(trs, schedules) if plantable(ph)]
        trs, planted = [c.training for c in cleaned], cleaned[0]
    tr = trs[0]
    if not (isinstance(stride, (int, np.integer)) and not isinstance(stride, bool) and 1 <= stride <= len(tr.t) // 4):
        raise ProblemError(f"[options] training_stride: must be an integer from 1 to {len(tr.t) // 4} (frames), "
                           f"got {stride!r}")
    Ys = [t.Y[::stride] for t in trs]
    gp = cached_gpdm(Ys if len(trs) > 1 else Ys[0], gpdm_settings or GPDMSettings(latent_dim=latent_dim))
    geom = robot.geometry(model, tr.Q[0])
    # a planted jump keeps the schedule it was planted to: its feet are planted exactly then
    phases = schedules[0] if planted is not None else training_phases(model, tr, geom, declared=schedule)
    contact = phases.on_ground(tr.t)
    loaded = np.column_stack([phases.loaded(k, tr.t) for k in POINTS])
    limits: TrainingDynamics | TorqueLimits = estimate_training_dynamics(
        model, smap, tr, geom, contact, margin=torque_margin, loaded=loaded, floor=torque_floor) \
        if robot.limits == "training" else urdf_torque_limits(model)
    X = gp.latent_trajectories()[0]
    spline = phases.latent_spline(n_control)
    P = initial_latent_path(spline, tr.t[::stride], X, path_smoothing, np.array([phases.takeoff, phases.touchdown]))
    # the full-space baseline's start: the least-squares fit of the training joints (every frame);
    # unsmoothed, its accelerations are already below the latent start's joint motion's
    P_joint = spline.fit(tr.t, tr.Y)
    bx = toe_path(model, tr.Q, geom)[:, 0]
    td = int(np.argmin(np.abs(tr.t - phases.touchdown)))
    init = {"P": P, "P_joint": P_joint, "t": tr.t, "base": tr.base, "x_L": float(np.median(bx[td:]))}
    return JumpSetup(model, smap, tr, gp, phases, geom, limits, init, float(np.median(bx[td:]) - bx[0]),
                     SymbolicModel(model), planted, joint_limits=robot.limits == "urdf")


# ------------------------------------------------------------------ the problem file
SWEEP_STARTS = ("warm+cold", "warm")  # a tube after a solved smaller one: both starts, or warm only

#: the ``[options]`` the set-up and the solve read themselves (not JumpSettings fields): key -> (check, default, doc)
SETUP_OPTIONS: dict[str, tuple[Check, Any, str]] = {
    "training_jumps": (choice("one", "all"), "one", '"one" (the paper) or "all" (every jump of take 01_01)'),
    "training_stride": (integer(1), 1, "the GPDM learns every k-th captured frame (120 Hz)"),
    "torque_margin": (number(0), 0.1, "torque limits widened by this fraction of each joint's peak |tau|"),
    "torque_floor": (number(0), 5.0, "... and by at least this many N m"),
    "plant_training": (boolean(), False, "plant the training jump's feet before learning (least joint change)"),
    "sweep_starts": (choice(*SWEEP_STARTS), SWEEP_STARTS[0],
                     "a tube after a solved smaller one: solved warm and cold (the better kept), or warm"),
    "leg_residual": (number(0.0), 0.0, "deg: a bounded residual on the legs' sagittal joints beside the latent path "
                                        "(0: none)"),
}
#: JumpSettings fields set by other tables of the file, not by [options]
_ELSEWHERE = {"tube": "latent.tube", "n_control": "latent.control_points", "hessian": "solver.hessian",
              "max_iter": "solver.max_iter", "tol": "solver.tol"}
_TOML_NAMES = {"mu": "friction"}  # JumpSettings field -> its [options] key
#: ranges of the JumpSettings fields in [options] (lo, hi, lo_open); a field not listed has its type only
RANGES: dict[str, tuple[float | None, float | None, bool]] = {
    "mu": (0.0, None, True), "n_stance": (2, None, False), "n_flight": (2, None, False), "n_land": (2, None, False),
    "sample_spacing": (0.0, None, False)}


def _field_check(name: str, type_name: str) -> Check:
    lo, hi, lo_open = RANGES.get(name, (None, None, False))
    if type_name == "bool":
        return boolean()
    if type_name == "int":
        return integer(None if lo is None else int(lo), None if hi is None else int(hi))
    if type_name == "float":
        return number(lo, hi, lo_open)
    raise TypeError(f"JumpSettings.{name}: no [options] check for type {type_name}")


_DEFAULTS = JumpSettings()
#: [options] key -> the JumpSettings field it sets (None: read by the set-up)
OPTIONS: dict[str, str | None] = {**{k: None for k in SETUP_OPTIONS},
                                  **{_TOML_NAMES.get(f.name, f.name): f.name for f in fields(JumpSettings)
                                     if f.name not in _ELSEWHERE}}

#: the keys of a broad-jump problem file
SCHEMA = Schema("broad-jump", (
    Setting("latent.dim", "latent_dim", integer(1), 3, "latent dimension d"),
    Setting("latent.control_points", "control_points", integer(4), _DEFAULTS.n_control,
            "latent spline control points m (paper 11: too few for the push-off)"),
    Setting("latent.tube", "tube", TUBE, _DEFAULTS.tube, 'delta (units of sigma^2, Eq. 29) or "<k>x" times '
            "tube_training"),
    Setting("solver.hessian", "hessian", choice("exact", "lbfgs"), _DEFAULTS.hessian, "Ipopt's Hessian"),
    Setting("solver.max_iter", "max_iter", integer(1), _DEFAULTS.max_iter, "Ipopt iterations per phase"),
    Setting("solver.tol", "tol", number(0, lo_open=True), _DEFAULTS.tol, "Ipopt tolerance"),
    Setting("sweep.tubes", "sweep_tubes", list_of(TUBE), [_DEFAULTS.tube], "the sweep's tubes"),
    Setting("sweep.ranges", "sweep_ranges", list_of(number(0, lo_open=True)), [30.0],
            "the baseline sweep's joint ranges, deg (sweep --baseline joint-range)"),
    Setting("baseline.joint_range_deg", "joint_range_deg", number(0, lo_open=True), 30.0,
            "full-space baseline (method joint-range): +-deg around the training joints' fit"),
    *[Setting(f"robot.{k}", f"robot_{k}", c, d, doc) for k, (c, d, doc) in ROBOT_KEYS.items()],
    *[Setting(f"schedule.{k}", f"schedule_{k}", optional(number(0, lo_open=True)), None,
              f"s: the {k.replace('_', ' ')} time (none: detected from the training motion)") for k in SCHEDULE_ORDER],
    Table("options", "options", tuple(
        [Setting(k, k, c, d, doc) for k, (c, d, doc) in SETUP_OPTIONS.items()]
        + [Setting(_TOML_NAMES.get(f.name, f.name), _TOML_NAMES.get(f.name, f.name),
                   _field_check(f.name, f.type if isinstance(f.type, str) else f.type.__name__), getattr(_DEFAULTS, f.name), FIELD_DOCS[f.name])
           for f in fields(JumpSettings) if f.name not in _ELSEWHERE]),
        "the set-up's keys and the JumpSettings fields (latentoc/jump/settings.py)"),
), "the CMU humanoid's standing broad jump (Sect. 4.2)")


def check_options(problem: Problem) -> None:
    """The problem's ``[options]`` checked again (they were at load; a SolveError if changed since)."""
    try:
        SCHEMA.checked({"options": problem.options}, f"problem {problem.name!r}")
    except ProblemError as exc:
        raise SolveError(str(exc)) from None


def settings_from_problem(problem: Problem, tube: float, hessian: str | None = None) -> JumpSettings:
    """JumpSettings of a problem at tube delta ``tube`` (``[options]`` as :data:`OPTIONS` maps them)."""
    check_options(problem)
    kw = {name: problem.options[key] for key, name in OPTIONS.items() if name is not None}
    return JumpSettings(tube=float(tube), n_control=int(problem.control_points), max_iter=int(problem.max_iter),
                        tol=float(problem.tol), hessian=hessian or problem.hessian, **kw)


_SETUP_CACHE: dict[tuple[Any, ...], JumpSetup] = {}  # one set-up per process and training settings


def problem_setup(problem: Problem) -> JumpSetup:
    """The problem's set-up (:func:`setup`), made once per process for its training settings."""
    o = problem.options
    training: str | int = "all" if o["training_jumps"] == "all" else 0
    robot, base_dir = declaration(problem.settings), problem_dir(problem)
    schedule = {k: problem.settings[f"schedule_{k}"] for k in SCHEDULE_ORDER
                if problem.settings[f"schedule_{k}"] is not None}
    key = (training, problem.latent_dim, problem.control_points, o["torque_margin"], o["torque_floor"],
           o["training_stride"], o["plant_training"], robot, base_dir, tuple(sorted(schedule.items())))
    if key not in _SETUP_CACHE:
        try:
            _SETUP_CACHE[key] = setup(training, problem.latent_dim, problem.control_points, o["torque_margin"],
                                      torque_floor=o["torque_floor"], stride=o["training_stride"],
                                      plant=o["plant_training"], robot=robot, base_dir=base_dir,
                                      schedule=schedule)
        except ProblemError as exc:
            raise SolveError(f"problem {problem.name!r}, {exc}") from None
    return _SETUP_CACHE[key]


def tube_reference(problem: Problem) -> float:
    """What a relative tube multiplies: tube_training of the set-up's GPDM (Eq. 30)."""
    return problem_setup(problem).gpdm.tube_size()


def _better(a: dict, b: dict) -> bool:
    """Whether result ``a`` is a better jump than ``b``: converged first, then farther."""
    return (a["success"], a["distance"]) > (b["success"], b["distance"])


def usable_warm_start(warm_start: Solution | None, delta: float) -> dict | None:
    """What a Solution of this problem at another tube offers a solve at tube ``delta``: its
    ``warm`` when it was solved at a tube no larger than delta, else None."""
    if warm_start is not None and warm_start.warm and warm_start.warm.get("tube", np.inf) <= delta:
        return warm_start.warm
    return None


def solve_from_starts(solve: Callable[[dict | None], JumpSolution], warm: dict | None,
                      sweep_starts: str = SWEEP_STARTS[0]) -> JumpSolution:
    """``solve(warm)``; with a warm start, also ``solve(None)`` (from the training fit) when
    ``sweep_starts`` is "warm+cold" or the warm solve failed: a warm start can stay in a worse
    local optimum than a cold one. The better jump is kept, the other reported in its result's
    ``other_start``."""
    sol = solve(warm)
    if warm is not None and (sweep_starts == "warm+cold" or not sol.result["success"]):
        cold = solve(None)
        sol, other = (cold, sol) if _better(cold.result, sol.result) else (sol, cold)
        ro = other.result
        sol.result["other_start"] = {"warm_start": ro["warm_start"],
                                     "solve_time_s": ro["times"]["solve_s"],
                                     **{k: ro[k] for k in ("status", "iterations", "distance")}}
    return sol


def _violations(r: dict[str, Any], checks: dict[str, float], mu: float) -> dict[str, float]:
    """The 1 kHz checks as amounts beyond each limit (0: held): tube, torque (N m), friction ratio,
    point cones (body weights), centre of pressure, ZMP and COM outside their polygons (m), joint
    positions (rad) and velocities (rad/s) beyond the model's limits."""
    cop = checks.get("cop_margin_loaded", checks["cop_margin"])
    return {"tube": r["max_tube_violation"], "torque_nm": checks["max_torque_violation"],
            "friction_ratio": max(0.0, checks["max_friction_ratio"] - mu),
            "point_cone_bw": checks["max_point_cone_violation"], "cop_m": max(0.0, -cop),
            "zmp_m": max(0.0, -checks["zmp_margin"]), "com_m": max(0.0, -checks["com_margin"]),
            "dynamics_bw": checks["max_dynamics_residual"], "joint_limit_rad": checks["max_joint_limit_violation"],
            "velocity_rad_s": checks["max_velocity_violation"]}


def _training_on(js: JumpSetup, t: np.ndarray) -> np.ndarray:
    """The training jump's configurations at times t (linear in its coordinates): the initial motion
    a view and the plots show beside the optimised one."""
    tr = js.training
    Z = np.column_stack([tr.base, tr.Y])
    Zt = np.column_stack([np.interp(t, tr.t, Z[:, j]) for j in range(Z.shape[1])])
    return js.smap.to_full(Zt[:, 3:], base_to_freeflyer(Zt[:, :3])[0])


def _joint_range(problem: Problem, method: str, joint_range_deg: float | None) -> float | None:
    """The joint range (deg) of ``method`` (None for the latent path); a SolveError for an unknown
    method or a bad range, before any work."""
    if method not in METHODS:
        raise SolveError(f"unknown method {method!r} for broad-jump; choose one of {', '.join(METHODS)}")
    if method == "latent":
        return None
    return joint_range(problem, joint_range_deg)


def jump_path(js: JumpSetup, leg_residual: float, joint_range_deg: float | None = None) -> JumpPath:
    """The path a solve optimises: the joints within +-``joint_range_deg`` of the training fit (the
    full-space baseline), or the latent path with the left leg's sagittal joints (not the closure's)
    given a residual of +-``leg_residual`` deg, or the latent path alone (:mod:`.schedule.path`)."""
    if joint_range_deg is not None:
        return joint_range_path(js.init["P_joint"], joint_range_deg, antisymmetric_centre(js.smap))
    if leg_residual > 0:
        sagittal = [j for j in learned_leg(js.model, js.smap, js.geom) if j not in js.closure.dependent]
        return leg_residual_path(js.gpdm, js.init["P"], sagittal, leg_residual)
    return latent_path(GPLayer(js.gpdm), js.init["P"])


def solve_jump_problem(problem: Problem, *, method: str = "latent", joint_range_deg: float | None = None,
                       gpdm: GPDM | None = None, verbose: bool = False, warm_start: Solution | None = None,
                       **overrides: Any) -> Solution:
    """Solve, check on 1 kHz, return a :class:`latentoc.problem.kinds.Solution`. ``method``: ``"latent"``,
    or ``"joint-range"`` (the 37 joints as the spline, within +-``joint_range_deg`` of the training
    fit; default the problem's ``baseline.joint_range_deg``; no tube, no warm start). ``warm_start``:
    the Solution of this problem at a smaller tube (the sweep's previous one); with ``sweep_starts =
    "warm+cold"`` the tube is also solved from the training fit and the better jump kept.
    ``overrides`` (tube, control_points, ...) change the problem's settings first."""
    from latentoc.jump.check.verify import verify

    problem = apply_overrides(problem, overrides)
    k = _joint_range(problem, method, joint_range_deg)
    o = problem.options
    t0 = time.perf_counter()
    js = problem_setup(problem)
    gpdm_time = time.perf_counter() - t0
    path = jump_path(js, o["leg_residual"], k)
    delta = tube_delta(problem.tube, js.gpdm)
    s = settings_from_problem(problem, delta)
    robot = js.robot(s.mu)
    t1 = time.perf_counter()
    blocks = js.blocks(robot, path.layer)
    compile_time = time.perf_counter() - t1
    start = {**js.init, "P": path.P, "P_range": path.P_range}
    warm = usable_warm_start(warm_start, delta) if path.has_tube else None
    sol = solve_from_starts(lambda w: solve_jump(robot, path.layer, blocks, js.phases, s, start, js.model, warm=w,
                                                 verbose=verbose), warm, o["sweep_starts"])
    t2 = time.perf_counter()
    traj = sol.trajectory
    checks = verify(js.model, traj, s.mu, checked=sol.series)
    verify_time = time.perf_counter() - t2
    r = sol.result
    r.update({"problem": problem.name, "kind": problem.kind, "method": method, "distance_initial": js.distance_training,
              "performance_gain_pct": 100.0 * (r["distance"] - js.distance_training) / js.distance_training,
              "control_points": s.n_control, "gpdm_time_s": gpdm_time, "compile_time_s": compile_time,
              "build_time_s": sol.result["times"]["build_s"], "solve_time_s": sol.result["times"]["solve_s"],
              "check_time_s": sol.result["times"]["check_s"] + verify_time,
              "cost_initial": js.distance_training, "cost": r["distance"],
              "cost_meaning": "jump distance of the toe tip in metres (maximised, Eq. 33)",
              "friction": s.mu, "restitution_paper": 0.5, "restitution_used": 0.0, "quadrature_error": 0.0,
              "jump_settings": asdict(s)})
    if path.has_tube:
        r.update({"tube_spec": problem.tube, "training_points": int(js.gpdm.X.shape[0]),
                  "tube_training": js.gpdm.tube_size(), "tube_relative": relative_tube(delta, js.gpdm),
                  "latent_dim": js.gpdm.latent_dim, "max_sigma2": float(np.max(traj["sigma2"])),
                  "max_tube_violation": max(0.0, float(np.max(traj["sigma2"])) - delta), **js.gpdm.learning_summary()})
    else:  # the joints are the spline: no tube, no GPDM in the solve
        assert path.P_range is not None
        r.update({"tube": None, "joint_range_deg": k, "joints": int(path.layer.latent_dim),
                  "fixed_joints": int(np.sum(np.all(path.P_range == 0, axis=0))), "max_tube_violation": 0.0})
    r.update(checks)
    if js.planted is not None:  # the training jump's change by planting, largest per joint (deg)
        r["training_planting_deg"] = js.planted.change_deg
    r["violations"] = _violations(r, checks, s.mu)
    traj["q_initial"] = _training_on(js, traj["t"])
    traj["P"] = traj.pop("control_points")  # the result schema's names
    if "latent" in traj:
        traj["x"] = traj.pop("latent")
    r["total_time_s"] = time.perf_counter() - t0
    warm_out = sol.warm_start() if r["success"] and path.has_tube else None
    return Solution(result=r, trajectory=traj, warm=warm_out, gpdm=js.gpdm if path.has_tube else None)
