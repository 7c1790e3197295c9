"""Solving the broad jump: phase 1 (feasible), phase 2 (distance), warm starts as arguments.

Phase 1 finds the point satisfying every hard constraint nearest the training fit, without the
wrench samples; phase 2 maximises the distance from there with every row. A warm start (the
sweep's previous tube) skips phase 1 and starts phase 2 from that solution's point and
multipliers.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..latent.gp_layer import GPLayer
from ..nlp import ipopt
from ..nlp.blocks import RobotBlock
from .nlp import JumpNLP, build_nlp
from .phases import Phases
from .robot import JumpRobot
from .settings import JumpSettings
from .start import initial_point

__all__ = ["JumpSolution", "solve_jump", "ipopt_options"]


@dataclass
class JumpSolution:
    """A solved jump: its NLP, the solution vector, the Ipopt runs and the result fields."""

    nlp: JumpNLP
    w: np.ndarray
    phase2: ipopt.IpoptResult
    phase1: ipopt.IpoptResult | None
    result: dict

    def warm_start(self) -> dict:
        """What a neighbouring tube's solve starts from (:func:`solve_jump`'s ``warm``)."""
        return {"tube": self.result["tube"], **self.phase2.multipliers()}


def ipopt_options(s: JumpSettings, verbose: bool = False) -> dict:
    opts = {"tol": s.tol, "max_iter": s.max_iter, "acceptable_tol": 1e-4, "acceptable_iter": 10,
            "constr_viol_tol": 1e-6, "mu_strategy": "adaptive", "print_level": 5 if verbose else 0}
    if s.hessian == "lbfgs":
        opts["hessian_approximation"] = "limited-memory"
    return opts


def _summary(run: ipopt.IpoptResult, nlp: JumpNLP, t0: float) -> dict:
    viol = np.maximum(nlp.lbg - run.g, 0) + np.maximum(run.g - nlp.ubg, 0)
    return {"status": run.status, "success": run.success, "iterations": run.iterations, "time_s": run.time_s,
            "max_constraint_violation": float(viol.max(initial=0.0)),
            "distance": float(nlp.variables.unpack(run.x)["x_L"][0]), "wall_s": time.perf_counter() - t0}


def solve_jump(robot: JumpRobot, layer: GPLayer, blocks: dict[str, RobotBlock], phases: Phases,
               settings: JumpSettings, start: dict, warm: dict | None = None, verbose: bool = False) -> JumpSolution:
    """Solve the jump (module doc). ``start`` holds the training start (P, t, base, x_L);
    ``warm`` is a neighbouring solve's :meth:`JumpSolution.warm_start`."""
    s = settings
    t0 = time.perf_counter()
    nlp2 = build_nlp(robot, layer, blocks, phases, s, start["P"], "distance", wrench_samples=True)
    build = time.perf_counter() - t0
    opts = ipopt_options(s, verbose)
    run1 = None
    if warm is not None:
        if np.size(warm["x0"]) != nlp2.variables.n or np.size(warm["lam_g0"]) != nlp2.nlp.m:
            raise ValueError(f"warm start: its point ({np.size(warm['x0'])} variables, {np.size(warm['lam_g0'])} "
                             f"rows) does not fit this NLP ({nlp2.variables.n}, {nlp2.nlp.m})")
        x_start = warm["x0"]
    else:
        t1 = time.perf_counter()
        nlp1 = build_nlp(robot, layer, blocks, phases, s, start["P"], "feasibility", wrench_samples=False)
        x_start = initial_point(robot, layer, nlp1, start["P"], start["t"], start["base"], start["x_L"],
                                phases.takeoff, phases.touchdown)
        build += time.perf_counter() - t1
        if s.two_phase:
            run1 = ipopt.solve(nlp1.nlp, x_start, nlp1.lbx, nlp1.ubx, nlp1.lbg, nlp1.ubg, opts,
                               desc=f"broad jump, delta {s.tube:g}: phase 1 (feasible)")
            x_start = run1.x
    run2 = ipopt.solve(nlp2.nlp, x_start, nlp2.lbx, nlp2.ubx, nlp2.lbg, nlp2.ubg, opts,
                       warm=None if warm is None else {k: warm[k] for k in ("x0", "lam_g0", "lam_x0")},
                       desc=f"broad jump, delta {s.tube:g}: phase 2 (distance)")
    w = run2.x
    viol = np.maximum(nlp2.lbg - run2.g, 0) + np.maximum(run2.g - nlp2.ubg, 0)
    worst, binding = {}, {}
    for name, v, lam in zip(nlp2.row_names, viol, np.abs(run2.lam_g)):
        worst[name] = max(worst.get(name, 0.0), float(v))
        binding[name] = binding.get(name, 0.0) + float(lam)
    distance = float(nlp2.variables.unpack(w)["x_L"][0])
    timings = {k: run2.timings.get(k, 0.0) + (run1.timings.get(k, 0.0) if run1 else 0.0)
               for k in set(run2.timings) | set(run1.timings if run1 else {})}
    result = {
        "tube": s.tube, "status": run2.status, "success": run2.success, "iterations": run2.iterations,
        "build_time_s": build, "solve_time_s": (run1.time_s if run1 else 0.0) + run2.time_s,
        "objective": run2.f, "distance": distance,
        "max_constraint_violation": float(viol.max(initial=0.0)), "constraint_violation_by_kind": worst,
        # sum of |multiplier| per row kind: what binds (torque rows in units of each joint's limit range)
        "multiplier_by_kind": binding, "warm_start": warm is not None,
        "phase1": _summary(run1, nlp1, t0) if run1 else {},
        "phase2_time_s": run2.time_s, "evaluation_time_s": timings,
        "n_variables": int(nlp2.variables.n), "n_constraints": int(nlp2.nlp.m), "settings": asdict(s),
    }
    return JumpSolution(nlp2, w, run2, run1, result)
