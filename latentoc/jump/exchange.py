"""Rows only where they can bind: the exchange between the NLP's selection and the 1 kHz checks.

A solve starts with the rows that are within a margin of binding at its start point (the seed)
and, after each converged solve, re-checks every hard constraint on the exported 1 kHz motion
with numeric Pinocchio (:mod:`.export`, :func:`.verify.series`): torque limits, the needed
wrench's cone and centre of pressure, the exported point forces' cones and their balance of the
base rows, the ZMP and the COM in the support polygon, the tube and, with sticking contacts, the
feet's placement (:func:`placement`). Every violated or nearly violated stretch adds a sample at its
worst 1 kHz time and its neighbours (contact: its own edge weights and the rows that are near
there; flight: its own free-fall variables and torque rows; the tube: a point), and the contact
nodes' own torque and polygon rows that are near are switched on; then the solve resumes warm
(:mod:`.warm`). It ends when nothing on the 1 kHz grid is violated beyond :data:`TOLERANCE`
(the loop: :func:`latentoc.nlp.exchange.exchange_rounds`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..nlp.evaluators import BlockEvaluator
from ..nlp.exchange import TUBE_TOL, worst_times
from .nlp import JumpNLP
from .phases import Phases
from .robot import JumpRobot
from .selection import POLYGON_EDGES, Selection
from .settings import JumpSettings

__all__ = ["Margins", "SEED", "NEAR", "TOLERANCE", "placement", "violations", "violated", "chosen_rows", "seed_selection", "with_samples", "NEIGHBOUR", "SPACING"]

NEIGHBOUR = 0.002  # s: either side of a short stretch's worst time (a bound moves a little)
SPACING = 0.005  # s between the samples along a stretch that comes near


@dataclass(frozen=True)
class Margins:
    """How close to binding a row must come to be chosen: torque (fraction of the joint's limit
    range), wrench (body weights: needed normal force, friction cone, point cones), cop,
    polygon and placement (m), tube (fraction of delta), dynamics (body weights: the base rows'
    residual with the exported point forces, a contact time past it gets its own forces)."""

    torque: float
    wrench: float
    cop: float
    polygon: float
    tube: float
    placement: float
    dynamics: float


SEED = Margins(torque=0.25, wrench=0.05, cop=0.01, polygon=0.02, tube=0.05, placement=0.0, dynamics=1e-6)  # at a phase's start
NEAR = Margins(torque=0.05, wrench=0.01, cop=0.002, polygon=0.002, tube=0.005, placement=0.0, dynamics=1e-6)  # after a solve
# what counts as violated on the 1 kHz grid (torque in N m, wrench in N, lengths in m, tube in delta):
# far below what the physics can tell apart, and above what Ipopt holds the rows to
TOLERANCE = Margins(torque=0.01, wrench=0.1, cop=1e-4, polygon=1e-5, tube=TUBE_TOL, placement=1e-5, dynamics=1e-6)


def _allowed(idx: np.ndarray, allowed: np.ndarray) -> np.ndarray:
    return idx[allowed[idx]] if len(idx) else idx


def _rel_torque(sr: dict[str, np.ndarray], robot: JumpRobot) -> np.ndarray:
    """Torque slack of the kept joints in units of their limit range (n x kept)."""
    kept = robot.unmirrored
    return sr["torque"][:, kept] / robot.torque_scale[kept]


def placement(sr: dict[str, np.ndarray], traj: dict, x_L: float, robot: JumpRobot, phases: Phases,
              s: JumpSettings) -> np.ndarray:
    """The foot placement rows' slack on the 1 kHz grid (n x 7, m, NaN where a row does not apply),
    the numeric twin of :func:`.rows.contact._placement_at`: the toe tip's x from its ground point and
    its height, the heel and ball heights, the pad's while the ball is off the ground, the toe tip's
    and the rearmost loaded point's sideways offsets."""
    t, P = np.asarray(traj["t"]), sr["points"]  # (n, 4, 3): heel, ball, toe, pad
    contact = np.asarray(traj["contact"]).astype(bool)
    fp = robot.geom.footprint
    assert fp is not None
    x_pin = np.where(t >= phases.touchdown - 1e-9, x_L, 0.0)
    on = {p: phases.loaded(p, t) for p in ("heel", "ball", "pad")}
    ct, bt, ft = s.contact_tolerance, s.ball_tolerance, s.foot_tolerance
    out = np.full((len(t), 7), np.nan)
    out[:, 0] = ft - np.abs(P[:, 2, 0] - x_pin)
    out[:, 1] = ft - np.abs(P[:, 2, 2] - fp[2, 2])  # heights above the standing ones
    for c, k, point in ((2, 0, "heel"), (3, 1, "ball")):  # loaded: within ct of the ground; unloaded: above it
        z = P[:, k, 2] - fp[2, k]
        out[:, c] = np.where(on[point], ct - np.abs(z), z + (ct if point == "heel" else bt))
    out[:, 4] = ct - np.abs(P[:, 2, 1] - fp[1, 2])
    # the rearmost loaded point's sideways offset: the heel's, else the ball's, else the pad's
    yaw = np.select([on["heel"], on["ball"], on["pad"]], [P[:, k, 1] - fp[1, k] for k in (0, 1, 3)], np.nan)
    out[:, 5] = ct - np.abs(yaw)
    pad = P[:, 3, 2] - fp[2, 3]
    out[:, 6] = np.where(on["ball"], np.nan, np.where(on["pad"], ct - np.abs(pad), pad + bt))
    out[~contact] = np.nan
    return out


def violations(sr: dict[str, np.ndarray], traj: dict, delta: float, weight: float,
               placement_slack: np.ndarray | None = None) -> dict[str, float]:
    """The worst violation of each checked kind on the 1 kHz grid (0: held), in N m, N, m and delta."""
    def worst(x: np.ndarray) -> float:
        return float(max(0.0, -np.nanmin(x))) if np.isfinite(x).any() else 0.0

    return {"torque": worst(sr["torque"]), "normal": worst(sr["normal"]), "friction": worst(sr["friction"]),
            "point_cone": worst(sr["point_cone"]), "cop": worst(sr["cop_loaded"]), "zmp": worst(sr["zmp"]),
            "com": worst(sr["com"]), "tube": float(max(0.0, np.max(traj["sigma2"]) / delta - 1.0)) if "sigma2" in traj
            else 0.0, "placement": 0.0 if placement_slack is None else worst(placement_slack),
            "dynamics": float(np.max(sr["residual"][np.asarray(traj["contact"]).astype(bool)], initial=0.0)) / weight}


def violated(v: dict[str, float]) -> bool:
    """Whether any kind is violated beyond :data:`TOLERANCE`."""
    tol = {"torque": TOLERANCE.torque, "normal": TOLERANCE.wrench, "friction": TOLERANCE.wrench,
           "point_cone": TOLERANCE.wrench, "cop": TOLERANCE.cop, "zmp": TOLERANCE.polygon, "com": TOLERANCE.polygon,
           "tube": TOLERANCE.tube, "placement": TOLERANCE.placement, "dynamics": TOLERANCE.dynamics}
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
    polygon[tc < phases.touchdown - 1e-9] = False
    polygon[tc < phases.settle - 1e-9, POLYGON_EDGES:] = False
    return torque, polygon


def chosen_rows(nlp: JumpNLP, w: np.ndarray, traj: dict, sr: dict[str, np.ndarray], place: np.ndarray | None,
                robot: JumpRobot, phases: Phases, s: JumpSettings, m: Margins) -> Selection:
    """The rows within the margins ``m`` of binding at ``w`` (module doc): the contact nodes' own
    rows, and samples at the worst 1 kHz time of each stretch that comes that near; ``place``: the
    foot placement's slack (:func:`placement`, None without sticking contacts)."""
    delta = s.tube
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
    if place is not None:  # the feet between the samples: where a placement row is violated
        for c in range(place.shape[1]):
            picked_c.update(worst_times(place[:, c], place[:, c] < m.placement, every, nb).tolist())
    kc = _allowed(np.array(sorted(picked_c), int), contact & inside)
    kf = _allowed(np.array(sorted(picked_f), int), ~contact & inside)
    kt = np.zeros(0, int)
    if "sigma2" in traj:  # a latent path: the tube
        sigma = np.asarray(traj["sigma2"]) / delta
        kt = _allowed(worst_times(-sigma, (sigma > 1.0 - m.tube) & inside, every, nb), inside)
    node_torque, node_polygon = _node_rows(nlp, w, robot, phases, m)
    return Selection(node_torque, node_polygon, t[kc], torque_near[kc], poly_near[kc], t[kf], torque_near[kf], t[kt])


def seed_selection(nlp: JumpNLP, w: np.ndarray, traj: dict, sr: dict[str, np.ndarray], place: np.ndarray | None,
                   robot: JumpRobot, phases: Phases, s: JumpSettings, tube: np.ndarray) -> Selection:
    """A phase's first selection: the rows within :data:`SEED` of binding at its start ``w``, and
    the tube at ``tube``."""
    seed = chosen_rows(nlp, w, traj, sr, place, robot, phases, s, SEED)
    return seed.merged(Selection.empty(seed.node_torque.shape[0], seed.n_joints, tube))


def with_samples(selection: Selection, contact: np.ndarray, flight: np.ndarray) -> Selection:
    """``selection`` with contact samples at ``contact`` and flight samples at ``flight``, each with
    every torque row (and the contact samples every polygon row that applies)."""
    nj, npoly = selection.n_joints, 2 * POLYGON_EDGES
    return selection.merged(Selection(np.zeros_like(selection.node_torque), np.zeros_like(selection.node_polygon),
                                      contact, np.ones((len(contact), nj)), np.ones((len(contact), npoly)),
                                      flight, np.ones((len(flight), nj)), np.zeros(0)))
