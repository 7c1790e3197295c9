"""Solving the broad jump: phase 1 (feasible), phase 2 (distance) in rounds of the exchange.

Phase 1 finds the point satisfying the contact nodes' hard constraints nearest the training fit;
phase 2 maximises the distance from there. Each starts with the rows within a margin of binding
at its start (:func:`.exchange.seed_selection`); after each phase-2 solve the exported 1 kHz
motion is checked with numeric Pinocchio and the rows that fail or come near are added
(:func:`.exchange.chosen_rows`), and the solve resumes warm (:mod:`.warm`), until every hard
constraint holds on the 1 kHz grid. A warm start (the sweep's previous tube) skips phase 1 and
starts phase 2 from that solution's point, multipliers and rows.
"""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np
import pinocchio as pin

from ..latent.gp_layer import GPLayer
from ..nlp import ipopt
from ..nlp.blocks import RobotBlock
from . import exchange
from .export import trajectory
from .nlp import JumpNLP, build_nlp, contact_sample_grid, flight_sample_grid, tube_times
from .phases import Phases
from .robot import JumpRobot
from .selection import Selection
from .settings import JumpSettings
from .start import initial_point
from .verify import series
from .warm import carried_multipliers, carried_point

__all__ = ["JumpSolution", "solve_jump", "ipopt_options"]


@dataclass
class JumpSolution:
    """A solved jump: its last NLP, the solution vector, the Ipopt runs, its 1 kHz export with the
    constraints' slack there, and the result fields (times in ``result["times"]``)."""

    nlp: JumpNLP
    w: np.ndarray
    phase2: ipopt.IpoptResult
    phase1: ipopt.IpoptResult | None
    trajectory: dict
    series: dict
    result: dict

    def warm_start(self) -> dict:
        """What a neighbouring tube's solve starts from (:func:`solve_jump`'s ``warm``): the NLP
        (with its rows), the point and the multipliers."""
        return {"tube": self.result["tube"], "nlp": self.nlp, **self.phase2.multipliers()}


@dataclass
class _Clock:
    """Wall seconds of each part of a solve; they add up to its wall."""

    parts: dict[str, float] = field(default_factory=lambda: {"build_s": 0.0, "solve_s": 0.0, "check_s": 0.0})

    def add(self, part: str, t0: float) -> float:
        now = time.perf_counter()
        self.parts[part] += now - t0
        return now


def ipopt_options(s: JumpSettings, verbose: bool = False) -> dict:
    opts = {"tol": s.tol, "max_iter": s.max_iter, "acceptable_tol": 1e-4, "acceptable_iter": 10,
            "constr_viol_tol": 1e-8, "mu_strategy": "adaptive", "print_level": 5 if verbose else 0}
    if s.hessian == "lbfgs":
        opts["hessian_approximation"] = "limited-memory"
    return opts


def _run_summary(run: ipopt.IpoptResult, nlp: JumpNLP) -> dict:
    viol = np.maximum(nlp.lbg - run.g, 0) + np.maximum(run.g - nlp.ubg, 0)
    return {"status": run.status, "success": run.success, "iterations": run.iterations, "time_s": run.time_s,
            "max_constraint_violation": float(viol.max(initial=0.0)), "n_variables": int(nlp.variables.n),
            "n_constraints": int(nlp.nlp.m), "distance": float(nlp.variables.unpack(run.x)["x_L"][0]),
            **nlp.selection.summary()}


def solve_jump(robot: JumpRobot, layer: GPLayer, blocks: dict[str, RobotBlock], phases: Phases,
               settings: JumpSettings, start: dict, model: pin.Model, warm: dict | None = None,
               verbose: bool = False) -> JumpSolution:
    """Solve the jump (module doc). ``start`` holds the training start (P, t, base, x_L);
    ``model`` is the numeric model the 1 kHz checks use; ``warm`` is a neighbouring solve's
    :meth:`JumpSolution.warm_start`."""
    s, ph, clock = settings, phases, _Clock()
    t0 = time.perf_counter()
    P = start["P"]
    tube0 = tube_times(s, ph)
    opts = ipopt_options(s, verbose)

    def build(objective: str, selection: Selection) -> JumpNLP:
        return build_nlp(robot, layer, blocks, ph, s, P, objective, selection)

    def check(nlp: JumpNLP, w: np.ndarray) -> tuple[dict, dict]:
        traj = trajectory(robot, layer, ph, nlp, w)
        return traj, series(model, traj, robot.mu)

    run1, warm2 = None, None
    if warm is None:
        full = build("feasibility", Selection.every_node_row(s.n_stance + s.n_land, robot.unmirrored.size, tube0))
        x_start = initial_point(robot, layer, full, P, start["t"], start["base"], start["x_L"], ph.takeoff,
                                ph.touchdown)
        nlp_start = full
        if s.two_phase:
            t0 = clock.add("build_s", t0)
            traj, sr = check(full, x_start)
            t0 = clock.add("check_s", t0)
            seed = exchange.seed_selection(full, x_start, traj, sr, robot, ph, s.tube, tube0)
            # phase 1: every row of the nodes (Ipopt takes 3x the iterations with the seed's alone) and
            # the seed's flight samples
            first = full.selection.merged(Selection(full.selection.node_torque, full.selection.node_polygon,
                                                    seed.contact[:0], seed.contact_torque[:0],
                                                    seed.contact_polygon[:0], seed.flight, seed.flight_torque,
                                                    seed.tube))
            nlp1 = build("feasibility", first)
            x1, _ = carried_point(full, nlp1, x_start)
            t0 = clock.add("build_s", t0)
            run1 = ipopt.solve(nlp1.nlp, x1, nlp1.lbx, nlp1.ubx, nlp1.lbg, nlp1.ubg, opts,
                               desc=f"broad jump, delta {s.tube:g}: phase 1 (feasible)")
            t0 = clock.add("solve_s", t0)
            x_start, nlp_start = run1.x, nlp1
    else:
        nlp_start, x_start = warm["nlp"], np.asarray(warm["x0"], float)
        if x_start.size != nlp_start.variables.n:
            raise ValueError(f"warm start: its point has {x_start.size} variables, its NLP {nlp_start.variables.n}")
    t0 = clock.add("build_s", t0)
    traj, sr = check(nlp_start, x_start)
    t0 = clock.add("check_s", t0)
    # phase 2: the start's rows and samples with every row on the packaged grids (rows only where
    # they are near binding at the start took 2-3x the iterations in the exchange's later rounds)
    selection = exchange.with_samples(nlp_start.selection, contact_sample_grid(s, ph), flight_sample_grid(s, ph))
    nlp2 = build("distance", selection)
    x, lam_x = carried_point(nlp_start, nlp2, x_start, warm.get("lam_x0") if warm else None)
    if warm is not None:
        warm2 = {"x0": x, "lam_x0": lam_x, "lam_g0": carried_multipliers(nlp_start, nlp2, warm["lam_g0"])}
    t0 = clock.add("build_s", t0)
    rounds: list[dict] = []
    convergence = [{"phase": "1", "round": 1, "history": run1.history}] if run1 else []
    while True:
        run2 = ipopt.solve(nlp2.nlp, x, nlp2.lbx, nlp2.ubx, nlp2.lbg, nlp2.ubg, opts, warm=warm2,
                           desc=f"broad jump, delta {s.tube:g}: phase 2 (distance), round {len(rounds) + 1}")
        t0 = clock.add("solve_s", t0)
        traj, sr = check(nlp2, run2.x)
        worst = exchange.violations(sr, traj, s.tube, robot.weight)
        t0 = clock.add("check_s", t0)
        rounds.append({**_run_summary(run2, nlp2), "violation_1khz": worst})
        convergence.append({"phase": "2", "round": len(rounds), "history": run2.history})
        if not s.exchange or not run2.success or not exchange.violated(worst) or len(rounds) >= s.exchange_rounds:
            break
        more = nlp2.selection.merged(exchange.chosen_rows(nlp2, run2.x, traj, sr, robot, ph, s.tube, exchange.NEAR))
        if more.rows() == nlp2.selection.rows() and len(more.contact) == len(nlp2.selection.contact):
            break  # nothing new to add: the violations are in what the rows already hold to tolerance
        old, nlp2 = nlp2, build("distance", more)
        x, lam_x = carried_point(old, nlp2, run2.x, run2.lam_x)
        warm2 = {"x0": x, "lam_x0": lam_x, "lam_g0": carried_multipliers(old, nlp2, run2.lam_g)}
        t0 = clock.add("build_s", t0)
    w = run2.x
    viol = np.maximum(nlp2.lbg - run2.g, 0) + np.maximum(run2.g - nlp2.ubg, 0)
    worst_kind: dict[str, float] = {}
    binding: dict[str, float] = {}
    for name, v, lam in zip(nlp2.row_names, viol, np.abs(run2.lam_g)):
        worst_kind[name] = max(worst_kind.get(name, 0.0), float(v))
        binding[name] = binding.get(name, 0.0) + float(lam)
    result = {
        "tube": s.tube, "status": run2.status, "success": run2.success,
        "iterations": sum(r["iterations"] for r in rounds) + (run1.iterations if run1 else 0),
        "times": dict(clock.parts), "objective": run2.f, "distance": float(nlp2.variables.unpack(w)["x_L"][0]),
        "max_constraint_violation": float(viol.max(initial=0.0)), "constraint_violation_by_kind": worst_kind,
        # sum of |multiplier| per row kind: what binds (torque rows in units of each joint's limit range)
        "multiplier_by_kind": binding, "warm_start": warm is not None,
        "phase1": _run_summary(run1, nlp_start) if run1 else {}, "phase2_rounds": rounds,
        "n_variables": int(nlp2.variables.n), "n_constraints": int(nlp2.nlp.m), "settings": asdict(s),
        "convergence": convergence,
    }
    return JumpSolution(nlp2, w, run2, run1, traj, sr, result)
