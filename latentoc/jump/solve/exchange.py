"""Rows only where they can bind: the exchange between the NLP's selection and the 1 kHz checks.

A solve starts with the rows that are within a margin of binding at its start point (the seed)
and, after each converged solve, re-checks every hard constraint on the exported 1 kHz motion
with numeric Pinocchio (:mod:`..check.export`, :func:`..check.verify.series`): torque limits, the needed
wrench's cone and centre of pressure, the exported point forces' cones and their balance of the
base rows, the ZMP and the COM in the support polygon, the tube and the unloaded points' clearance
of the ground (:func:`clearance`; the loaded ones hold theirs by construction). Every violated or nearly violated stretch adds a sample at its
worst 1 kHz time and its neighbours (contact: its own edge weights and the rows that are near
there; flight: its own free-fall variables and torque rows; the tube: a point), and the contact
nodes' own torque and polygon rows that are near are switched on; then the solve resumes warm
(:mod:`.warm`). It ends when nothing on the 1 kHz grid is violated beyond :data:`TOLERANCE`, or
after :data:`EXCHANGE_ROUNDS` runs (the loop: :func:`latentoc.nlp.exchange_rounds.exchange_rounds`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from latentoc.nlp.evaluators import BlockEvaluator
from latentoc.nlp.exchange_rounds import TUBE_TOL, worst_times
from latentoc.jump.robot.feet import POINTS
from latentoc.jump.transcription.nlp import JumpNLP
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.transcription.selection import POLYGON_EDGES, Selection

__all__ = ["Margins", "SEED", "NEAR", "TOLERANCE", "clearance", "violations", "violated", "chosen_rows", "seed_selection", "grown_selection", "NEIGHBOUR", "SPACING", "EXCHANGE_ROUNDS"]

NEIGHBOUR = 0.002  # s: either side of a short stretch's worst time (a bound moves a little)
SPACING = 0.005  # s between the samples along a stretch that comes near
EXCHANGE_ROUNDS = 8  # phase 2's Ipopt runs at the most


@dataclass(frozen=True)
class Margins:
    """How close to binding a row must come to be chosen: torque (fraction of the joint's limit
    range), wrench (body weights: needed normal force, friction cone, point cones), cop,
    polygon and clearance (m), tube (fraction of delta), dynamics (body weights: the base rows'
    residual with the exported point forces, a contact time past it gets its own forces)."""

    torque: float
    wrench: float
    cop: float
    polygon: float
    tube: float
    clearance: float
    dynamics: float


SEED = Margins(torque=0.25, wrench=0.05, cop=0.01, polygon=0.02, tube=0.05, clearance=0.0, dynamics=1e-6)  # at a phase's start
NEAR = Margins(torque=0.05, wrench=0.01, cop=0.002, polygon=0.002, tube=0.005, clearance=0.0, dynamics=1e-6)  # after a solve
# what counts as violated on the 1 kHz grid (torque in N m, wrench in N, lengths in m, tube in delta):
# far below what the physics can tell apart, and above what Ipopt holds the rows to
TOLERANCE = Margins(torque=0.01, wrench=0.1, cop=1e-4, polygon=1e-5, tube=TUBE_TOL, clearance=1e-5, dynamics=1e-6)


def _allowed(idx: np.ndarray, allowed: np.ndarray) -> np.ndarray:
    return idx[allowed[idx]] if len(idx) else idx


def _rel_torque(sr: dict[str, np.ndarray], robot: JumpRobot) -> np.ndarray:
    """Torque slack of the kept joints in units of their limit range (n x kept)."""
    kept = robot.unmirrored
    return sr["torque"][:, kept] / robot.torque_scale[kept]


def clearance(sr: dict[str, np.ndarray], traj: dict, robot: JumpRobot, phases: Phases) -> np.ndarray:
    """The unloaded points' heights above their standing ones in the contact phases on the 1 kHz grid
    (n x 4, m, NaN where a point is loaded or in flight), the numeric twin of
    :func:`..rows.contact._clearance_at`."""
    t, P = np.asarray(traj["t"]), sr["points"]  # (n, 4, 3): heel, ball, toe, pad
    contact = np.asarray(traj["contact"]).astype(bool)
    assert robot.geom.footprint is not None
    out = P[:, :, 2] - robot.geom.footprint[2][None, :]
    for k, p in enumerate(POINTS):
        out[phases.loaded(p, t) | ~contact, k] = np.nan
    return out


def violations(sr: dict[str, np.ndarray], traj: dict, delta: float, weight: float, clearance_slack: np.ndarray
               ) -> dict[str, float]:
    """The worst violation of each checked kind on the 1 kHz grid (0: held), in N m, N, m and delta."""
    def worst(x: np.ndarray) -> float:
        return float(max(0.0, -np.nanmin(x))) if np.isfinite(x).any() else 0.0

    return {"torque": worst(sr["torque"]), "normal": worst(sr["normal"]), "friction": worst(sr["friction"]),
            "point_cone": worst(sr["point_cone"]), "cop": worst(sr["cop_loaded"]), "zmp": worst(sr["zmp"]),
            "com": worst(sr["com"]), "tube": float(max(0.0, np.max(traj["sigma2"]) / delta - 1.0)) if "sigma2" in traj
            else 0.0, "clearance": worst(clearance_slack),
            "dynamics": float(np.max(sr["residual"][np.asarray(traj["contact"]).astype(bool)], initial=0.0)) / weight}


def violated(v: dict[str, float]) -> bool:
    """Whether any kind is violated beyond :data:`TOLERANCE`."""
    tol = {"torque": TOLERANCE.torque, "normal": TOLERANCE.wrench, "friction": TOLERANCE.wrench,
           "point_cone": TOLERANCE.wrench, "cop": TOLERANCE.cop, "zmp": TOLERANCE.polygon, "com": TOLERANCE.polygon,
           "tube": TOLERANCE.tube, "clearance": TOLERANCE.clearance, "dynamics": TOLERANCE.dynamics}
    return any(v[k] > tol[k] for k in tol)


def _node_rows(nlp: JumpNLP, w: np.ndarray, robot: JumpRobot, phases: Phases, m: Margins
               ) -> tuple[np.ndarray, np.ndarray]:
    """The contact nodes' torque and polygon rows within the margins at ``w``, from every output of
    their block (chosen or not)."""
    fam = next(f for f in nlp.nlp.families if f.name == "contact")
    ev = fam.evaluator
    assert isinstance(ev, BlockEvaluator)
    F = ev.values(fam.local_inputs(w))
    layout = ev.block.layout
    kept = robot.unmirrored
    tau = F[:, layout["torque"]][:, kept]
    lo, hi = robot.limits.tau_min[robot.active][kept], robot.limits.tau_max[robot.active][kept]
    torque = np.minimum(tau - lo, hi - tau) / robot.torque_scale[kept] < m.torque
    tc = np.concatenate([nlp.grid["stance"], nlp.grid["land"]])
    polygon = np.hstack([-F[:, layout["zmp_polygon"]], -F[:, layout["com_polygon"]]]) < m.polygon
    polygon[~phases.landed(tc)] = False
    polygon[~phases.settled(tc), POLYGON_EDGES:] = False
    return torque, polygon


def chosen_rows(nlp: JumpNLP, w: np.ndarray, traj: dict, sr: dict[str, np.ndarray], place: np.ndarray,
                robot: JumpRobot, phases: Phases, m: Margins) -> Selection:
    """The rows within the margins ``m`` of binding at ``w`` (module doc): the contact nodes' own
    rows, and samples at the worst 1 kHz time of each stretch that comes that near; ``place``: the
    unloaded points' clearance (:func:`clearance`)."""
    t = np.asarray(traj["t"])
    contact = np.asarray(traj["contact"]).astype(bool)
    inside = (t > 0) & (t < phases.duration)
    W = robot.weight
    every = max(1, int(round(SPACING / (t[1] - t[0]))))
    nb = max(1, int(round(NEIGHBOUR / (t[1] - t[0]))))
    rel = _rel_torque(sr, robot)
    torque_near = rel < m.torque
    picked_c: set[int] = set()
    picked_f: set[int] = set()
    for j in range(rel.shape[1]):
        for k in worst_times(rel[:, j], torque_near[:, j] & inside, every, nb):
            (picked_c if contact[k] else picked_f).add(k)
    wrench = {"normal": (sr["normal"] / W, m.wrench), "friction": (sr["friction"] / W, m.wrench),
              "point_cone": (sr["point_cone"] / W, m.wrench), "cop_loaded": (sr["cop_loaded"], m.cop)}
    for x, thr in wrench.values():
        picked_c.update(worst_times(x, (x < thr) & contact & inside, every, nb).tolist())
    residual = sr["residual"] / W  # where the exported point forces do not balance the base rows
    picked_c.update(worst_times(-residual, (residual > m.dynamics) & contact & inside, every, nb).tolist())
    poly = np.hstack([sr["zmp"], sr["com"]])
    poly_near = poly < m.polygon  # NaN: False
    for e in range(poly.shape[1]):
        picked_c.update(worst_times(poly[:, e], poly_near[:, e] & inside, every, nb).tolist())
    for c in range(place.shape[1]):  # the unloaded points between the samples: where one comes near the ground
        picked_c.update(worst_times(place[:, c], place[:, c] < m.clearance, every, nb).tolist())
    kc = _allowed(np.array(sorted(picked_c), int), contact & inside)
    kf = _allowed(np.array(sorted(picked_f), int), ~contact & inside)
    kt = np.zeros(0, int)
    if "sigma2" in traj:  # a latent path: the tube
        sigma = np.asarray(traj["sigma2"]) / nlp.settings.tube
        kt = _allowed(worst_times(-sigma, (sigma > 1.0 - m.tube) & inside, every, nb), inside)
    node_torque, node_polygon = _node_rows(nlp, w, robot, phases, m)
    return Selection(node_torque, node_polygon, t[kc], torque_near[kc], poly_near[kc], t[kf], torque_near[kf], t[kt])


def seed_selection(nlp: JumpNLP, w: np.ndarray, traj: dict, sr: dict[str, np.ndarray], place: np.ndarray,
                   robot: JumpRobot, phases: Phases) -> Selection:
    """Phase 1's selection from the full transcription ``nlp`` (every node row, the tube) at its start
    ``w``: every node row and the tube, and the flight samples within :data:`SEED` of binding there
    (no contact samples)."""
    nodes = nlp.selection
    seed = chosen_rows(nlp, w, traj, sr, place, robot, phases, SEED)
    seed = seed.merged(Selection.empty(seed.node_torque.shape[0], seed.n_joints, nodes.tube))
    return nodes.merged(Selection(nodes.node_torque, nodes.node_polygon, seed.contact[:0], seed.contact_torque[:0],
                                  seed.contact_polygon[:0], seed.flight, seed.flight_torque, seed.tube))


def grown_selection(nlp: JumpNLP, w: np.ndarray, traj: dict, sr: dict[str, np.ndarray], place: np.ndarray,
                    robot: JumpRobot, phases: Phases) -> tuple[Selection | None, dict[str, float]]:
    """After a solve of ``nlp`` to ``w``: the worst violation of each kind on the 1 kHz grid
    (:func:`violations`) and, where one is violated, ``nlp``'s selection with the rows within
    :data:`NEAR` of binding (:func:`chosen_rows`); None where nothing is violated or nothing new
    is added (the rows hold to Ipopt's tolerance)."""
    worst = violations(sr, traj, nlp.settings.tube, robot.weight, place)
    if not violated(worst):
        return None, worst
    more = nlp.selection.merged(chosen_rows(nlp, w, traj, sr, place, robot, phases, NEAR))
    grown = more.rows() > nlp.selection.rows() or len(more.contact) > len(nlp.selection.contact)
    return (more if grown else None), worst
