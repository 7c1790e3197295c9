"""The broad-jump NLP (Sect. 4.2, Eq. 33-36): row families on the node grid, bounds, objective.

Joint motion: y = mu_Q(x(t)) along the latent spline (Eq. 18, 26-28, the GP layer); the base
has its own (x, z, pitch) splines in the stance and the landing, and is ballistic in flight
(:mod:`.flight`). Hard constraints, each a row family (:mod:`.rows`) on its nodes:

* contact nodes (stance and landing, every 10 ms): base rows = sum J^T f, torque limits
  (Eq. 34), the toe tip within ``foot_tolerance`` of its ground point, the training contact
  schedule (a loaded heel or ball on the ground, an unloaded one carries no force), the ZMP
  and, once the landing has settled, the projected COM in the support polygon (Eq. 35-36);
* wrench samples between the contact nodes (phase 2): the needed wrench in the loaded points'
  cone, the torques of the joints no foot force enters;
* takeoff and touchdown: the flight's state from the stance, the inelastic impact;
* flight nodes: torque limits and foot clearance; the pitch integrates the pitch rate;
* the tube sigma^2 <= delta (Eq. 29) on a 5 ms grid.

Objective: phase 1 (``"feasibility"``) the feasible point nearest the training fit; phase 2
(``"distance"``) the jump distance x_L (Eq. 33); both with a tiny force regulariser.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sp

from ..latent.gp_layer import GPLayer
from ..nlp.assemble import Family, SparseNLP
from ..nlp.blocks import RobotBlock
from ..nlp.evaluators import BlockEvaluator, VarianceEvaluator
from ..nlp.inputs import NodeInputs
from ..spline import BSpline
from .flight import cumulative_trapezoid_matrix
from .phases import Phases
from .robot import JumpRobot
from .settings import JumpSettings
from .variables import JumpVariables

__all__ = ["JumpNLP", "Samples", "build_nlp", "default_samples", "node_grid", "OBJECTIVES"]

OBJECTIVES = ("feasibility", "distance")
FORCE_REGULARISATION = 1e-4


@dataclass
class JumpNLP:
    """A built NLP with its bounds and what a solution is read with."""

    nlp: SparseNLP
    variables: JumpVariables
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    row_names: np.ndarray
    grid: dict[str, np.ndarray]
    splines: tuple[BSpline, BSpline, BSpline]
    meta: dict = field(default_factory=dict)

    def control_points(self, w: np.ndarray) -> np.ndarray:
        """All latent control points of solution ``w``: the fixed end points and the free ones."""
        P = np.array(self.meta["P_fixed"], float)
        P[1:-1] = self.variables.unpack(w)["P"]
        return P


def between(nodes: np.ndarray, spacing: float) -> np.ndarray:
    """Sample times about ``spacing`` apart strictly between consecutive node times."""
    out = [np.linspace(a, b, max(1, int(np.ceil((b - a) / spacing - 1e-9))) + 1)[1:-1]
           for a, b in zip(nodes[:-1], nodes[1:])]
    return np.concatenate(out) if out else np.zeros(0)


def merge_samples(samples: np.ndarray, extra: np.ndarray, nodes: np.ndarray, gap: float = 1e-4) -> np.ndarray:
    """``samples`` and ``extra`` sorted, without extra times within ``gap`` of a node, a sample or
    an earlier extra time."""
    taken = list(np.concatenate([nodes, samples]))
    keep = []
    for t in np.sort(extra):
        if not taken or np.min(np.abs(np.asarray(taken) - t)) > gap:
            keep.append(t)
            taken.append(t)
    return np.sort(np.concatenate([samples, np.asarray(keep, float)]))


@dataclass
class Samples:
    """Times of the rows that are not tied to variables: the wrench samples in contact, the
    flight's torque rows and the tube (the exchange of :mod:`.exchange` adds to them)."""

    wrench: np.ndarray
    flight_torque: np.ndarray
    tube: np.ndarray

    def merged(self, other: "Samples") -> "Samples":
        return Samples(*(np.union1d(a, b) for a, b in zip(self.fields(), other.fields())))

    def minus(self, other: "Samples") -> "Samples":
        """The times of self not (to 1 us) in other."""
        return Samples(*(a[~np.isin(np.round(a, 6), np.round(b, 6))] for a, b in zip(self.fields(), other.fields())))

    def fields(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.wrench, self.flight_torque, self.tube


def node_grid(settings: JumpSettings, phases: Phases) -> dict[str, np.ndarray]:
    """Contact and flight node times: stance, flight, landing."""
    s, ph = settings, phases
    return {"stance": np.linspace(0.0, ph.takeoff, s.n_stance), "flight": np.linspace(ph.takeoff, ph.touchdown, s.n_flight),
            "land": np.linspace(ph.touchdown, ph.duration, s.n_land)}


def default_samples(settings: JumpSettings, phases: Phases) -> Samples:
    """Wrench samples every ``wrench_spacing`` between the contact nodes, just inside each unloaded
    interval of the contact schedule and at the splines' breakpoints (their accelerations kink
    there); the flight's torque rows at the flight nodes; the tube every ``tube_spacing``."""
    s, ph = settings, phases
    grid = node_grid(s, ph)
    ts, tl, T = grid["stance"], grid["land"], ph.duration
    tw = np.zeros(0)
    if s.wrench_spacing > 0:
        knots = np.concatenate([BSpline(s.n_control, T).breakpoints, BSpline(s.n_base_stance, ph.takeoff).breakpoints,
                                ph.touchdown + BSpline(s.n_base_land, T - ph.touchdown).breakpoints])
        sw = ph.switch_samples()
        tws = merge_samples(between(ts, s.wrench_spacing),
                            np.concatenate([sw[sw < ph.takeoff], knots[(knots > 0) & (knots < ph.takeoff)]]), ts)
        twl = merge_samples(between(tl, s.wrench_spacing),
                            np.concatenate([sw[sw > ph.touchdown], knots[(knots > ph.touchdown) & (knots < T)]]), tl)
        tw = np.concatenate([tws, twl])
    t_tube = np.linspace(0.0, T, max(2, int(round(T / s.tube_spacing)) + 1))[1:-1]  # the ends are fixed
    return Samples(tw, grid["flight"].copy(), t_tube)


class _Rows:
    """Row selection of one family: (node, output, scale) triples and their names."""

    def __init__(self, block: RobotBlock):
        self.block, self.entries, self.names, self.nodes = block, [], [], []

    def add(self, k: int, part: str, scale: np.ndarray | float = 1.0, subset: np.ndarray | None = None) -> None:
        s = self.block.layout[part]
        rows = np.arange(s.start, s.stop) if subset is None else s.start + np.asarray(subset, int)
        scale = np.broadcast_to(np.asarray(scale, float), rows.shape)
        for o, c in zip(rows, scale):
            self.entries.append((k * self.block.n_out + o, c))
        self.names.extend([part] * len(rows))
        self.nodes.extend([k] * len(rows))

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


def build_nlp(robot: JumpRobot, layer: GPLayer, blocks: dict[str, RobotBlock], phases: Phases,
              settings: JumpSettings, P_fixed: np.ndarray, objective: str = "distance",
              samples: Samples | None = None) -> JumpNLP:
    """The NLP of one phase of the solve (module doc); ``P_fixed`` holds the latent end points,
    ``samples`` the wrench samples and flight torque times (default :func:`default_samples`)."""
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, got {objective!r}")
    s, ph = settings, phases
    d = layer.latent_dim
    T = ph.duration
    grid = node_grid(s, ph)
    ts, tf, tl = grid["stance"], grid["flight"], grid["land"]
    samples = default_samples(s, ph) if samples is None else samples
    sp_ = BSpline(s.n_control, T)
    sps, spl = BSpline(s.n_base_stance, ph.takeoff), BSpline(s.n_base_land, T - ph.touchdown)
    tc = np.concatenate([ts, tl])
    nS, nC, nF = len(ts), len(ts) + len(tl), len(tf)
    var = JumpVariables.layout(s.n_control, d, s.n_base_stance, s.n_base_land, nC, nF)
    n_w = var.n
    families, names, times = [], [], []
    kept = robot.unmirrored
    tscale = 1.0 / robot.torque_scale
    free_kept = np.intersect1d(robot.force_free, kept)

    def family(name: str, ni: NodeInputs, rows: _Rows, node_t: np.ndarray) -> None:
        S, s0 = ni.build()
        families.append(Family(name, BlockEvaluator(rows.block, layer), S, s0, Cg=rows.matrix(ni.K)))
        names.extend(rows.names)
        times.extend(np.asarray(node_t, float)[rows.nodes])

    # contact nodes
    ni = NodeInputs(nC, n_w)
    _latent(ni, sp_, tc, var, P_fixed)
    _base(ni, sps, spl, tc, ph.touchdown, var)
    ni.variables(np.concatenate([-np.ones(nS, np.int64), np.full(len(tl), var.index("x_L")[0])])[:, None])
    ni.variables(var.index("lam"))
    rows = _Rows(blocks["contact"])
    for k, t in enumerate(tc):
        rows.add(k, "dynamics")
        if s.torque_limits:
            rows.add(k, "torque", tscale[kept], kept)
        for part in ("ball_height", "toe_position", "heel_height"):
            rows.add(k, part)
        if k >= nS and s.polygon:
            rows.add(k, "zmp_polygon")
            if t >= ph.settle - 1e-9:
                rows.add(k, "com_polygon")
    family("contact", ni, rows, tc)

    tw = np.asarray(samples.wrench, float)
    if len(tw):
        ni = NodeInputs(len(tw), n_w)
        _latent(ni, sp_, tw, var, P_fixed)
        _base(ni, sps, spl, tw, ph.touchdown, var)
        heel, ball = ph.loaded("heel", tw), ph.loaded("ball", tw)
        rows = _Rows(blocks["wrench"])
        for k in range(len(tw)):
            for part in ("wrench_normal", "wrench_friction", "cop_front"):
                rows.add(k, part)
            rows.add(k, "cop_heel" if heel[k] else "cop_ball" if ball[k] else "cop_pad")
            if s.torque_limits:
                rows.add(k, "torque_free", tscale[free_kept], np.searchsorted(robot.force_free, free_kept))
        family("wrench", ni, rows, tw)

    # takeoff
    t_to = np.array([ph.takeoff])
    ni = NodeInputs(1, n_w)
    _latent(ni, sp_, t_to, var, P_fixed)
    _base(ni, sps, spl, t_to, ph.touchdown, var, orders=2)
    ni.variables(np.concatenate([var.index("c_to"), var.index("cd_to"), var.index("L_to"),
                                 var.index("pitch_flight")[:1]])[None, :])
    rows = _Rows(blocks["takeoff"])
    rows.add(0, "takeoff")
    family("takeoff", ni, rows, t_to)

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
    families.append(Family("pitch_integration", BlockEvaluator(blocks["pitch_rate"], layer), S, s0,
                           Cg=sp.csr_matrix(-A), L=L))
    names.extend(["pitch_integration"] * (nF - 1))
    times.extend(tf[1:])

    # flight: torque rows at the sample times, foot clearance at the interior nodes
    tft = np.asarray(samples.flight_torque, float)
    if s.torque_limits and len(tft):
        ni = NodeInputs(len(tft), n_w)
        _latent(ni, sp_, tft, var, P_fixed)
        ni.variables(np.full((len(tft), 1), var.index("L_to")[0]))
        rows = _Rows(blocks["flight_torque"])
        for k in range(len(tft)):
            rows.add(k, "torque", tscale[kept], kept)
        family("flight_torque", ni, rows, tft)
    ni = NodeInputs(nF - 2, n_w)
    _latent(ni, sp_, tf[1:-1], var, P_fixed)
    ni.variables(np.column_stack([pf[1:-1], np.tile(np.concatenate([var.index("L_to"), var.index("c_to"),
                                                                     var.index("cd_to")]), (nF - 2, 1))]))
    ni.constant(tau_f[1:-1, None])
    rows = _Rows(blocks["flight_clearance"])
    for k in range(nF - 2):
        rows.add(k, "flight_clearance")
    family("flight_clearance", ni, rows, tf[1:-1])

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
    family("touchdown", ni, rows, t_td)

    # the tube (Eq. 29) at its sample times
    t_tube = np.asarray(samples.tube, float)
    ni = NodeInputs(len(t_tube), n_w)
    ni.spline([sp_.basis(t_tube, 0)], var.latent_index(), P_fixed)
    S, s0 = ni.build()
    # relative, sigma^2 / delta <= 1, so that Ipopt's tolerances are relative to delta
    families.append(Family("tube", VarianceEvaluator(layer), S, s0, Cg=sp.identity(len(t_tube), format="csr") / s.tube))
    names.extend(["tube"] * len(t_tube))
    times.extend(t_tube)

    nlp = SparseNLP(n_w, families, _objective(var, P_fixed, objective))
    names = np.array(names)
    lbg, ubg = _row_bounds(names, robot, s, ph, tc, nS, kept, free_kept)
    lbx, ubx = _variable_bounds(var, ph, tc)
    return JumpNLP(nlp, var, lbx, ubx, lbg, ubg, names, grid, (sp_, sps, spl),
                   {"samples": samples, "row_times": np.asarray(times, float), "tube_times": t_tube, "tau_fine": tau_fine,
                                      "flight_substeps": nsub, "objective": objective,
                                      "P_fixed": np.asarray(P_fixed, float)})


def _objective(var: JumpVariables, P_fixed: np.ndarray, objective: str) -> ca.Function:
    w = ca.SX.sym("w", var.n)
    lam, imp = w[var.slices["lam"]], w[var.slices["lam_impact"]]
    reg = FORCE_REGULARISATION * (ca.sumsqr(lam) + ca.sumsqr(imp))
    if objective == "distance":
        f = -w[var.slices["x_L"]] + reg
    else:  # the squared deviation of the free latent control points from the training fit
        P0 = np.asarray(P_fixed, float)[1:-1].ravel()
        f = ca.sumsqr(w[var.slices["P"]] - P0) / max(float(np.mean(np.square(P_fixed))), 1e-12) + reg
    return ca.Function("jump_objective", [w], [f])


def _row_bounds(names: np.ndarray, robot: JumpRobot, s: JumpSettings, ph: Phases, tc: np.ndarray, nS: int,
                kept: np.ndarray, free_kept: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    bounds = {"dynamics": (0, 0), "ball_height": (-s.ball_tolerance, np.inf),
              "toe_position": (-s.foot_tolerance, s.foot_tolerance), "heel_height": (-s.contact_tolerance, np.inf),
              "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0), "takeoff": (0, 0),
              "pitch_integration": (0, 0), "flight_clearance": (0, np.inf), "touchdown_position": (0, 0),
              "impact": (0, 0), "tube": (-np.inf, 1.0),
              **{k: (0, np.inf) for k in ("wrench_normal", "wrench_friction", "cop_front", "cop_heel", "cop_ball",
                                          "cop_pad")}}
    lbg, ubg = np.zeros(len(names)), np.zeros(len(names))
    for k, (lo, hi) in bounds.items():
        sel = names == k
        lbg[sel], ubg[sel] = lo, hi
    act = robot.active
    tmin = robot.limits.tau_min[act] / robot.torque_scale
    tmax = robot.limits.tau_max[act] / robot.torque_scale
    for part, pos in (("torque", kept), ("torque_free", free_kept)):
        sel = names == part
        n = int(sel.sum()) // max(len(pos), 1)
        lbg[sel], ubg[sel] = np.tile(tmin[pos], n), np.tile(tmax[pos], n)
    # the contact schedule: a loaded heel stays on the ground, a loaded ball within the tolerance
    heel, ball = ph.loaded("heel", tc), ph.loaded("ball", tc)
    ubg[names == "heel_height"] = np.where(heel, s.contact_tolerance, np.inf)
    lbg[names == "ball_height"] = np.where(ball, -s.contact_tolerance, -s.ball_tolerance)
    ubg[names == "ball_height"] = np.where(ball, s.contact_tolerance, np.inf)
    return lbg, ubg


def _variable_bounds(var: JumpVariables, ph: Phases, tc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edge weights >= 0; an unloaded heel or ball (contact schedule) carries none."""
    lbx, ubx = np.full(var.n, -np.inf), np.full(var.n, np.inf)
    for name in ("lam", "lam_impact"):
        lbx[var.slices[name]] = 0.0
    lam_ub = ubx[var.slices["lam"]].reshape(len(tc), 6)  # a view
    lam_ub[~ph.loaded("heel", tc), 0:2] = 0.0
    lam_ub[~ph.loaded("ball", tc), 2:4] = 0.0
    imp_ub = ubx[var.slices["lam_impact"]]
    t_td = np.array([ph.touchdown])
    imp_ub[0:2] = np.inf if ph.loaded("heel", t_td)[0] else 0.0
    imp_ub[2:4] = np.inf if ph.loaded("ball", t_td)[0] else 0.0
    return lbx, ubx
