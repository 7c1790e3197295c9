"""Solving the broad jump: phase 1 (feasible), phase 2 (distance), warm starts as arguments.

Phase 1 finds the point satisfying every hard constraint nearest the training fit, without the
wrench samples; phase 2 maximises the distance from there with every row, in rounds of the
exchange (:mod:`.exchange`) until the sampled rows hold on the 1 kHz grid. A warm start (the
sweep's previous tube) skips phase 1 and starts phase 2 from that solution's point, multipliers
and samples.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..latent.gp_layer import GPLayer
from ..nlp import ipopt
from ..nlp.blocks import RobotBlock
from .exchange import binding_times, candidates
from .nlp import JumpNLP, Samples, build_nlp, default_samples
from .phases import Phases
from .robot import JumpRobot
from .settings import JumpSettings
from .start import initial_point

__all__ = ["JumpSolution", "solve_jump", "ipopt_options"]

TUBE_TOL = 1e-6  # the 1 kHz grid's sigma^2 may exceed delta by this fraction of it


@dataclass
class JumpSolution:
    """A solved jump: its NLP, the solution vector, the Ipopt runs and the result fields."""

    nlp: JumpNLP
    w: np.ndarray
    phase2: ipopt.IpoptResult
    phase1: ipopt.IpoptResult | None
    result: dict

    def warm_start(self) -> dict:
        """What a neighbouring tube's solve starts from (:func:`solve_jump`'s ``warm``): the point,
        the multipliers with the NLP they belong to, and the samples the exchange placed."""
        return {"tube": self.result["tube"], "nlp": self.nlp, "samples": self.nlp.meta["samples"],
                **self.phase2.multipliers()}


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


def row_keys(nlp: JumpNLP) -> list[tuple]:
    """A key per constraint row, the same for the same row in NLPs with other samples."""
    seen: dict = {}
    keys = []
    for name, t in zip(nlp.row_names, np.round(nlp.meta["row_times"], 9)):
        k = (str(name), float(t))
        seen[k] = seen.get(k, -1) + 1
        keys.append((*k, seen[k]))
    return keys


def carried_multipliers(old: JumpNLP, new: JumpNLP, lam_g: np.ndarray) -> np.ndarray:
    """``old``'s row multipliers on ``new``'s rows (zero for the new rows)."""
    index = {k: i for i, k in enumerate(row_keys(old))}
    return np.array([lam_g[index[k]] if k in index else 0.0 for k in row_keys(new)])


def solve_jump(robot: JumpRobot, layer: GPLayer, blocks: dict[str, RobotBlock], phases: Phases,
               settings: JumpSettings, start: dict, warm: dict | None = None, verbose: bool = False) -> JumpSolution:
    """Solve the jump (module doc). ``start`` holds the training start (P, t, base, x_L);
    ``warm`` is a neighbouring solve's :meth:`JumpSolution.warm_start`."""
    s = settings
    t0 = time.perf_counter()
    P = start["P"]
    samples = default_samples(s, phases)
    if warm is not None and "samples" in warm:
        samples = samples.merged(warm["samples"])
    if s.exchange:
        probe = build_nlp(robot, layer, blocks, phases, s, P, "distance", samples=candidates(phases))
    nlp2 = build_nlp(robot, layer, blocks, phases, s, P, "distance", samples=samples)
    build = time.perf_counter() - t0
    opts = ipopt_options(s, verbose)
    run1, nlp1, warm2 = None, None, None
    if warm is not None:
        if np.size(warm["x0"]) != nlp2.variables.n:
            raise ValueError(f"warm start: its point has {np.size(warm['x0'])} variables, this NLP "
                             f"{nlp2.variables.n}")
        x_start = warm["x0"]
        if "nlp" in warm:
            warm2 = {"x0": warm["x0"], "lam_x0": warm["lam_x0"],
                     "lam_g0": carried_multipliers(warm["nlp"], nlp2, warm["lam_g0"])}
    else:
        t1 = time.perf_counter()
        phase1_samples = Samples(np.zeros(0), samples.flight_torque, samples.tube)
        nlp1 = build_nlp(robot, layer, blocks, phases, s, P, "feasibility", samples=phase1_samples)
        x_start = initial_point(robot, layer, nlp1, P, start["t"], start["base"], start["x_L"],
                                phases.takeoff, phases.touchdown)
        build += time.perf_counter() - t1
        if s.two_phase:
            run1 = ipopt.solve(nlp1.nlp, x_start, nlp1.lbx, nlp1.ubx, nlp1.lbg, nlp1.ubg, opts,
                               desc=f"broad jump, delta {s.tube:g}: phase 1 (feasible)")
            x_start = run1.x
    rounds = []
    while True:
        run2 = ipopt.solve(nlp2.nlp, x_start, nlp2.lbx, nlp2.ubx, nlp2.lbg, nlp2.ubg, opts, warm=warm2,
                           desc=f"broad jump, delta {s.tube:g}: phase 2 (distance), round {len(rounds) + 1}")
        smp = nlp2.meta["samples"]
        entry = {"iterations": run2.iterations, "time_s": run2.time_s, "status": run2.status,
                 "wrench_samples": int(len(smp.wrench)), "flight_torque_samples": int(len(smp.flight_torque)),
                 "tube_samples": int(len(smp.tube))}
        rounds.append(entry)
        if not s.exchange or not run2.success:
            break
        tol = {"wrench": s.exchange_tol, "flight_torque": s.exchange_tol, "tube": TUBE_TOL}
        found, worst = binding_times(probe, run2.x, tol)
        new = found.minus(nlp2.meta["samples"])
        entry["violation_1khz"] = worst
        if not any(len(f) for f in new.fields()) or len(rounds) >= s.exchange_rounds:
            break
        t1 = time.perf_counter()
        old = nlp2
        nlp2 = build_nlp(robot, layer, blocks, phases, s, P, "distance", samples=nlp2.meta["samples"].merged(new))
        build += time.perf_counter() - t1
        x_start = run2.x
        warm2 = {"x0": run2.x, "lam_x0": run2.lam_x, "lam_g0": carried_multipliers(old, nlp2, run2.lam_g)}
    runs2 = rounds
    w = run2.x
    viol = np.maximum(nlp2.lbg - run2.g, 0) + np.maximum(run2.g - nlp2.ubg, 0)
    worst_kind, binding = {}, {}
    for name, v, lam in zip(nlp2.row_names, viol, np.abs(run2.lam_g)):
        worst_kind[name] = max(worst_kind.get(name, 0.0), float(v))
        binding[name] = binding.get(name, 0.0) + float(lam)
    distance = float(nlp2.variables.unpack(w)["x_L"][0])
    phase2_time = sum(r["time_s"] for r in runs2)
    result = {
        "tube": s.tube, "status": run2.status, "success": run2.success,
        "iterations": sum(r["iterations"] for r in runs2), "build_time_s": build,
        "solve_time_s": (run1.time_s if run1 else 0.0) + phase2_time, "objective": run2.f, "distance": distance,
        "max_constraint_violation": float(viol.max(initial=0.0)), "constraint_violation_by_kind": worst_kind,
        # sum of |multiplier| per row kind: what binds (torque rows in units of each joint's limit range)
        "multiplier_by_kind": binding, "warm_start": warm is not None,
        "phase1": _summary(run1, nlp1, t0) if run1 else {}, "phase2_rounds": runs2, "phase2_time_s": phase2_time,
        "n_variables": int(nlp2.variables.n), "n_constraints": int(nlp2.nlp.m), "settings": asdict(s),
    }
    return JumpSolution(nlp2, w, run2, run1, result)
