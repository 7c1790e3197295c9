"""The broad-jump NLP (Sect. 4.2, Eq. 33-36): row families on nodes and samples, bounds, objective.

Joint motion: y = mu_Q(x(t)) along the latent spline (Eq. 18, 26-28, the GP layer); the base
has its own (x, z, pitch) splines in the stance and the landing, and falls freely in flight.
Hard constraints, each a row family (:mod:`.rows`), where :class:`~.selection.Selection` puts
them:

* contact nodes (stance and landing, every 10 ms): base rows = sum J^T f, the toe tip within
  ``foot_tolerance`` of its ground point, the training contact schedule (a loaded heel or ball
  on the ground, an unloaded one carries no force), and the chosen torque limits (Eq. 34) and
  edges of the support polygon for the ZMP and, once the landing has settled, the COM (Eq. 35-36);
* contact samples between the nodes: their own edge weights, the base rows and chosen rows;
* takeoff and touchdown: the flight's state from the stance, the inelastic impact;
* the flight: the pitch integrates the pitch rate of the conserved momentum, the feet stay above
  the ground at the flight nodes, and flight samples hold the free-fall rows and chosen torques;
* the tube sigma^2 <= delta (Eq. 29) at the selection's times.

Objective: phase 1 (``"feasibility"``) the feasible point nearest the training fit; phase 2
(``"distance"``) the jump distance x_L (Eq. 33); both with a tiny force regulariser.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import scipy.sparse as sp

from ..latent.gp_layer import GPLayer
from ..nlp.assemble import Family, SparseNLP
from ..nlp.blocks import RobotBlock
from ..nlp.evaluators import BlockEvaluator, VarianceEvaluator
from ..nlp.inputs import NodeInputs
from ..spline import BSpline
from .contact import EDGES, POINTS
from .flight import cumulative_trapezoid_matrix
from .phases import Phases
from .robot import JumpRobot
from .selection import POLYGON_EDGES, Selection
from .settings import JumpSettings
from .variables import JumpVariables

__all__ = ["JumpNLP", "build_nlp", "node_grid", "tube_times", "contact_sample_grid", "flight_sample_grid", "OBJECTIVES", "FORCE_REGULARISATION"]

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
    identity across NLPs with other selections (:func:`latentoc.jump.warm.carried`)."""

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
    splines: tuple[BSpline, BSpline, BSpline]
    selection: Selection
    objective: str
    P_fixed: np.ndarray
    tau_fine: np.ndarray  # flight times (from takeoff) of the pitch integration
    flight_substeps: int

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


def node_grid(settings: JumpSettings, phases: Phases) -> dict[str, np.ndarray]:
    """Contact and flight node times: stance, flight, landing."""
    s, ph = settings, phases
    return {"stance": np.linspace(0.0, ph.takeoff, s.n_stance), "flight": np.linspace(ph.takeoff, ph.touchdown, s.n_flight),
            "land": np.linspace(ph.touchdown, ph.duration, s.n_land)}


def tube_times(settings: JumpSettings, phases: Phases) -> np.ndarray:
    """The tube every ``tube_spacing`` inside the motion (its ends are the fixed end points)."""
    T = phases.duration
    return np.linspace(0.0, T, max(2, int(round(T / settings.tube_spacing)) + 1))[1:-1]


def contact_sample_grid(settings: JumpSettings, phases: Phases, rate_hz: float = 1000.0) -> np.ndarray:
    """Contact sample times on the export's 1 kHz grid: every ``sample_spacing``, at the splines'
    breakpoints (their accelerations kink there) and just inside each unloaded interval of the
    contact schedule, in the stance and the landing, none within 1 ms of a contact node."""
    s, ph = settings, phases
    T = ph.duration
    if s.sample_spacing <= 0:
        return np.zeros(0)
    knots = np.concatenate([BSpline(s.n_control, T).breakpoints, BSpline(s.n_base_stance, ph.takeoff).breakpoints,
                            ph.touchdown + BSpline(s.n_base_land, T - ph.touchdown).breakpoints])
    sw = ph.switch_samples(eps=1.0 / rate_hz)
    t = np.concatenate([np.arange(0.0, T, s.sample_spacing), knots, sw])
    t = np.unique(np.round(t * rate_hz) / rate_hz)
    grid = node_grid(s, ph)
    nodes = np.concatenate([grid["stance"], grid["land"]])
    inside = ((t > 0) & (t < ph.takeoff)) | ((t > ph.touchdown) & (t < T))
    far = np.min(np.abs(t[:, None] - nodes[None, :]), axis=1) > 1.0 / rate_hz - 1e-9
    return t[inside & far]


def flight_sample_grid(settings: JumpSettings, phases: Phases, rate_hz: float = 1000.0) -> np.ndarray:
    """Flight sample times on the export's 1 kHz grid, about every ``sample_spacing`` inside the flight."""
    ph, h = phases, settings.sample_spacing
    if h <= 0:
        return np.zeros(0)
    t = np.unique(np.round(np.arange(ph.takeoff + h / 2, ph.touchdown, h) * rate_hz) / rate_hz)
    return t[(t > ph.takeoff) & (t < ph.touchdown)]


class _Rows:
    """Row selection of one family: (node, output, scale) entries with each row's name and component."""

    def __init__(self, block: RobotBlock):
        self.block, self.entries, self.names, self.nodes, self.comps = block, [], [], [], []

    def add(self, k: int, part: str, scale: np.ndarray | float = 1.0, subset: np.ndarray | None = None) -> None:
        s = self.block.layout[part]
        local = np.arange(s.stop - s.start) if subset is None else np.asarray(subset, int)
        scale = np.broadcast_to(np.asarray(scale, float), local.shape)
        for o, c in zip(s.start + local, scale):
            self.entries.append((k * self.block.n_out + o, c))
        self.names.extend([part] * len(local))
        self.nodes.extend([k] * len(local))
        self.comps.extend(local.tolist())

    def matrix(self, K: int) -> sp.csr_matrix:
        cols = np.array([e[0] for e in self.entries], np.int64)
        vals = np.array([e[1] for e in self.entries], float)
        return sp.csr_matrix((vals, (np.arange(len(cols)), cols)), shape=(len(cols), K * self.block.n_out))


def _latent(ni: NodeInputs, sp_: BSpline, t: np.ndarray, var: JumpVariables, P_fixed: np.ndarray) -> None:
    ni.spline([sp_.basis(t, k) for k in range(3)], var.latent_index(), P_fixed)


def _base(ni: NodeInputs, sps: BSpline, spl: BSpline, t: np.ndarray, touchdown: float, var: JumpVariables,
          orders: int = 3) -> None:
    """(b, bd, bdd) of the stance spline at times before takeoff and the landing's after touchdown."""
    land = t >= touchdown - 1e-12
    bases = []
    for k in range(orders):
        B = np.zeros((len(t), sps.n_control + spl.n_control))
        B[~land, :sps.n_control] = sps.basis(np.clip(t[~land], 0, sps.duration), k)
        B[land, sps.n_control:] = spl.basis(np.clip(t[land] - touchdown, 0, spl.duration), k)
        bases.append(B)
    index = np.vstack([var.index("base_stance"), var.index("base_land")])
    ni.spline(bases, index, np.zeros(index.shape))


class _Builder:
    """Collects the families with each row's name, time and component."""

    def __init__(self, layer: GPLayer, n_w: int):
        self.layer, self.n_w = layer, n_w
        self.families: list[Family] = []
        self.names: list[str] = []
        self.times: list[float] = []
        self.comps: list[int] = []

    def add(self, name: str, ni: NodeInputs, rows: _Rows, node_t: np.ndarray, L: sp.spmatrix | None = None) -> None:
        if not rows.entries:
            return
        S, s0 = ni.build()
        self.families.append(Family(name, BlockEvaluator(rows.block, self.layer), S, s0, Cg=rows.matrix(ni.K), L=L))
        self.names.extend(rows.names)
        self.times.extend(np.asarray(node_t, float)[rows.nodes])
        self.comps.extend(rows.comps)


def _contact_rows(rows: _Rows, k: int, t: float, torque: np.ndarray, polygon: np.ndarray, ph: Phases,
                  robot: JumpRobot, s: JumpSettings) -> None:
    """Base rows always; the chosen torque rows; the chosen ZMP edges in the landing and COM edges
    once it has settled."""
    kept = robot.unmirrored
    rows.add(k, "dynamics")
    rows.add(k, "cop_front")
    rows.add(k, "cop_heel" if ph.loaded("heel", np.array([t]))[0] else
             "cop_ball" if ph.loaded("ball", np.array([t]))[0] else "cop_pad")
    if s.torque_limits and torque.any():
        rows.add(k, "torque", 1.0 / robot.torque_scale[kept[torque]], kept[torque])
    if s.polygon and t >= ph.touchdown - 1e-9:
        zmp, com = polygon[:POLYGON_EDGES], polygon[POLYGON_EDGES:]
        if zmp.any():
            rows.add(k, "zmp_polygon", subset=np.flatnonzero(zmp))
        if com.any() and t >= ph.settle - 1e-9:
            rows.add(k, "com_polygon", subset=np.flatnonzero(com))


def build_nlp(robot: JumpRobot, layer: GPLayer, blocks: dict[str, RobotBlock], phases: Phases,
              settings: JumpSettings, P_fixed: np.ndarray, objective: str = "distance",
              selection: Selection | None = None) -> JumpNLP:
    """The NLP of one phase of the solve (module doc); ``P_fixed`` holds the latent end points,
    ``selection`` the chosen rows and samples (default: every node row, the tube, no samples)."""
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
    s, ph = settings, phases
    d, T = layer.latent_dim, ph.duration
    grid = node_grid(s, ph)
    ts, tf, tl = grid["stance"], grid["flight"], grid["land"]
    tc = np.concatenate([ts, tl])
    nS, nC, nF = len(ts), len(ts) + len(tl), len(tf)
    kept = robot.unmirrored
    sel = Selection.every_node_row(nC, len(kept), tube_times(s, ph)) if selection is None else selection
    if sel.node_torque.shape != (nC, len(kept)):
        raise ValueError(f"the selection is for {sel.node_torque.shape} contact nodes x joints, the NLP has "
                         f"{(nC, len(kept))}")
    sp_ = BSpline(s.n_control, T)
    sps, spl = BSpline(s.n_base_stance, ph.takeoff), BSpline(s.n_base_land, T - ph.touchdown)
    var = JumpVariables.layout(s.n_control, d, s.n_base_stance, s.n_base_land, nC, nF, len(sel.contact), len(sel.flight))
    n_w = var.n
    b = _Builder(layer, n_w)

    # contact nodes, then the contact samples (the same block, their own edge weights)
    ni = NodeInputs(nC, n_w)
    _latent(ni, sp_, tc, var, P_fixed)
    _base(ni, sps, spl, tc, ph.touchdown, var)
    ni.variables(np.concatenate([-np.ones(nS, np.int64), np.full(len(tl), var.index("x_L")[0])])[:, None])
    ni.variables(var.index("lam"))
    rows = _Rows(blocks["contact"])
    for k, t in enumerate(tc):
        _contact_rows(rows, k, t, sel.node_torque[k], sel.node_polygon[k], ph, robot, s)
        for part in ("ball_height", "toe_position", "heel_height"):
            rows.add(k, part)
    b.add("contact", ni, rows, tc)
    if len(sel.contact):
        tcs = sel.contact
        ni = NodeInputs(len(tcs), n_w)
        _latent(ni, sp_, tcs, var, P_fixed)
        _base(ni, sps, spl, tcs, ph.touchdown, var)
        ni.constant(np.zeros((len(tcs), 1)))  # the toe tip's ground point: no placement rows here
        ni.variables(var.index("lam_sample"))
        rows = _Rows(blocks["contact"])
        for k, t in enumerate(tcs):
            _contact_rows(rows, k, t, sel.contact_torque[k], sel.contact_polygon[k], ph, robot, s)
        b.add("contact_sample", ni, rows, tcs)

    # takeoff
    t_to = np.array([ph.takeoff])
    ni = NodeInputs(1, n_w)
    _latent(ni, sp_, t_to, var, P_fixed)
    _base(ni, sps, spl, t_to, ph.touchdown, var, orders=2)
    ni.variables(np.concatenate([var.index("c_to"), var.index("cd_to"), var.index("L_to"),
                                 var.index("pitch_flight")[:1]])[None, :])
    rows = _Rows(blocks["takeoff"])
    rows.add(0, "takeoff")
    b.add("takeoff", ni, rows, t_to)

    # pitch: p_k - p_0 = int_0^tau_k pd (trapezoid on a finer grid)
    tau_f = tf - ph.takeoff
    nsub = max(1, int(s.flight_substeps))
    tau_fine = np.linspace(0.0, tau_f[-1], (nF - 1) * nsub + 1)
    ni = NodeInputs(len(tau_fine), n_w)
    _latent(ni, sp_, ph.takeoff + tau_fine, var, P_fixed)
    ni.variables(np.full((len(tau_fine), 1), var.index("L_to")[0]))
    A = cumulative_trapezoid_matrix(tau_fine)[:, ::nsub].T[1:]  # (nF - 1) x fine
    pf = var.index("pitch_flight")
    L = sp.csr_matrix((np.concatenate([np.ones(nF - 1), -np.ones(nF - 1)]),
                       (np.concatenate([np.arange(nF - 1)] * 2), np.concatenate([pf[1:], np.full(nF - 1, pf[0])]))),
                      shape=(nF - 1, n_w))
    S, s0 = ni.build()
    b.families.append(Family("pitch_integration", BlockEvaluator(blocks["pitch_rate"], layer), S, s0,
                             Cg=sp.csr_matrix(-A), L=L))
    b.names.extend(["pitch_integration"] * (nF - 1))
    b.times.extend(tf[1:])
    b.comps.extend([0] * (nF - 1))

    # flight samples: free fall with the sample's pitch rate and base accelerations, tied to the momentum
    if len(sel.flight):
        tfs, fs = sel.flight, var.index("flight_sample")
        ni = NodeInputs(len(tfs), n_w)
        _latent(ni, sp_, tfs, var, P_fixed)
        ni.variables(fs)
        rows = _Rows(blocks["flight_dynamics"])
        for k in range(len(tfs)):
            rows.add(k, "flight_base")
            if s.torque_limits and sel.flight_torque[k].any():
                m = sel.flight_torque[k]
                rows.add(k, "torque", 1.0 / robot.torque_scale[kept[m]], kept[m])
        b.add("flight", ni, rows, tfs)
        ni = NodeInputs(len(tfs), n_w)
        _latent(ni, sp_, tfs, var, P_fixed)
        ni.variables(np.full((len(tfs), 1), var.index("L_to")[0]))
        rows = _Rows(blocks["pitch_rate"])
        for k in range(len(tfs)):
            rows.add(k, "pitch_rate")
        tie = sp.csr_matrix((-np.ones(len(tfs)), (np.arange(len(tfs)), fs[:, 0])), shape=(len(tfs), n_w))
        b.add("flight_pitch", ni, rows, tfs, L=tie)  # pd(y, yd, L) - pd_sample = 0

    # flight clearance at the interior nodes
    ni = NodeInputs(nF - 2, n_w)
    _latent(ni, sp_, tf[1:-1], var, P_fixed)
    ni.variables(np.column_stack([pf[1:-1], np.tile(np.concatenate([var.index("L_to"), var.index("c_to"),
                                                                     var.index("cd_to")]), (nF - 2, 1))]))
    ni.constant(tau_f[1:-1, None])
    rows = _Rows(blocks["flight_clearance"])
    for k in range(nF - 2):
        rows.add(k, "flight_clearance")
    b.add("flight_clearance", ni, rows, tf[1:-1])

    # touchdown
    t_td = np.array([ph.touchdown])
    ni = NodeInputs(1, n_w)
    _latent(ni, sp_, t_td, var, P_fixed)
    _base(ni, sps, spl, t_td, ph.touchdown, var, orders=2)
    ni.variables(np.concatenate([pf[-1:], var.index("L_to"), var.index("c_to"), var.index("cd_to")])[None, :])
    ni.constant([[tau_f[-1]]])
    ni.variables(var.index("lam_impact")[None, :])
    rows = _Rows(blocks["touchdown"])
    rows.add(0, "touchdown_position")
    rows.add(0, "impact")
    b.add("touchdown", ni, rows, t_td)

    # the tube (Eq. 29), relative (sigma^2 / delta <= 1) so that Ipopt's tolerances are relative to delta
    t_tube = np.asarray(sel.tube, float)
    if len(t_tube):
        ni = NodeInputs(len(t_tube), n_w)
        ni.spline([sp_.basis(t_tube, 0)], var.latent_index(), P_fixed)
        S, s0 = ni.build()
        b.families.append(Family("tube", VarianceEvaluator(layer), S, s0,
                                 Cg=sp.identity(len(t_tube), format="csr") / s.tube))
        b.names.extend(["tube"] * len(t_tube))
        b.times.extend(t_tube)
        b.comps.extend([0] * len(t_tube))

    nlp = SparseNLP(n_w, b.families, _objective(var, P_fixed, objective))
    names, comps = np.array(b.names), np.array(b.comps, np.int64)
    lbg, ubg = _row_bounds(names, comps, np.array(b.times), robot, s, ph)
    lbx, ubx = _variable_bounds(var, ph, tc, sel.contact)
    return JumpNLP(nlp, var, lbx, ubx, lbg, ubg, names, np.array(b.times, float), comps, grid, (sp_, sps, spl), sel,
                   objective, np.asarray(P_fixed, float), tau_fine, nsub)


def _objective(var: JumpVariables, P_fixed: np.ndarray, objective: str) -> ca.Function:
    w = ca.SX.sym("w", var.n)
    lam, imp, lam_s = w[var.slices["lam"]], w[var.slices["lam_impact"]], w[var.slices["lam_sample"]]
    reg = FORCE_REGULARISATION * (ca.sumsqr(lam) + ca.sumsqr(imp) + ca.sumsqr(lam_s))
    if objective == "distance":
        f = -w[var.slices["x_L"]] + reg
    else:  # the squared deviation of the free latent control points from the training fit
        P0 = np.asarray(P_fixed, float)[1:-1].ravel()
        f = ca.sumsqr(w[var.slices["P"]] - P0) / max(float(np.mean(np.square(P_fixed))), 1e-12) + reg
    return ca.Function("jump_objective", [w], [f])


def _row_bounds(names: np.ndarray, comps: np.ndarray, times: np.ndarray, robot: JumpRobot, s: JumpSettings,
                ph: Phases) -> tuple[np.ndarray, np.ndarray]:
    bounds = {"dynamics": (0, 0), "flight_base": (0, 0), "flight_pitch": (0, 0), "ball_height": (-s.ball_tolerance, np.inf),
              "toe_position": (-s.foot_tolerance, s.foot_tolerance), "heel_height": (-s.contact_tolerance, np.inf),
              "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0), "takeoff": (0, 0),
              "pitch_integration": (0, 0), "flight_clearance": (0, np.inf), "touchdown_position": (0, 0),
              "impact": (0, 0), "tube": (-np.inf, 1.0 - TUBE_BACKOFF), "pitch_rate": (0, 0),
              **{k: (0, np.inf) for k in ("cop_front", "cop_heel", "cop_ball", "cop_pad")}}
    lbg, ubg = np.zeros(len(names)), np.zeros(len(names))
    for k, (lo, hi) in bounds.items():
        sel = names == k
        lbg[sel], ubg[sel] = lo, hi
    torque = names == "torque"  # components: positions among the active joints
    act, scale = robot.active, robot.torque_scale
    lbg[torque] = (robot.limits.tau_min[act][comps[torque]] + TORQUE_BACKOFF) / scale[comps[torque]]
    ubg[torque] = (robot.limits.tau_max[act][comps[torque]] - TORQUE_BACKOFF) / scale[comps[torque]]
    # the contact schedule: a loaded heel stays on the ground, a loaded ball within the tolerance
    heel, ball = names == "heel_height", names == "ball_height"
    ubg[heel] = np.where(ph.loaded("heel", times[heel]), s.contact_tolerance, np.inf)
    loaded = ph.loaded("ball", times[ball])
    lbg[ball] = np.where(loaded, -s.contact_tolerance, -s.ball_tolerance)
    ubg[ball] = np.where(loaded, s.contact_tolerance, np.inf)
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
    lbx[var.slices["lam_impact"]] = 0.0
    imp_ub = ubx[var.slices["lam_impact"]]
    t_td = np.array([ph.touchdown])
    for k, point in enumerate(POINTS):
        imp_ub[2 * k:2 * k + 2] = np.inf if ph.loaded(point, t_td)[0] else 0.0
    return lbx, ubx
