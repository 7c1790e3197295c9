"""The ``"broad-jump"`` problem kind: set-up from the training data, settings, solve, result.

:func:`setup` learns the GPDM on the symmetric training jump (37 learned DOF; or every jump of
the take), estimates the phases, the heel point and the torque limits, and fits the training
start. :func:`solve_jump_problem` is ``latentoc.solve.SOLVERS["broad-jump"]``.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, fields
from typing import Callable

import numpy as np
import pinocchio as pin

from ..dynamics import SymbolicModel
from ..gpdm import GPDM, GPDMSettings, learn_gpdm
from ..latent.gp_layer import GPLayer
from ..nlp.blocks import RobotBlock, compile_blocks
from ..spline import BSpline
from .contact import FootGeometry, foot_points
from .export import trajectory
from .phases import Phases, training_phases
from .robot import JumpRobot
from .rows import row_blocks
from .settings import JumpSettings
from .solve import JumpSolution, solve_jump
from .torque_limits import TrainingDynamics, estimate_training_dynamics
from .training import JumpTraining, jump_model, training_jumps

__all__ = ["JumpSetup", "setup", "solve_jump_problem", "solve_from_starts", "usable_warm_start",
           "settings_from_problem", "OPTIONS"]

PATH_SMOOTHING = 1e-3  # weight of int ||x''||^2 dt in the initial latent path fit


@dataclass(eq=False)
class JumpSetup:
    """Everything the NLP needs from the training data."""

    model: pin.Model
    smap: object
    training: JumpTraining
    gpdm: GPDM
    phases: Phases
    geom: FootGeometry
    limits: TrainingDynamics
    init: dict
    distance_training: float
    sym: SymbolicModel
    _blocks: dict = field(default_factory=dict, repr=False)

    def robot(self, mu: float) -> JumpRobot:
        return JumpRobot(self.sym, self.smap, self.geom, self.limits, mu, float(sum(i.mass for i in self.model.inertias)))

    def blocks(self, robot: JumpRobot) -> dict[str, RobotBlock]:
        """The row families' blocks, compiled (or found in the disk cache) once per set-up and mu."""
        if robot.mu not in self._blocks:
            blocks = row_blocks(robot, self.gpdm.latent_dim)
            compile_blocks(list(blocks.values()))
            self._blocks[robot.mu] = blocks
        return self._blocks[robot.mu]


def _toe_x(model: pin.Model, Q: np.ndarray, geom: FootGeometry) -> np.ndarray:
    d = model.createData()
    out = np.zeros(len(Q))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, d, q)
        out[i] = foot_points(model, d, geom)[0, 2]
    return out


def setup(training: str | int = 0, latent_dim: int = 3, n_control: int = 21, torque_margin: float = 0.1,
          gpdm_settings: GPDMSettings | None = None, path_smoothing: float = PATH_SMOOTHING,
          torque_floor: float = 5.0, stride: int = 1) -> JumpSetup:
    """Model, GPDM, phases, feet, torque limits and training start. ``stride``: the GPDM learns
    every ``stride``-th captured frame (120 Hz) of each jump."""
    model, smap = jump_model()
    trs = training_jumps(training)
    tr = trs[0]
    if not (isinstance(stride, (int, np.integer)) and not isinstance(stride, bool) and 1 <= stride <= len(tr.t) // 4):
        raise ValueError(f"training stride must be an integer from 1 to {len(tr.t) // 4} (frames), got {stride!r}")
    Ys = [t.Y[::stride] for t in trs]
    gp = learn_gpdm(Ys if len(trs) > 1 else Ys[0], gpdm_settings or GPDMSettings(latent_dim=latent_dim))
    geom = FootGeometry.from_standing(model, tr.Q[0])
    phases = training_phases(model, tr, geom=geom)
    contact = (tr.t <= phases.takeoff + 1e-9) | (tr.t >= phases.touchdown - 1e-9)
    loaded = np.column_stack([phases.loaded(k, tr.t) for k in ("heel", "ball", "toe")])
    limits = estimate_training_dynamics(model, smap, tr, geom, contact, margin=torque_margin, loaded=loaded,
                                        floor=torque_floor)
    X = gp.latent_trajectories()[0]
    P = initial_latent_path(BSpline(n_control, tr.duration), tr.t[::stride], X, path_smoothing,
                            np.array([phases.takeoff, phases.touchdown]))
    bx = _toe_x(model, tr.Q, geom)
    td = int(np.argmin(np.abs(tr.t - phases.touchdown)))
    init = {"P": P, "t": tr.t, "base": tr.base, "x_L": float(np.median(bx[td:]))}
    return JumpSetup(model, smap, tr, gp, phases, geom, limits, init, float(np.median(bx[td:]) - bx[0]),
                     SymbolicModel(model))


def initial_latent_path(sp: BSpline, t: np.ndarray, X: np.ndarray, smoothing: float, keep: np.ndarray) -> np.ndarray:
    """Control points of the smoothed fit (:meth:`BSpline.fit` with ``smoothing * int ||x''||^2``)
    whose value and velocity at the times ``keep`` (takeoff, touchdown) equal the plain fit's, so
    the smoothing does not slow the push-off. Equality-constrained least squares (KKT system)."""
    plain = sp.fit(t, X)
    if smoothing <= 0:
        return plain
    S = sp.smoothing_rows(smoothing)
    A = np.vstack([sp.basis(t), S])
    b = np.vstack([X, np.zeros((S.shape[0], X.shape[1]))])
    C = np.vstack([sp.basis(keep, 0), sp.basis(keep, 1)])
    d = C @ plain
    P = plain.copy()  # the end control points stay (the end poses)
    b = b - A[:, [0, -1]] @ P[[0, -1]]
    d = d - C[:, [0, -1]] @ P[[0, -1]]
    A, C = A[:, 1:-1], C[:, 1:-1]
    n, m = A.shape[1], C.shape[0]
    K = np.block([[2 * A.T @ A, C.T], [C, np.zeros((m, m))]])
    P[1:-1] = np.linalg.solve(K, np.vstack([2 * A.T @ b, d]))[:n]
    return P


# ------------------------------------------------------------------ the problem file
_SETUP_CACHE: dict = {}

#: the ``[options]`` of a broad-jump problem file and the JumpSettings field each sets (None:
#: read by the set-up or reported, not a setting)
OPTIONS = {"mass": None, "height": None, "learned_dof": None, "restitution": None, "training_jumps": None,
           "training_stride": None, "torque_margin": None, "torque_floor": None, "sweep_starts": None,
           "friction": "mu", "n_stance": "n_stance", "n_flight": "n_flight", "n_land": "n_land",
           "two_phase": "two_phase", "torque_limits": "torque_limits", "polygon": "polygon",
           "n_base_stance": "n_base_stance", "n_base_land": "n_base_land", "foot_tolerance": "foot_tolerance",
           "wrench_spacing": "wrench_spacing"}
SWEEP_STARTS = ("warm+cold", "warm")  # a tube after a solved smaller one: both starts, or warm only


def check_options(problem) -> None:
    """Refuse ``[options]`` keys a broad-jump problem does not know and bad ``sweep_starts``."""
    from ..solve import SolveError

    unknown = sorted(set(problem.options) - set(OPTIONS))
    if unknown:
        raise SolveError(f"problem {problem.name!r}: unknown [options] key(s) {unknown}; "
                         f"a broad-jump problem knows {sorted(OPTIONS)}")
    starts = problem.options.get("sweep_starts", SWEEP_STARTS[0])
    if starts not in SWEEP_STARTS:
        raise SolveError(f"problem {problem.name!r}, [options] sweep_starts must be one of {SWEEP_STARTS}, "
                         f"got {starts!r}")


def settings_from_problem(problem, tube: float, hessian: str | None = None) -> JumpSettings:
    """JumpSettings from a problem file's tables (``[options]`` as :data:`OPTIONS` maps them)."""
    check_options(problem)
    types = {f.name: f.type for f in fields(JumpSettings)}
    kw = {}
    for key, value in problem.options.items():
        name = OPTIONS[key]
        if name is not None:
            kw[name] = {"int": int, "float": float, "bool": bool}.get(str(types[name]), type(value))(value)
    h = hessian or problem.hessian
    return JumpSettings(tube=float(tube), n_control=int(problem.control_points), max_iter=int(problem.max_iter),
                        tol=float(problem.tol), hessian="lbfgs" if h in ("lbfgs", "limited-memory") else "exact", **kw)


def _better(a: dict, b: dict) -> bool:
    """Whether result ``a`` is a better jump than ``b``: converged first, then farther."""
    return (a["success"], a["distance"]) > (b["success"], b["distance"])


def usable_warm_start(warm_start, delta: float) -> dict | None:
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
                                     **{k: ro[k] for k in ("status", "iterations", "solve_time_s", "distance")}}
    return sol


def solve_jump_problem(problem, *, tube=None, latent_dim=None, control_points=None, hessian=None,
                       method: str = "latent", joint_range_deg=None, gpdm=None, verbose: bool = False,
                       warm_start=None):
    """Solve, check on 1 kHz, return a :class:`latentoc.solve.Solution`. ``warm_start``: the
    Solution of this problem at a smaller tube (the sweep's previous one); with ``sweep_starts =
    "warm+cold"`` the tube is also solved from the training fit and the better jump kept."""
    from ..solve import Solution, SolveError, resolve_tube
    from .verify import verify

    if method != "latent":
        raise SolveError(f"broad-jump supports method 'latent' only, got {method!r}")
    if hessian not in (None, "lbfgs", "exact"):
        raise SolveError(f"broad-jump supports hessian 'exact' or 'lbfgs', got {hessian!r}")
    check_options(problem)
    o = problem.options
    training = "all" if o.get("training_jumps", "one") == "all" else 0
    stride = o.get("training_stride", 1)
    key = (training, latent_dim or problem.latent_dim, control_points or problem.control_points,
           float(o.get("torque_margin", 0.1)), float(o.get("torque_floor", 5.0)), stride)
    t0 = time.perf_counter()
    if key not in _SETUP_CACHE:
        try:
            _SETUP_CACHE[key] = setup(training, key[1], key[2], key[3], torque_floor=key[4], stride=stride)
        except ValueError as exc:
            raise SolveError(f"problem {problem.name!r}, [options] training_stride: {exc}") from None
    js = _SETUP_CACHE[key]
    gpdm_time = time.perf_counter() - t0
    spec = problem.tube if tube is None else tube
    delta = resolve_tube(spec, js.gpdm.tube_size())
    if not delta > 0:
        raise SolveError(f"tube must be positive, got {spec!r}")
    s = settings_from_problem(problem, delta, hessian)
    s.n_control = int(key[2])
    robot = js.robot(s.mu)
    layer = GPLayer(js.gpdm)
    t1 = time.perf_counter()
    blocks = js.blocks(robot)
    compile_time = time.perf_counter() - t1
    sol = solve_from_starts(lambda warm: solve_jump(robot, layer, blocks, js.phases, s, js.init, warm=warm,
                                                    verbose=verbose),
                            usable_warm_start(warm_start, delta), o.get("sweep_starts", SWEEP_STARTS[0]))
    traj = trajectory(robot, layer, js.phases, sol)
    checks = verify(js.model, traj, s.mu)
    r = sol.result
    r.update({"problem": problem.name, "kind": problem.kind, "method": "latent", "tube_spec": spec,
              "distance_initial": js.distance_training,
              "performance_gain_pct": 100.0 * (r["distance"] - js.distance_training) / js.distance_training,
              "training_jumps": o.get("training_jumps", "one"), "training_stride": stride,
              "training_points": int(js.gpdm.X.shape[0]), "tube_training": js.gpdm.tube_size(),
              "tube_relative": delta * js.gpdm.beta[2], "latent_dim": js.gpdm.latent_dim,
              "control_points": s.n_control, "gpdm_time_s": gpdm_time, "compile_time_s": compile_time,
              "cost_initial": js.distance_training, "cost": r["distance"],
              "cost_meaning": "jump distance of the toe tip in metres (maximised, Eq. 33)",
              "friction": s.mu, "restitution_paper": o.get("restitution", 0.5), "restitution_used": 0.0,
              "max_tube_violation": max(0.0, float(np.max(traj["sigma2"])) - delta), "quadrature_error": 0.0,
              "settings": asdict(s)})
    r.update(checks)
    return Solution(result=r, trajectory=traj, warm=sol.warm_start() if r["success"] else None)
