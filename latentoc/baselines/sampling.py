"""Kinodynamic RRT* on OMPL for the arm: the sampling-based baseline of the paper's Table 3.

Formulation (docs/sampling-baseline.md has the reasoning and the measurements):

* state x = (q, qdot, t), 2 nv + 1 dims; time is a coordinate so that the fixed duration T of
  the problem is kept: the start is (q_start, 0, 0), the goal (q_goal, 0, T), both at rest at the
  training motion's first and last poses; sampled states lie within the joint limits,
  |qdot| <= ``velocity_factor`` x the training motion's largest joint speed, 0 <= t <= T;
* steering (the edge between two states): the cubic Hermite q(t) with the given end positions
  and velocities over [t1, t2], the fixed-time steering of the joint-space double integrator
  that minimises the integral of |qddot|^2 (the double integrator is what kinodynamic RRT*,
  the paper's [18], steers exactly); edges go forward in time only (t2 - t1 >= a minimum);
* edge validity: the joint limits at the cubic's exact extrema, the torque limits (if the
  problem has any) at the quadrature points;
* edge cost: the integral of |tau|^2 with tau = pinocchio.rnea(q, qdot, qddot) along the cubic
  (5-point Gauss-Legendre panels of at most ``quadrature_step`` s and ``quadrature_angle`` rad
  of joint motion), so the planner minimises the problem's cost J = int |tau|^2 dt;
* planner: OMPL's geometric RRT* with this motion validator and objective (asymptotically
  optimal for the steered edges). OMPL's control planners (SST, RRT) cannot be used: their
  Python bindings (ompl 2.0) give SST no constructor and allow no steering function.

The goal is reached exactly (the last edge steers to it): the goal tolerance is
``goal_tolerance`` in the state metric, and the result reports the measured boundary errors.
Every result is re-checked on a uniform ``grid_hz`` grid with numeric Pinocchio
(:func:`check_motion`): tau from rnea on the exported q, v, a, J by the trapezoid rule, the joint
and torque limits.

Reproducibility: OMPL seeds all its generators from one seed that can be set once per process,
before its first random number; with an iteration cap (``iterations=``) a fresh process with the
same seed plans the same tree. A wall-time budget makes the iteration count, so the result,
depend on the machine and its load. A second plan in the same process is not reproducible
(``SamplingResult.seeded`` is False).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.min_torque.limits import torque_limit_vector
from latentoc.min_torque.training import training_frames
from latentoc.problem.declaration import Problem
from latentoc.robots import load_robot

__all__ = ["EXTRA", "OmplUnavailable", "require_ompl", "SamplingSettings", "ArmTask", "HermiteEdges",
           "SamplingResult", "KinodynamicRRTStar", "plan", "hermite_samples", "check_motion"]

#: the optional dependency group (``pip install latentoc[sampling]``)
EXTRA = "sampling"
_SEEDED: list[int] = []  # the seed OMPL was given in this process (at most one)


class OmplUnavailable(LatentocError, ImportError):
    """OMPL's Python bindings are not installed."""


def require_ompl() -> tuple[Any, Any, Any]:
    """OMPL's ``base``, ``geometric`` and ``util`` modules, or :class:`OmplUnavailable`."""
    try:
        from ompl import base as ob, geometric as og, util as ou
    except ImportError as exc:
        raise OmplUnavailable(f"the sampling baseline needs OMPL's Python bindings (ompl >= 2): "
                              f"pip install 'latentoc[{EXTRA}]' ({exc})") from None
    return ob, og, ou


@dataclass(frozen=True)
class SamplingSettings:
    """Planner settings; ``connect_range`` None: steer straight to every sample (the space's extent)."""

    seed: int = 0
    goal_bias: float = 0.05
    rewire_factor: float = 1.1
    connect_range: float | None = None
    velocity_factor: float = 2.0     # sampled |qdot| <= factor x the training motion's largest
    quadrature_step: float = 0.4     # s per 5-point Gauss-Legendre panel of the edge cost, at most
    quadrature_angle: float = 0.7    # rad of joint motion per panel, at most
    min_edge_duration: float = 0.01  # s
    goal_tolerance: float = 1e-6     # state metric (rad, rad/s, s)
    grid_hz: float = 1000.0          # the re-check's uniform grid


@dataclass(frozen=True)
class ArmTask:
    """What the planner needs from a problem: robot, duration, boundary poses (at rest), limits."""

    model: Any  # pinocchio.Model
    duration: float
    q_start: np.ndarray
    q_goal: np.ndarray
    q_lower: np.ndarray
    q_upper: np.ndarray
    v_bound: np.ndarray
    tau_max: np.ndarray | None = None
    joint_limits: bool = True

    @property
    def nv(self) -> int:
        return int(self.model.nv)

    @classmethod
    def from_problem(cls, problem: Problem, velocity_factor: float = 2.0) -> ArmTask:
        """The task of a ``latent-min-torque`` problem (robot, duration, training end poses, limits)."""
        model = load_robot(problem.robot)
        t, Q = (np.asarray(a, dtype=float) for a in training_frames(problem))
        vmax = np.max(np.abs(np.gradient(Q, t, axis=0)), axis=0)
        if problem.joint_limits:
            lo, hi = np.array(model.lowerPositionLimit), np.array(model.upperPositionLimit)
        else:  # sampling bounds only: the training range +-90 deg
            lo, hi = Q.min(0) - math.pi / 2, Q.max(0) + math.pi / 2
        return cls(model=model, duration=float(problem.duration), q_start=Q[0].copy(), q_goal=Q[-1].copy(),
                   q_lower=lo, q_upper=hi, v_bound=np.maximum(velocity_factor * vmax, 0.1),
                   tau_max=torque_limit_vector(problem.torque_limits, model),
                   joint_limits=bool(problem.joint_limits))


def _hermite(q1: np.ndarray, v1: np.ndarray, q2: np.ndarray, v2: np.ndarray, h: np.ndarray | float
             ) -> tuple[np.ndarray, np.ndarray]:
    """(c2, c3) of q(s) = q1 + v1 s + c2 s^2 + c3 s^3 on [0, h] (rows: segments if arrays)."""
    h = np.asarray(h, dtype=float)[..., None] if np.ndim(h) else float(h)
    d = (q2 - q1) / h
    return (3 * d - 2 * v1 - v2) / h, (v1 + v2 - 2 * d) / h**2


class HermiteEdges:
    """Cubic Hermite edges between states x = (q, qdot, t): validity and the torque cost."""

    def __init__(self, task: ArmTask, quadrature_step: float = 0.4, quadrature_angle: float = 0.7,
                 min_duration: float = 0.01):
        self.task, self.n = task, task.nv
        self.step, self.angle, self.min_duration = float(quadrature_step), float(quadrature_angle), float(min_duration)
        self.data = task.model.createData()
        self._panels: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def panels(self, m: int) -> tuple[np.ndarray, np.ndarray]:
        """m 5-point Gauss-Legendre panels on [0, 1]: the power basis of q, h v and h^2 a at
        the N nodes (3N x 4), and the weights (N)."""
        if m not in self._panels:
            g, w = np.polynomial.legendre.leggauss(5)
            u = ((np.arange(m)[:, None] + (g[None] + 1) / 2) / m).ravel()
            one, zero = np.ones_like(u), np.zeros_like(u)
            basis = np.vstack([np.stack([one, u, u**2, u**3], 1), np.stack([zero, one, 2 * u, 3 * u**2], 1),
                               np.stack([zero, zero, 2 * one, 6 * u], 1)])
            self._panels[m] = (basis, np.tile(w / (2 * m), m))
        return self._panels[m]

    def _split(self, x1: np.ndarray, x2: np.ndarray) -> tuple:
        n = self.n
        h = x2[2 * n] - x1[2 * n]
        q1, v1, q2, v2 = x1[:n], x1[n:2 * n], x2[:n], x2[n:2 * n]
        return h, q1, v1, *_hermite(q1, v1, q2, v2, h)

    def torques(self, x1: np.ndarray, x2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(weights, tau) at the Gauss points of the edge (h >= min_duration assumed)."""
        h, q1, v1, c2, c3 = self._split(x1, x2)
        n = self.n  # panels: h / step, and the joint excursion (a bound of the cubic's) / angle
        excursion = max(h * np.abs(v1).max(), h * np.abs(x2[n:2 * n]).max(), 1.5 * np.abs(x2[:n] - q1).max())
        m = max(1, math.ceil(h / self.step - 1e-9), math.ceil(excursion / self.angle - 1e-9))
        basis, w = self.panels(m)
        N = len(w)
        qva = basis @ np.stack([q1, v1 * h, c2 * (h * h), c3 * h**3])
        q, v, a = qva[:N], qva[N:2 * N] / h, qva[2 * N:] / (h * h)
        model, data = self.task.model, self.data
        return w * h, np.array([pin.rnea(model, data, qk, vk, ak) for qk, vk, ak in zip(q, v, a)])

    def cost(self, x1: np.ndarray, x2: np.ndarray) -> float:
        """int |tau|^2 dt along the edge; inf if it does not go forward in time."""
        if x2[2 * self.n] - x1[2 * self.n] < self.min_duration:
            return math.inf
        w, tau = self.torques(x1, x2)
        return float(w @ np.einsum("ij,ij->i", tau, tau))

    def feasible(self, x1: np.ndarray, x2: np.ndarray) -> bool:
        """Forward in time, joint limits at the exact extrema, torque limits at the Gauss points."""
        h, q1, v1, c2, c3 = self._split(x1, x2)
        if h < self.min_duration:
            return False
        task = self.task
        if task.joint_limits:
            A, B, C = 3 * c3, 2 * c2, v1  # qdot(s) = A s^2 + B s + C
            with np.errstate(all="ignore"):
                disc = np.sqrt(np.maximum(B * B - 4 * A * C, 0.0))
                r = -(B + np.where(B >= 0, disc, -disc)) / 2
                roots = np.stack([r / A, C / r])
            s = np.where(np.isfinite(roots) & (roots > 0) & (roots < h), roots, 0.0)
            s = np.vstack([s, np.full(self.n, h)])
            q = q1 + v1 * s + c2 * s**2 + c3 * s**3
            if np.any(q < task.q_lower - 1e-12) or np.any(q > task.q_upper + 1e-12):
                return False
        if task.tau_max is not None:
            _, tau = self.torques(x1, x2)
            if np.any(np.abs(tau) > task.tau_max):
                return False
        return True


def hermite_samples(knots: np.ndarray, t: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, v, a at times t of the piecewise cubic Hermite through knots (K x (2n+1): q, qdot, t).

    At a knot, the segment that starts there (the last sample: the one that ends there)."""
    tk = knots[:, 2 * n]
    i = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, len(tk) - 2)
    q1, v1, q2, v2 = knots[:-1, :n], knots[:-1, n:2 * n], knots[1:, :n], knots[1:, n:2 * n]
    c2, c3 = _hermite(q1, v1, q2, v2, np.diff(tk))
    s = (t - tk[i])[:, None]
    q = q1[i] + v1[i] * s + c2[i] * s**2 + c3[i] * s**3
    return q, v1[i] + 2 * c2[i] * s + 3 * c3[i] * s**2, 2 * c2[i] + 6 * c3[i] * s


def check_motion(model: Any, t: np.ndarray, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                 q_lower: np.ndarray | None = None, q_upper: np.ndarray | None = None,
                 tau_max: np.ndarray | None = None) -> dict[str, Any]:
    """Numeric Pinocchio re-check on a uniform grid: tau (rnea), J (trapezoid), limit excesses."""
    data = model.createData()
    tau = np.array([pin.rnea(model, data, q[k], v[k], a[k]) for k in range(len(t))])
    L = np.einsum("ij,ij->i", tau, tau)
    dt = float(t[1] - t[0])
    out: dict[str, Any] = {"tau": tau, "cost": float(dt * (L.sum() - 0.5 * (L[0] + L[-1]))),
                           "max_joint_violation": 0.0, "max_torque_violation": None}
    if q_lower is not None and q_upper is not None:
        out["max_joint_violation"] = float(max(0.0, np.max(q - q_upper), np.max(q_lower - q)))
    if tau_max is not None:
        out["max_torque_violation"] = float(max(0.0, np.max(np.abs(tau) - tau_max)))
    return out


@dataclass
class SamplingResult:
    """One checkpoint of a plan (times and iterations count from the planner's start)."""

    solved: bool                 # an exact solution (the goal within goal_tolerance)
    time_s: float                # wall time inside OMPL's solve, cumulative
    iterations: int              # RRT* iterations, cumulative
    vertices: int                # states in the tree
    cost_planner: float          # the planner's J (Gauss quadrature of its edges)
    cost: float                  # J re-checked on the uniform grid (numeric rnea, trapezoid)
    first_solution_s: float      # when the first solution was found
    best_found_s: float          # when this solution was found
    seed: int
    seeded: bool                 # OMPL took this seed (first plan in the process)
    knots: np.ndarray            # K x (2 nv + 1): the solution's states (q, qdot, t)
    trajectory: dict[str, np.ndarray] = field(default_factory=dict)  # t, q, v, a, tau on the grid
    checks: dict[str, float] = field(default_factory=dict)  # boundary errors, limit excesses
    improvements: list[tuple[float, int, float]] = field(default_factory=list)  # (s, iteration, J)


class KinodynamicRRTStar:
    """OMPL RRT* over (q, qdot, t) with Hermite steering; :meth:`run` continues the same tree."""

    def __init__(self, task: ArmTask, settings: SamplingSettings = SamplingSettings()):
        ob, og, ou = require_ompl()
        self.task, self.settings, self._ou = task, settings, ou
        self.seeded = not _SEEDED
        if self.seeded:  # OMPL refuses seed 0
            ou.RNG.setSeed(settings.seed + 1)
            _SEEDED.append(settings.seed)
        self._level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_WARN)
        n, dim = task.nv, 2 * task.nv + 1
        self.n, self.dim = n, dim
        self.edges = edges = HermiteEdges(task, settings.quadrature_step, settings.quadrature_angle,
                                           settings.min_edge_duration)
        space = ob.RealVectorStateSpace(dim)
        bounds = ob.RealVectorBounds(dim)
        lows = np.concatenate([task.q_lower, -task.v_bound, [0.0]])
        highs = np.concatenate([task.q_upper, task.v_bound, [task.duration]])
        for i in range(dim):
            bounds.setLow(i, float(lows[i]))
            bounds.setHigh(i, float(highs[i]))
        space.setBounds(bounds)

        class Validator(ob.MotionValidator):  # type: ignore[name-defined]  # OMPL ships no stubs
            def checkMotion(self, s1: Any, s2: Any) -> bool:
                return edges.feasible(np.array(s1[0:dim]), np.array(s2[0:dim]))

        class TorqueCost(ob.OptimizationObjective):  # type: ignore[name-defined]  # OMPL ships no stubs
            def stateCost(self, s: Any) -> Any:
                return ob.Cost(0.0)

            def motionCost(self, s1: Any, s2: Any) -> Any:
                return ob.Cost(edges.cost(np.array(s1[0:dim]), np.array(s2[0:dim])))

            def isSymmetric(self) -> bool:
                return False

        si = ob.SpaceInformation(space)
        si.setStateValidityChecker(ob.AllValidStateValidityChecker(si))
        self._validator = Validator(si)
        si.setMotionValidator(self._validator)
        si.setup()
        start, goal = si.allocState(), si.allocState()
        for state, q, t in ((start, task.q_start, 0.0), (goal, task.q_goal, task.duration)):
            for i, value in enumerate(np.concatenate([q, np.zeros(n), [t]])):
                state[i] = float(value)
        pdef = ob.ProblemDefinition(si)
        pdef.setStartAndGoalStates(start, goal, settings.goal_tolerance)
        self._objective = TorqueCost(si)
        pdef.setOptimizationObjective(self._objective)
        planner = og.RRTstar(si)
        planner.setProblemDefinition(pdef)
        planner.setGoalBias(settings.goal_bias)
        planner.setRewireFactor(settings.rewire_factor)
        planner.setRange(settings.connect_range or si.getMaximumExtent())
        planner.setup()
        self._ob, self._si, self._pdef, self._planner = ob, si, pdef, planner
        self._states = (start, goal)
        self.time_s = 0.0
        self.improvements: list[tuple[float, int, float]] = []  # (s, iteration, J) of each better plan

    def close(self) -> None:
        """Restore OMPL's log level."""
        self._ou.setLogLevel(self._level)

    def run(self, seconds: float = math.inf, iterations: int | None = None) -> SamplingResult:
        """Plan on until ``seconds`` (cumulative) or ``iterations`` (cumulative) and report."""
        planner, ob = self._planner, self._ob
        best = [self.improvements[-1][2] if self.improvements else math.inf]
        t0 = time.perf_counter() - self.time_s

        def stop() -> bool:
            elapsed = time.perf_counter() - t0
            c = planner.bestCost().value()
            if c < best[0]:
                best[0] = c
                self.improvements.append((elapsed, int(planner.numIterations()), c))
            return elapsed >= seconds or (iterations is not None and planner.numIterations() >= iterations)

        self._pdef.clearSolutionPaths()
        planner.solve(ob.PlannerTerminationCondition(stop))
        self.time_s = time.perf_counter() - t0
        stop()  # the last improvement
        data = ob.PlannerData(self._si)
        planner.getPlannerData(data)
        solved = bool(self._pdef.hasExactSolution())
        knots = np.array([s[0:self.dim] for s in self._pdef.getSolutionPath().getStates()]) if solved else \
            np.zeros((0, self.dim))
        result = SamplingResult(
            solved=solved, time_s=self.time_s, iterations=int(planner.numIterations()),
            vertices=int(data.numVertices()), cost_planner=float(planner.bestCost().value()), cost=math.nan,
            first_solution_s=self.improvements[0][0] if self.improvements else math.nan,
            best_found_s=self.improvements[-1][0] if self.improvements else math.nan,
            seed=self.settings.seed, seeded=self.seeded, knots=knots, improvements=list(self.improvements))
        if solved:
            self._check(result)
        return result

    def _check(self, r: SamplingResult) -> None:
        task, n = self.task, self.n
        t = np.arange(round(task.duration * self.settings.grid_hz) + 1) / self.settings.grid_hz
        q, v, a = hermite_samples(r.knots, t, n)
        chk = check_motion(task.model, t, q, v, a, task.q_lower if task.joint_limits else None,
                           task.q_upper if task.joint_limits else None, task.tau_max)
        r.trajectory = {"t": t, "q": q, "v": v, "a": a, "tau": chk.pop("tau")}
        r.cost = chk.pop("cost")
        r.checks = {**chk, "start_q_error": float(np.max(np.abs(q[0] - task.q_start))),
                    "start_v_error": float(np.max(np.abs(v[0]))),
                    "goal_q_error": float(np.max(np.abs(q[-1] - task.q_goal))),
                    "goal_v_error": float(np.max(np.abs(v[-1]))),
                    "end_time_error": float(abs(r.knots[-1, 2 * n] - task.duration))}


def plan(problem: Problem, seconds: list[float] | None = None, iterations: list[int] | None = None,
         settings: SamplingSettings = SamplingSettings()) -> list[SamplingResult]:
    """Plan ``problem``'s motion and report at each cumulative budget (``seconds`` or ``iterations``)."""
    if (seconds is None) == (iterations is None):
        raise ValueError("give either seconds or iterations")
    task = ArmTask.from_problem(problem, settings.velocity_factor)
    planner = KinodynamicRRTStar(task, settings)
    try:
        if seconds is not None:
            return [planner.run(seconds=float(s)) for s in sorted(seconds)]
        return [planner.run(iterations=int(k)) for k in sorted(iterations or [])]
    finally:
        planner.close()
