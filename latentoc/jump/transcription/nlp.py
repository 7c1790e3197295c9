"""The broad-jump NLP (Sect. 4.2, Eq. 33-36): row families on nodes and samples, bounds, objective.

Joint motion: y = mu_Q(x(t)) along the latent spline (Eq. 18, 26-28, the GP layer; a double knot
at each contact event, :meth:`..schedule.phases.Phases.latent_spline`), or, for the full configuration-space
baseline, the joint spline itself (the identity layer, :mod:`..schedule.path`). In the stance and the landing
the legs are closed and the base follows from the planted body (:mod:`..closure.planted_legs`), which holds its
ground pose exactly; in flight the base falls freely. Hard constraints, each a row family
(:mod:`..rows`), where :class:`~.selection.Selection` puts them:

* contact nodes (stance and landing, every 10 ms): base rows = sum J^T f, the training contact
  schedule (an unloaded point above the ground, carrying no force), and the chosen torque limits
  (Eq. 34) and edges of the support polygon for the ZMP and, once the landing has settled, the COM
  (Eq. 35-36);
* contact samples between the nodes: their own edge weights, the base rows and chosen rows;
* takeoff and touchdown: the flight's state from the stance, the landing at rest; the hinge's
  switches at the heel's lift-off and strike;
* the flight: the pitch integrates the pitch rate of the conserved momentum, the feet stay above
  the ground at the flight nodes, and flight samples hold the free-fall rows and chosen torques;
* the tube sigma^2 <= delta (Eq. 29) at the selection's times (a latent path only).

Objective: phase 1 (``"feasibility"``) the feasible point nearest the training fit; phase 2
(``"distance"``) the jump distance x_L (Eq. 33); both with a tiny force regulariser.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from latentoc.latent.gp_layer import Layer
from latentoc.nlp.assemble import SparseNLP
from latentoc.nlp.blocks import RobotBlock
from latentoc.latent.spline import BSpline
from latentoc.jump.robot.feet import EDGES, POINTS
from latentoc.jump.schedule.phases import Phases, node_grid
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.rows import families, joint_limits
from latentoc.jump.rows.flight import FLIGHT_SUBSTEPS, pitch_grid
from latentoc.jump.rows.tube_rows import TUBE_SPACING
from latentoc.jump.transcription.selection import Selection
from latentoc.jump.settings import JumpSettings
from latentoc.jump.transcription.variables import JumpVariables
from latentoc.jump.transcription.wiring import Wiring

__all__ = ["JumpNLP", "build_nlp", "tube_times", "OBJECTIVES", "FORCE_REGULARISATION"]

OBJECTIVES = ("feasibility", "distance")
FORCE_REGULARISATION = 1e-4
# the rows held this much inside their limits, so that between the samples the 1 kHz grid stays
# inside them: torque in N m, the tube as a fraction of delta
TORQUE_BACKOFF, TUBE_BACKOFF = 0.02, 1e-4


@dataclass
class JumpNLP:
    """A built NLP with its bounds, what each row is, and what a solution is read with.

    Each constraint row has a name (its block output, e.g. ``torque``), a time and a component
    (the joint among the kept ones, the polygon edge, or the output's index): together the row's
    identity across NLPs with other selections (:func:`latentoc.jump.solve.warm.carried`)."""

    nlp: SparseNLP
    variables: JumpVariables
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    row_names: np.ndarray
    row_times: np.ndarray
    row_components: np.ndarray
    grid: dict[str, np.ndarray]
    spline: BSpline
    selection: Selection
    objective: str
    P_fixed: np.ndarray
    tau_fine: np.ndarray  # flight times (from takeoff) of the pitch integration
    settings: JumpSettings  # what it was built with: its nodes, spline and tube (the exchange checks against it)

    def control_points(self, w: np.ndarray) -> np.ndarray:
        """All latent control points of solution ``w``: the fixed end points and the free ones."""
        P = np.array(self.P_fixed, float)
        P[1:-1] = self.variables.unpack(w)["P"]
        return P

    def family_rows(self, name: str) -> slice:
        """The rows of row family ``name`` in the constraint vector (empty if it has none)."""
        off = self.nlp.row_offset.get(name)
        if off is None:
            return slice(0, 0)
        return slice(off, off + next(f.n_rows for f in self.nlp.families if f.name == name))


def tube_times(phases: Phases, layer: Layer) -> np.ndarray:
    """The tube every :data:`~latentoc.jump.rows.tube_rows.TUBE_SPACING` inside the motion (its ends are the fixed end points); none on
    a joint path, which has no GPDM variance."""
    if not layer.has_tube:
        return np.zeros(0)
    T = phases.duration
    return np.linspace(0.0, T, max(2, int(round(T / TUBE_SPACING)) + 1))[1:-1]


def build_nlp(robot: JumpRobot, layer: Layer, blocks: dict[str, RobotBlock], phases: Phases,
              settings: JumpSettings, P_fixed: np.ndarray, objective: str = "distance",
              selection: Selection | None = None, P_range: np.ndarray | None = None) -> JumpNLP:
    """The NLP of one phase of the solve (module doc); ``P_fixed`` holds the spline's end points
    (and the free points' centres), ``selection`` the chosen rows and samples (default: every
    node row, the tube of a latent path, no samples), ``P_range`` the free control points'
    half-widths around ``P_fixed`` (None: unbounded)."""
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
    s, ph = settings, phases
    grid = node_grid(s, ph)
    tc = np.concatenate([grid["stance"], grid["land"]])
    nC, nk = len(tc), len(robot.unmirrored)
    sel = Selection.every_node_row(nC, nk, tube_times(ph, layer)) if selection is None else selection
    if sel.node_torque.shape != (nC, nk):
        raise ValueError(f"the selection is for {sel.node_torque.shape} contact nodes x joints, the NLP has {(nC, nk)}")
    if len(sel.tube) and not layer.has_tube:
        raise ValueError("the selection has tube points but the layer has no sigma^2 (a joint path)")
    spline = ph.latent_spline(s.n_control)
    var = JumpVariables.layout(s.n_control, layer.latent_dim, nC, len(grid["flight"]), len(sel.contact), len(sel.flight))
    w = Wiring(robot, layer, blocks, ph, s, sel, var, spline, np.asarray(P_fixed, float), grid)
    for wire in families():
        wire(w)
    nlp = SparseNLP(var.n, w.families, _objective(var, P_fixed, objective))
    names, times, comps = np.array(w.names), np.array(w.times, float), np.array(w.comps, np.int64)
    lbg, ubg = _row_bounds(names, comps, robot)
    lbx, ubx = _variable_bounds(var, ph, tc, sel.contact)
    if P_range is not None:  # the free control points within +-P_range of P_fixed's (joint range)
        P0 = np.asarray(P_fixed, float)[1:-1]
        half = np.broadcast_to(np.asarray(P_range, float), P0.shape)
        lbx[var.slices["P"]], ubx[var.slices["P"]] = (P0 - half).ravel(), (P0 + half).ravel()
    return JumpNLP(nlp, var, lbx, ubx, lbg, ubg, names, times, comps, grid, spline, sel, objective,
                   np.asarray(P_fixed, float), pitch_grid(grid["flight"] - ph.takeoff, FLIGHT_SUBSTEPS), s)


def _objective(var: JumpVariables, P_fixed: np.ndarray, objective: str) -> ca.Function:
    w = ca.SX.sym("w", var.n)
    lam, lam_s = w[var.slices["lam"]], w[var.slices["lam_sample"]]
    reg = FORCE_REGULARISATION * (ca.sumsqr(lam) + ca.sumsqr(lam_s))
    if objective == "distance":
        f = -w[var.slices["x_L"]] + reg
    else:  # the squared deviation of the free control points from the training fit
        P0 = np.asarray(P_fixed, float)[1:-1].ravel()
        f = ca.sumsqr(w[var.slices["P"]] - P0) / max(float(np.mean(np.square(P_fixed))), 1e-12) + reg
    return ca.Function("jump_objective", [w], [f])


def _row_bounds(names: np.ndarray, comps: np.ndarray, robot: JumpRobot) -> tuple[np.ndarray, np.ndarray]:
    bounds = {"dynamics": (0, 0), "flight_base": (0, 0), "flight_pitch": (0, 0), "height": (0, np.inf),
              "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0), "takeoff": (0, 0), "closure_gap": (0, 0),
              "pitch_integration": (0, 0), "flight_clearance": (0, np.inf), "touchdown_position": (0, 0),
              "touchdown_velocity": (0, 0), "hinge_switch": (0, 0), "tube": (-np.inf, 1.0 - TUBE_BACKOFF),
              "pitch_rate": (0, 0), **{k: (0, np.inf) for k in ("cop_front", "cop_heel", "cop_ball", "cop_pad")}}
    lbg, ubg = np.zeros(len(names)), np.zeros(len(names))
    for k, (lo, hi) in bounds.items():
        sel = names == k
        lbg[sel], ubg[sel] = lo, hi
    torque = names == "torque"  # components: positions among the active joints
    act, scale = robot.active, robot.torque_scale
    lbg[torque] = (robot.limits.tau_min[act][comps[torque]] + TORQUE_BACKOFF) / scale[comps[torque]]
    ubg[torque] = (robot.limits.tau_max[act][comps[torque]] - TORQUE_BACKOFF) / scale[comps[torque]]
    joint_limits.bounds(robot, names, comps, lbg, ubg)
    return lbg, ubg


def _variable_bounds(var: JumpVariables, ph: Phases, tc: np.ndarray, t_samples: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Edge weights >= 0; an unloaded heel or ball (contact schedule) carries none."""
    lbx, ubx = np.full(var.n, -np.inf), np.full(var.n, np.inf)
    for name, times in (("lam", tc), ("lam_sample", t_samples)):
        lbx[var.slices[name]] = 0.0
        ub = ubx[var.slices[name]].reshape(len(times), EDGES)  # a view
        for k, point in enumerate(POINTS):
            ub[~ph.loaded(point, times), 2 * k:2 * k + 2] = 0.0
    return lbx, ubx
