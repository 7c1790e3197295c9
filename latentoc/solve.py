"""Solving a problem end to end: learn the GPDM, transcribe, run Ipopt, rebuild the motion.

Entry point: :func:`solve`, which dispatches on ``problem.kind`` through :data:`SOLVERS`.

Contract for a problem kind (e.g. ``"broad-jump"`` from ``latentoc/jump/...``)::

    from latentoc.solve import SOLVERS, Solution, SolveError
    def solve_broad_jump(problem, **overrides) -> Solution: ...
    SOLVERS["broad-jump"] = solve_broad_jump

The function receives the :class:`~latentoc.problem.Problem` and the keyword overrides
of :func:`solve` (``tube``, ``latent_dim``, ``control_points``, ``hessian``, ``method``,
``joint_range_deg``, ``gpdm``, ``verbose``; ignore those that do not apply, raise
:class:`SolveError` for invalid ones BEFORE any work is written), and returns a
:class:`Solution` whose ``result`` is JSON-ready (at least: problem, status, success,
iterations, cost_initial, cost, performance_gain_pct, solve_time_s, build_time_s,
gpdm_time_s) and whose ``trajectory`` holds numpy arrays (at least t, q, v, a, tau and
``model`` = ``pinocchio.Model.saveToString()``). :func:`latentoc.results.write_solution`
and the CLI handle the rest. Modules registering kinds are imported by
:func:`solver_for` from :data:`KIND_MODULES`.

Tube sizes (Eq. 29). delta is in units of sigma^2 (Eq. 19), which depend on the learned
hyperparameters, so the paper's values do not transfer. ``tube`` is either a positive
number (absolute) or a string ``"<k>x"``: k times ``tube_training``, Eq. 30 for the
training sequence (max sigma^2 along its latent path, piecewise linear between the
frames). ``tube_initial`` (max sigma^2 along the initial spline, the least-squares fit
of that path, on a 1 kHz grid) is reported too: where a 9-point spline cannot follow
every turn of the learned path, ``tube_initial`` exceeds ``tube_training`` and for tubes
below it the initial guess is infeasible (Ipopt restores feasibility first). The smallest
feasible delta is sigma^2 at the fixed end points. Results also give ``tube_relative`` =
delta / noise variance (1/beta_3) to compare sweeps across problems.

GPDM settings of arm-raise (``[gpdm]``, measured; the table is in problems/arm-raise.toml):

* ``training_stride = 6``: learned on all 349 frames, the GPDM's latent path has small loops
  and a short kernel length scale (beta_2 ~ 29 against a path ~3 long); a 9-point spline
  then leaves the data (tube_initial ~1.5e5 x tube_training) and the initial motion costs
  64080, 68x the trial. Balanced (fit 1.1e4x) or a stride of 3 (568x) do not cure it; with
  every 6th frame (59 frames) the fit stays near the data (initial cost 943 vs. 947).
* ``beta3_max = 3000`` (noise variance floor): with the stride alone beta_3 grows to ~4e3
  and the spline fit reaches 18x tube_training, so tubes of 1-1.5x were infeasible. The
  floor gives 1.35x (initial cost 947.9). Balanced (704x) and more learning iterations
  (300x) made it worse. The fit is not monotone in the floor (500/1000/2000/3000/5000:
  2.9/2.2/5.6/1.35/16x) and depends on the early stop of the 5 x 60 iteration budget.
* What a tube near tube_training does: at 1.001 x tube_initial the optimised joint path
  stays within 0.3 deg of the initial one, but the cost still drops ~30%: Eq. 29 bounds
  where the latent path goes, not how fast it is traversed, and re-timing the trial along
  its own path is worth ~30% here. "delta near 0 returns the training motion" holds for
  the path, not the timing.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from importlib import import_module
from typing import Any, Callable

import casadi as ca
import numpy as np

from . import __version__
from .dynamics import SymbolicModel
from .gpdm import GPDM, GPDMSettings, learn_gpdm
from .kinds.min_torque import (METHODS, MinTorqueNLP, MinTorqueSettings, ipopt_options, joint_range_nlp, latent_nlp,
                               sampled_motion)
from .nlp import ipopt
from .nlp.ipopt import HESSIANS, IpoptResult
from .problem import TRAINING_MOTIONS, Problem, parse_tube, training_motion
from .robots import load_robot
from .spline_path import SplinePath, fixed_rows, trapezoid_cost

__all__ = ["solve", "Solution", "SolveError", "SOLVERS", "KIND_MODULES", "solver_for",
           "problem_gpdm", "resolve_tube", "METHODS"]

TRAJECTORY_RATE_HZ = 1000.0


class SolveError(ValueError):
    """Input that cannot be solved (bad parameter or a provably infeasible tube)."""


@dataclass
class Solution:
    """A solved problem: ``result`` (JSON-ready dict), ``trajectory`` (numpy arrays) and ``warm``,
    what a neighbouring solve of the same problem may start from (a kind's own data)."""

    result: dict[str, Any]
    trajectory: dict[str, np.ndarray] = field(default_factory=dict)
    warm: dict[str, Any] | None = None

    @property
    def success(self) -> bool:
        return bool(self.result.get("success", False))


#: problem kind -> solver function ``(problem, **overrides) -> Solution``.
SOLVERS: dict[str, Callable[..., Solution]] = {}
#: problem kind -> module that registers it in SOLVERS on import.
KIND_MODULES: dict[str, str] = {"broad-jump": "latentoc.jump"}


def solver_for(kind: str) -> Callable[..., Solution]:
    """The registered solver of a problem kind (importing its module if needed)."""
    if kind not in SOLVERS and kind in KIND_MODULES:
        try:
            import_module(KIND_MODULES[kind])
        except ImportError as exc:
            raise SolveError(f"problem kind {kind!r}: its module {KIND_MODULES[kind]} is not available ({exc})") from None
    if kind not in SOLVERS:
        raise SolveError(f"no solver for problem kind {kind!r}; known kinds: {', '.join(sorted(SOLVERS))}")
    return SOLVERS[kind]


def solve(problem: Problem, *, tube: float | str | None = None, latent_dim: int | None = None,
          control_points: int | None = None, hessian: str | None = None, method: str = "latent",
          joint_range_deg: float | None = None, gpdm: GPDM | None = None, verbose: bool = False,
          warm_start: Solution | None = None) -> Solution:
    """Solve ``problem`` with optional overrides of its declared parameters (see module doc).

    ``warm_start``: the Solution of the same problem at a smaller tube (the sweep passes the
    previous one), whose optimum is feasible here; each kind takes what it needs from its
    ``warm`` (the arm: the control points; the jump: the point and multipliers)."""
    return solver_for(problem.kind)(problem, tube=tube, latent_dim=latent_dim, control_points=control_points,
                                    hessian=hessian, method=method, joint_range_deg=joint_range_deg,
                                    gpdm=gpdm, verbose=verbose, warm_start=warm_start)


# ---------------------------------------------------------------- GPDM cache
_GPDM_CACHE: dict[str, tuple[GPDM, float]] = {}


def gpdm_settings(problem: Problem, latent_dim: int) -> GPDMSettings:
    """GPDMSettings from the problem's [gpdm] table (training_stride excluded)."""
    kw = {k: v for k, v in problem.gpdm.items() if k != "training_stride"}
    return GPDMSettings(latent_dim=int(latent_dim), **kw)


def problem_gpdm(problem: Problem, latent_dim: int | None = None) -> tuple[GPDM, float]:
    """The problem's GPDM and its learning time (s); learned once per problem + settings."""
    d = problem.latent_dim if latent_dim is None else int(latent_dim)
    settings = gpdm_settings(problem, d)
    key = json.dumps([problem.training, problem.training_stride, settings.to_json()])
    if key not in _GPDM_CACHE:
        _, Q = training_motion(problem)
        t0 = time.perf_counter()
        model = learn_gpdm(Q, settings)
        _GPDM_CACHE[key] = (model, time.perf_counter() - t0)
    return _GPDM_CACHE[key]


def resolve_tube(spec: float | str, reference: float) -> float:
    """Absolute delta from a tube spec (number or "<k>x" times ``reference``)."""
    try:
        value, relative = parse_tube(spec)
    except ValueError as exc:
        raise SolveError(str(exc)) from None
    return value * reference if relative else value


# ------------------------------------------------------------ latent solver
def _check_common(problem: Problem, m: int, hessian: str, method: str) -> None:
    if method not in METHODS:
        raise SolveError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    if hessian not in HESSIANS:
        raise SolveError(f"hessian must be one of {', '.join(HESSIANS)}, got {hessian!r}")
    if not isinstance(m, (int, np.integer)) or m < problem.spline_degree + 1:
        raise SolveError(f"control points m = {m} is fewer than spline degree + 1 = {problem.spline_degree + 1}")
    n_fixed = len(fixed_rows(max(m, 5), problem.boundary))
    if m <= n_fixed:
        raise SolveError(f'control points m = {m}: boundary "{problem.boundary}" fixes {n_fixed}, '
                         f"so at least {n_fixed + 1} are needed to leave one free")


def _time_grid(duration: float) -> np.ndarray:
    return np.linspace(0.0, duration, int(round(duration * TRAJECTORY_RATE_HZ)) + 1)


def _base_result(problem: Problem, method: str, m: int, hessian: str) -> dict[str, Any]:
    return {"problem": problem.name, "problem_source": problem.source, "kind": problem.kind, "method": method,
            "robot": problem.robot, "training": problem.training, "duration": problem.duration,
            "control_points": int(m), "spline_degree": problem.spline_degree, "boundary": problem.boundary,
            "quadrature": f"gauss-legendre, {problem.quadrature_points} nodes per knot interval",
            "quadrature_points": problem.quadrature_points, "constraint_points": problem.constraint_points,
            "joint_limits": problem.joint_limits, "torque_limits": list(problem.torque_limits),
            "hessian": hessian, "max_iter": problem.max_iter, "tol": problem.tol, "seed": problem.seed,
            "latentoc_version": __version__, "casadi_version": ca.__version__}


def _finish(result: dict, nlp: MinTorqueNLP, res: IpoptResult, cost_initial: float, motion: dict,
            motion_init_L: np.ndarray, t: np.ndarray) -> None:
    dt = float(t[1] - t[0])
    cost_fine = trapezoid_cost(motion["L"], dt)
    result.update({
        "status": res.status, "success": bool(res.success), "iterations": res.iterations,
        "cost_initial": cost_initial, "cost": res.f,
        "performance_gain_pct": 100.0 * (cost_initial - res.f) / cost_initial,
        "cost_trapezoid_1ms": cost_fine, "cost_initial_trapezoid_1ms": trapezoid_cost(motion_init_L, dt),
        "quadrature_error": abs(res.f - cost_fine) / abs(cost_fine),
        "solve_time_s": res.time_s, "n_variables": int(nlp.w0.size), "n_constraints": int(nlp.lbg.size),
    })


def _run_ipopt(problem: Problem, nlp: MinTorqueNLP, x0: np.ndarray, hessian: str, verbose: bool) -> IpoptResult:
    options = ipopt_options(nlp, tol=problem.tol, max_iter=problem.max_iter, verbose=verbose)
    return ipopt.solve(nlp.nlp, x0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, options, hessian=hessian,
                       desc=f"{problem.name} ({nlp.method})")


def solve_latent_min_torque(problem: Problem, *, tube: float | str | None = None, latent_dim: int | None = None,
                            control_points: int | None = None, hessian: str | None = None,
                            method: str = "latent", joint_range_deg: float | None = None,
                            gpdm: GPDM | None = None, verbose: bool = False,
                            warm_start: Solution | None = None) -> Solution:
    """Minimum-torque motion (L = |tau|^2) in the GPDM latent space or, with
    ``method="joint-range"``, in the full configuration space (Sect. 4.1.1);
    the NLP is :mod:`latentoc.kinds.min_torque`'s.

    ``warm_start``: a Solution whose latent control points (m x d, its ``warm["P"]``) Ipopt
    starts from instead of the training fit (:func:`latentoc.sweep.sweep` passes the previous,
    smaller tube's); cost_initial and the gain still refer to the training fit."""
    initial_guess = None if warm_start is None or not warm_start.warm else warm_start.warm.get("P")
    m = problem.control_points if control_points is None else control_points
    hessian = problem.hessian if hessian is None else hessian
    _check_common(problem, m, hessian, method)
    robot = load_robot(problem.robot)
    sym = SymbolicModel(robot)
    if method == "joint-range":
        return _solve_joint_range(problem, robot, sym, m, hessian, joint_range_deg, verbose)

    d = problem.latent_dim if latent_dim is None else latent_dim
    t_train, Q_train = training_motion(problem)
    D = Q_train.shape[1]
    if gpdm is not None:
        d = gpdm.latent_dim
    if not isinstance(d, (int, np.integer)) or not 1 <= d < D:
        raise SolveError(f"latent dimension d = {d} must satisfy 1 <= d < D = {D} (the training data's dimension)")
    if gpdm is not None and gpdm.X.shape[0] != len(t_train):
        raise SolveError(f"the given GPDM has {gpdm.X.shape[0]} latent points, the problem's training motion "
                         f"has {len(t_train)} frames")
    spec = problem.tube if tube is None else tube
    try:
        parse_tube(spec)
    except ValueError as exc:
        raise SolveError(str(exc)) from None
    if gpdm is None:
        gp, gpdm_time = problem_gpdm(problem, d)
    else:
        gp, gpdm_time = gpdm, 0.0

    settings = MinTorqueSettings.from_problem(problem, m)
    t = _time_grid(problem.duration)
    spline = settings.spline()
    path = SplinePath.fit(spline, t_train, gp.latent_trajectories()[0], problem.boundary)
    P0 = path.P_init
    x0 = spline.evaluate(P0, t)
    tube_training = gp.tube_size()
    tube_initial = float(np.max(gp.variance(x0)))
    tube_reference = tube_training
    delta = resolve_tube(spec, tube_reference)
    end_s2 = max(float(gp.variance(P0[0])), float(gp.variance(P0[-1])))
    if delta < end_s2:
        raise SolveError(f"tube delta = {delta:.4g} is infeasible: the fixed start/end latent points already have "
                         f"sigma^2 = {end_s2:.4g}; the smallest feasible delta is {end_s2:.4g} "
                         f"({end_s2 / tube_reference:.3g}x of tube_training = {tube_reference:.4g})")
    if initial_guess is not None and np.shape(initial_guess) != P0.shape:
        raise SolveError(f"initial guess has shape {np.shape(initial_guess)}, the control points {P0.shape}")

    t0 = time.perf_counter()
    nlp = latent_nlp(gp, sym, settings, delta, path)
    cost_initial = nlp.cost(nlp.w0)
    build_time = time.perf_counter() - t0
    x_start = nlp.w0 if initial_guess is None else path.decision_vector(initial_guess)
    res = _run_ipopt(problem, nlp, x_start, hessian, verbose)

    P = nlp.control_points(res.x)
    x = spline.evaluate(P, t)
    motion = sampled_motion(nlp.layer, robot, spline, P, t)
    init = sampled_motion(nlp.layer, robot, spline, P0, t)
    sigma2 = gp.variance(x)
    result = _base_result(problem, "latent", m, hessian)
    result.update({"latent_dim": int(d), "n_training_frames": int(len(t_train)),
                   "gpdm_settings": json.loads(gp.settings.to_json()),
                   "tube_spec": spec if isinstance(spec, str) else float(spec), "tube": delta,
                   "tube_relative": delta / gp.noise_variance, "noise_variance": gp.noise_variance,
                   "tube_training": tube_training, "tube_initial": tube_initial,
                   "max_sigma2": float(np.max(sigma2)),
                   "max_tube_violation": max(0.0, float(np.max(sigma2)) - delta),
                   "max_tube_violation_rel": max(0.0, float(np.max(sigma2)) - delta) / delta,
                   "build_time_s": build_time, "gpdm_time_s": gpdm_time, "warm_start": initial_guess is not None})
    _finish(result, nlp, res, cost_initial, motion, init["L"], t)
    trajectory = {"t": t, "q": motion["q"], "v": motion["v"], "a": motion["a"], "tau": motion["tau"],
                  "x": x, "P": P, "P_initial": P0, "q_initial": init["q"], "sigma2": sigma2,
                  "model": np.str_(robot.saveToString())}
    return Solution(result=result, trajectory=trajectory, warm={"P": P} if res.success else None)


def _solve_joint_range(problem: Problem, robot, sym: SymbolicModel, m: int, hessian: str,
                       joint_range_deg: float | None, verbose: bool) -> Solution:
    k = problem.joint_range_deg if joint_range_deg is None else joint_range_deg
    if isinstance(k, bool) or not isinstance(k, (int, float, np.floating)) or not np.isfinite(k) or k <= 0:
        raise SolveError(f"joint range must be a positive number of degrees, got {k!r}")
    t_train, Q_train = TRAINING_MOTIONS[problem.training]()  # all frames: no GPDM here
    settings = MinTorqueSettings.from_problem(problem, m)
    t = _time_grid(problem.duration)
    t0 = time.perf_counter()
    nlp = joint_range_nlp(sym, settings, np.asarray(t_train), np.asarray(Q_train), float(k))
    cost_initial = nlp.cost(nlp.w0)
    build_time = time.perf_counter() - t0
    res = _run_ipopt(problem, nlp, nlp.w0, hessian, verbose)
    P, P0, spline = nlp.control_points(res.x), nlp.path.P_init, nlp.path.spline
    motion = sampled_motion(nlp.layer, robot, spline, P, t)
    init = sampled_motion(nlp.layer, robot, spline, P0, t)
    result = _base_result(problem, "joint-range", m, hessian)
    result.update({"joint_range_deg": float(k), "n_training_frames": int(len(t_train)),
                   "build_time_s": build_time, "gpdm_time_s": 0.0, "max_tube_violation": None})
    _finish(result, nlp, res, cost_initial, motion, init["L"], t)
    trajectory = {"t": t, "q": motion["q"], "v": motion["v"], "a": motion["a"], "tau": motion["tau"],
                  "P": P, "P_initial": P0, "q_initial": init["q"], "model": np.str_(robot.saveToString())}
    return Solution(result=result, trajectory=trajectory)


SOLVERS["latent-min-torque"] = solve_latent_min_torque
