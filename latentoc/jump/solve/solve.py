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
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from latentoc.latent.gp_layer import Layer
from latentoc.nlp import ipopt
from latentoc.nlp.blocks import RobotBlock
from latentoc.nlp.exchange_rounds import Exchange, exchange_rounds
from latentoc.jump.solve import exchange
from latentoc.jump.check.export import trajectory
from latentoc.jump.transcription.nlp import JumpNLP, build_nlp
from latentoc.jump.schedule.phases import Phases, contact_sample_grid, flight_sample_grid
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.transcription.selection import Selection
from latentoc.jump.settings import JumpSettings
from latentoc.jump.solve.consistent_path import consistent_path
from latentoc.jump.solve.initial_point import initial_point
from latentoc.jump.check.verify import series
from latentoc.jump.solve.warm import carried_multipliers, carried_point

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


class _Solve:
    """One tube's solve: its clock, how it builds, checks and runs Ipopt (:func:`solve_jump`)."""

    def __init__(self, robot: JumpRobot, layer: Layer, blocks: dict[str, RobotBlock], phases: Phases,
                 settings: JumpSettings, start: dict, model: pin.Model, verbose: bool):
        self.robot, self.layer, self.blocks, self.ph, self.s = robot, layer, blocks, phases, settings
        self.start, self.model, self.clock = start, model, _Clock()
        self.opts = ipopt_options(settings, verbose)
        self.t0 = time.perf_counter()
        self.last_check: tuple[JumpNLP, np.ndarray, dict, dict] | None = None
        self.consistent: dict = {}  # the consistent start's residuals (:mod:`.consistent_path`)
        self.start_violation: dict[str, float] = {}  # phase 1's rows at its start: the worst per row kind

    def lap(self, part: str) -> None:
        self.t0 = self.clock.add(part, self.t0)

    def build(self, objective: str, selection: Selection | None = None) -> JumpNLP:
        nlp = build_nlp(self.robot, self.layer, self.blocks, self.ph, self.s, self.start["P"], objective, selection,
                        self.start.get("P_range"))
        self.lap("build_s")
        return nlp

    def check(self, nlp: JumpNLP, w: np.ndarray) -> tuple[dict, dict, np.ndarray]:
        """The export of ``w`` on the 1 kHz grid, its constraints' slack there and the unloaded points'
        clearance (:func:`.exchange.clearance`)."""
        traj = trajectory(self.robot, self.layer, self.ph, nlp, w)
        sr = series(self.model, traj, self.robot.mu)
        place = exchange.clearance(sr, traj, self.robot, self.ph)
        self.last_check = (nlp, w, traj, sr)
        self.lap("check_s")
        return traj, sr, place

    def run_ipopt(self, nlp: JumpNLP, x: np.ndarray, warm: dict | None, what: str) -> ipopt.IpoptResult:
        run = ipopt.solve(nlp.nlp, x, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg, self.opts, warm=warm,
                          desc=f"broad jump, delta {self.s.tube:g}: {what}")
        self.lap("solve_s")
        return run

    def phase1(self) -> tuple[JumpNLP, np.ndarray, ipopt.IpoptResult]:
        """The training start and the feasible point nearest it: every row of the
        nodes (Ipopt takes 3x the iterations with only those near binding) and the flight samples
        near binding at the start."""
        s, st = self.s, self.start
        full = self.build("feasibility")  # every node row and the tube: build_nlp's default selection
        P, x_L = st["P"], st["x_L"]
        if self.layer.has_tube:  # the latent path moved least so that its contacts are physical
            base = full.spline.fit(st["t"], st["base"])
            P, x_L, self.consistent = consistent_path(self.robot, self.layer, full.spline, self.ph, P, x_L,
                                                      lambda t: full.spline.evaluate(base, t, 2), s.tube,
                                                      columns=self.layer.latent_coordinates)
        x = initial_point(self.robot, self.layer, full, self.ph, P, x_L)
        self.lap("build_s")
        traj, sr, place = self.check(full, x)
        nlp1 = self.build("feasibility", exchange.seed_selection(full, x, traj, sr, place, self.robot, self.ph))
        x1, _ = carried_point(full, nlp1, x)
        self.start_violation = _violation_by_kind(nlp1, nlp1.nlp.constraints(x1))
        run1 = self.run_ipopt(nlp1, x1, None, "phase 1 (feasible)")
        return nlp1, run1.x, run1

    def phase2(self, nlp_start: JumpNLP, x_start: np.ndarray, warm: dict | None
               ) -> tuple[JumpNLP, ipopt.IpoptResult, list[dict]]:
        """The distance from ``x_start`` in rounds of the exchange: the start's rows and samples with
        every row on the packaged grids (rows only where they are near binding at the start took 2-3x
        the iterations in the later rounds), then the rows the 1 kHz checks add."""
        s, ph = self.s, self.ph
        selection = nlp_start.selection.with_samples(contact_sample_grid(s, ph), flight_sample_grid(s, ph))
        nlp2 = self.build("distance", selection)
        x, lam_x = carried_point(nlp_start, nlp2, x_start, warm.get("lam_x0") if warm else None)
        start: dict = {"x0": x}
        if warm is not None:
            start.update(lam_x0=lam_x, lam_g0=carried_multipliers(nlp_start, nlp2, warm["lam_g0"]))
        self.lap("build_s")

        def check(nlp: JumpNLP, run: ipopt.IpoptResult) -> tuple[Selection | None, dict[str, float]]:
            traj, sr, place = self.check(nlp, run.x)
            return exchange.grown_selection(nlp, run.x, traj, sr, place, self.robot, ph)

        def resume(old: JumpNLP, new: JumpNLP, run: ipopt.IpoptResult) -> dict:
            x, lam_x = carried_point(old, new, run.x, run.lam_x)
            self.lap("build_s")
            return {"x0": x, "lam_x0": lam_x, "lam_g0": carried_multipliers(old, new, run.lam_g)}

        def solve(nlp: JumpNLP, start: dict) -> ipopt.IpoptResult:
            warm_start = start if "lam_g0" in start else None
            return self.run_ipopt(nlp, start["x0"], warm_start, "phase 2 (distance)")

        kind = Exchange(solve=solve, record=lambda nlp, run: {**_run_summary(run, nlp), "history": run.history}, check=check,
                        grow=lambda nlp, more: self.build("distance", more), resume=resume)
        return exchange_rounds(nlp2, start, kind, exchange.EXCHANGE_ROUNDS)


def solve_jump(robot: JumpRobot, layer: Layer, blocks: dict[str, RobotBlock], phases: Phases,
               settings: JumpSettings, start: dict, model: pin.Model, warm: dict | None = None,
               verbose: bool = False) -> JumpSolution:
    """Solve the jump (module doc) along the path of ``layer`` (:mod:`..schedule.path`). ``start`` holds the
    training start (P, t, base, x_L) and, for a joint path, the control points' ``P_range``;
    ``model`` is the numeric model the 1 kHz checks use; ``warm`` is a neighbouring solve's
    :meth:`JumpSolution.warm_start`."""
    js = _Solve(robot, layer, blocks, phases, settings, start, model, verbose)
    if warm is None:
        nlp_start, x_start, run1 = js.phase1()
    else:
        nlp_start, x_start, run1 = warm["nlp"], np.asarray(warm["x0"], float), None
        if x_start.size != nlp_start.variables.n:
            raise ValueError(f"warm start: its point has {x_start.size} variables, its NLP {nlp_start.variables.n}")
    nlp2, run2, rounds = js.phase2(nlp_start, x_start, warm)
    if js.last_check is None or js.last_check[0] is not nlp2 or js.last_check[1] is not run2.x:
        js.check(nlp2, run2.x)  # a failed last run: its export all the same
    _, w, traj, sr = js.last_check  # type: ignore[misc]
    convergence = [{"phase": "1", "round": 1, "history": run1.history}] if run1 else []
    convergence += [{"phase": "2", "round": k + 1, "history": r.pop("history")} for k, r in enumerate(rounds)]
    result = _result(nlp2, run2, rounds, run1, nlp_start, warm is not None, js.clock)
    result["convergence"] = convergence
    result["consistent_start"] = js.consistent
    result["start_violation"] = js.start_violation
    return JumpSolution(nlp2, w, run2, run1, traj, sr, result)


def _violation_by_kind(nlp: JumpNLP, g: np.ndarray) -> dict[str, float]:
    """The largest violation of each kind of row of ``nlp`` at constraint values ``g`` (each in its
    row's own unit), and of all (``"max"``)."""
    viol = np.maximum(nlp.lbg - g, 0) + np.maximum(g - nlp.ubg, 0)
    out: dict[str, float] = {"max": float(viol.max(initial=0.0))}
    for name, v in zip(nlp.row_names, viol):
        out[name] = max(out.get(name, 0.0), float(v))
    return out


def _result(nlp2: JumpNLP, run2: ipopt.IpoptResult, rounds: list[dict],
            run1: ipopt.IpoptResult | None, nlp1: JumpNLP, warm: bool, clock: _Clock) -> dict:
    """The solve's result fields (:class:`JumpSolution`)."""
    worst_kind = _violation_by_kind(nlp2, run2.g)
    worst = worst_kind.pop("max")
    binding: dict[str, float] = {}
    for name, lam in zip(nlp2.row_names, np.abs(run2.lam_g)):
        binding[name] = binding.get(name, 0.0) + float(lam)
    return {
        "tube": nlp2.settings.tube, "status": run2.status, "success": run2.success,
        "iterations": sum(r["iterations"] for r in rounds) + (run1.iterations if run1 else 0),
        "times": dict(clock.parts), "objective": run2.f, "distance": float(nlp2.variables.unpack(run2.x)["x_L"][0]),
        "max_constraint_violation": worst, "constraint_violation_by_kind": worst_kind,
        # sum of |multiplier| per row kind: what binds (torque rows in units of each joint's limit range)
        "multiplier_by_kind": binding, "warm_start": warm,
        "phase1": _run_summary(run1, nlp1) if run1 else {}, "phase2_rounds": rounds,
        "n_variables": int(nlp2.variables.n), "n_constraints": int(nlp2.nlp.m),
    }
