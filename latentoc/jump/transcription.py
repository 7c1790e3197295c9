"""The broad-jump NLP (Kang & Park 2015, Sect. 4.2, Eq. 33-36), solved by Ipopt.

Decision variables
------------------
* the free latent control points P[1:-1] of the B-spline x(t) (m = 11, d = 3; the end
  points stay on the training path, Sect. 4.2 "boundary conditions");
* the foot pitch splines phi_s (stance) and phi_l (landing) of the toe-pinned anchoring
  (:mod:`.contact`) and the landing toe position x_L;
* contact force generator weights (6 per contact node) and the touchdown impulse (6).

Joint motion: y = mu_Q(x(t)) (GPDM mean, Eq. 18), y' and y'' by the chain rule
(Eq. 26-28); the right side is the mirror image.  Base: anchored in stance and landing,
ballistic in flight (the paper's forward "hybrid dynamics", integrated in closed form from
the takeoff state, :mod:`.flight`); in contact the base rows of RNEA equal sum J^T f at
every node.  The touchdown position of the flight must meet the landing's pinned toe.

Impact at touchdown: perfectly inelastic for the feet (restitution 0): the toe tip stops
(anchoring), the joints keep their (prescribed, continuous) velocities, and the base
velocity jumps by ``M_bb (v+ - v-) = (J^T Pi)_base`` with the ground impulse Pi built from
the same unilateral friction-pyramid generators as the forces (so Pi is unilateral and in
the cone).  The paper's restitution 0.5 belongs to its penalty-contact simulator; with
feet that must stay on the ground after landing, a bouncing contact would start a second
flight, which the fixed phase sequence excludes.

Constraints (hard): base rows (sagittal x, z, pitch; the lateral rows vanish by symmetry
and are checked in :mod:`.verify`), tube sigma^2 <= delta (Eq. 29), torque limits (Eq. 34),
contact-force cone/unilateral/CoP (by the generators), heel/toe complementarity, no
ground penetration in flight, ZMP in the support polygon over the landing and the projected
COM in it once the landing has settled (Eq. 35, 36).
Objective (Eq. 33): maximise the jump distance x_L - x_0 of the pinned toe tip.

Flight: ballistic, integrated from the takeoff state (:mod:`.flight`): no base variables, and
the base rows hold at every instant (1 kHz residual ~1e-13 body weights, against 0.3-0.5 with
the collocated base spline it replaced).  Contact phases: the base rows, cone, CoP, torque
limits and complementarity hold at the nodes; between nodes the exported motion is checked
by :mod:`.verify` with the wrench the motion needs.

Measured history (issue 6; 2 shared cores; L-BFGS; tube 0.02 unless stated):

* takeoff at the feet's lift (0.350 s) and m = 11: with all hard constraints on, phase 1 ends
  infeasible.  Two causes, both measured: the toe tip leaves the ground at 0.308 s (now the
  takeoff, :mod:`.phases`), and an 11-point latent spline smooths the push-off, so the
  toe-pinned takeoff has 1.26 m/s of vertical velocity against the captured 1.84 (m = 15:
  1.64, m = 21: 1.96); simulated ballistically, that flight lands the toe 25 cm below the
  ground at touchdown, against 1.5 cm with m = 21;
* m = 21, toe-off takeoff, collocated flight spline, nodes 12/12/18, all constraints on:
  phase 1 and phase 2 both converge (192 + 255 iterations, 256 s), distance 0.661 m (training
  0.732 m).  The 1 kHz check then showed the flight residual (0.48 body weights, now removed by
  the ballistic flight) and, between contact nodes, a needed wrench whose centre of pressure
  leaves the foot (torque-limit excess up to 380 N m at the toe joint, fz < 0 at one sample):
  the node constraints need a denser grid or inter-node constraints;
* ballistic flight and the tube on a 5 ms grid (this version), nodes 12/12/18, all
  constraints on: phase 1 and 2 converge (192 + 105 iterations, constraint violation 2e-8),
  distance 0.503 m (training 0.732 m), 774 s wall / 724 s CPU; the constraint Jacobian takes
  2.25 s per evaluation (241 s of phase 2's time for 107 evaluations).  1 kHz check: flight
  base residual 5.5e-14 body weights, min normal force 30.6 N, max sigma^2 0.020095 for
  delta 0.02; between contact nodes the needed wrench still leaves the foot (friction ratio
  9.5, centre of pressure 10 m outside where fz is small, torque-limit excess 977 N m), so the
  contact phases need inter-node constraints before the jump counts as valid.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import pinocchio as pin

from ..dynamics import SymbolicModel
from ..gpdm import GPDM
from ..spline import BSpline
from .base import base_function
from .flight import ballistic_base, flight_functions
from .contact import MU, FootGeometry, anchor_function, toe_wrench, joint_embedding, points_function, point_forces
from .phases import Phases
from .support_polygon import symbolic_rows
from .torque_limits import TrainingDynamics
from .zmp import G, zmp

SAGITTAL_ROWS = [0, 2, 4]


@dataclass
class JumpSettings:
    """Table 5 parameters and discretisation."""

    tube: float = 0.0005
    mu: float = MU
    n_control: int = 21  # paper 11; 11 cannot follow the push-off (see the module doc)
    n_stance: int = 10
    n_flight: int = 9
    n_land: int = 14
    n_phi_stance: int = 8  # 5 cannot follow the captured stance base (measured, issue 6)
    n_phi_land: int = 6
    flight_substeps: int = 4  # trapezoid steps of the pitch rate per flight node interval
    complementarity_eps: float = 1e-4  # body weights x metres
    ball_tolerance: float = 0.02
    tube_spacing: float = 0.005  # s; the tube (cheap: GP variance only) on this grid, not only at nodes
    max_iter: int = 400
    tol: float = 1e-5
    hessian: str = "limited-memory"  # or "exact"
    print_level: int = 0
    torque_limits: bool = True
    complementarity: bool = True
    polygon: bool = True
    two_phase: bool = True  # phase 1 feasibility near the training fit, then phase 2 max distance


@dataclass
class JumpNLP:
    """Built NLP and the pieces needed to read a solution."""

    solver: ca.Function
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    unpack: ca.Function
    names: list[str]
    build_time: float
    meta: dict = field(default_factory=dict)


def node_function(sym: SymbolicModel, smap, gpdm: GPDM, geom: FootGeometry, mu: float) -> ca.Function:
    """(x, xd, xdd, b, bd, bdd, lam) -> res[6], tau[nv-6], P[3x3 flat], com, wrench (one foot, at the toe tip), sigma2, q, v, a."""
    d = gpdm.latent_dim
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    b, bd, bdd = (ca.SX.sym(n, 3) for n in ("b", "bd", "bdd"))
    lam = ca.SX.sym("lam", 6)
    y = gpdm.mean_function()(x)
    yd = ca.jtimes(y, x, xd)
    ydd = ca.jtimes(y, x, xdd) + ca.jtimes(yd, x, xd)
    E = ca.DM(joint_embedding(smap))
    q7, v6, a6 = base_function()(b, bd, bdd)
    q, v, a = ca.vertcat(q7, E @ y), ca.vertcat(v6, E @ yd), ca.vertcat(a6, E @ ydd)
    tau = sym.rnea(q, v, a)
    P = points_function(sym, geom)(q)
    w = toe_wrench(lam, P, mu)
    gen = sym.frame_jacobian("ltoes_end")(q).T @ w + sym.frame_jacobian("rtoes_end")(q).T @ w
    res = tau[:6] - gen[:6]
    return ca.Function("jump_node", [x, xd, xdd, b, bd, bdd, lam],
                       [res, tau[6:] - gen[6:], ca.vec(P), sym.com(q), w,
                        gpdm.variance_function()(x), q, v, a],
                       ["x", "xd", "xdd", "b", "bd", "bdd", "lam"],
                       ["res", "tau", "P", "com", "wrench", "sigma2", "q", "v", "a"])


def anchored_function(sym: SymbolicModel, smap, gpdm: GPDM, geom: FootGeometry) -> ca.Function:
    """(x, xd, xdd, phi, phid, phidd, x_pin) -> b, bd, bdd of the toe-pinned base."""
    d = gpdm.latent_dim
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    phi, phid, phidd, xpin = (ca.SX.sym(n) for n in ("phi", "phid", "phidd", "x_pin"))
    y = gpdm.mean_function()(x)
    b = anchor_function(sym, smap, geom)(y, phi, xpin)
    z, zd, zdd = ca.vertcat(x, phi), ca.vertcat(xd, phid), ca.vertcat(xdd, phidd)
    bd = ca.jtimes(b, z, zd)
    bdd = ca.jtimes(b, z, zdd) + ca.jtimes(bd, z, zd)
    return ca.Function("anchored_base", [x, xd, xdd, phi, phid, phidd, xpin], [b, bd, bdd],
                       ["x", "xd", "xdd", "phi", "phid", "phidd", "x_pin"], ["b", "bd", "bdd"])


def _basis(sp: BSpline, t: np.ndarray, offset: float = 0.0) -> list[np.ndarray]:
    return [sp.basis(np.clip(t - offset, 0, sp.duration), k) for k in range(3)]


def build_nlp(model: pin.Model, smap, gpdm: GPDM, geom: FootGeometry, phases: Phases,
              limits: TrainingDynamics, settings: JumpSettings, init: dict,
              sym: SymbolicModel | None = None) -> JumpNLP:
    """Assemble the NLP; ``init`` holds initial guesses (P, phi_s, phi_l, flight, x_L, lam)."""
    t0 = time.perf_counter()
    s = settings
    sym = sym or SymbolicModel(model)
    mass = float(sum(i.mass for i in model.inertias))
    dlat = gpdm.latent_dim
    grid = phases.grid(s.n_stance, s.n_flight, s.n_land)
    T = phases.duration
    sp = BSpline(s.n_control, T)
    sps = BSpline(s.n_phi_stance, phases.takeoff)
    spl = BSpline(s.n_phi_land, T - phases.touchdown)

    # ---------------------------------------------------------------- variables
    Pfix = np.asarray(init["P"], float)
    Pfree = ca.MX.sym("P", s.n_control - 2, dlat)
    Pm = ca.vertcat(ca.DM(Pfix[:1]), Pfree, ca.DM(Pfix[-1:]))
    cs = ca.MX.sym("phi_s", s.n_phi_stance)
    cl = ca.MX.sym("phi_l", s.n_phi_land)
    xL = ca.MX.sym("x_L")
    n_contact = s.n_stance + s.n_land
    Lam = ca.MX.sym("lam", 6, n_contact)
    Limp = ca.MX.sym("lam_impact", 6)
    blocks = [("P", Pfree), ("phi_s", cs), ("phi_l", cl), ("x_L", xL), ("lam", Lam), ("lam_impact", Limp)]
    w = ca.veccat(*[v for _, v in blocks])

    anch = anchored_function(sym, smap, gpdm, geom)
    node = node_function(sym, smap, gpdm, geom, s.mu)

    # latent and base per node: stance, flight, landing
    ts, tf, tl = grid["stance"], grid["flight"], grid["land"]
    lat = [[ca.sparsify(ca.DM(B)) @ Pm for B in _basis(sp, tt)] for tt in (ts, tf, tl)]
    phis = [ca.sparsify(ca.DM(B)) @ cs for B in _basis(sps, ts)]
    phil = [ca.sparsify(ca.DM(B)) @ cl for B in _basis(spl, tl, phases.touchdown)]
    A_s = anch.map(len(ts))
    bs = A_s(lat[0][0].T, lat[0][1].T, lat[0][2].T, phis[0].T, phis[1].T, phis[2].T, ca.DM.zeros(1, len(ts)))
    A_l = anch.map(len(tl))
    bl = A_l(lat[2][0].T, lat[2][1].T, lat[2][2].T, phil[0].T, phil[1].T, phil[2].T, ca.repmat(xL, 1, len(tl)))
    # flight: ballistic from the takeoff state (:mod:`.flight`), pitch integrated on a grid with
    # flight_substeps steps per node interval, the nodes on every flight_substeps-th point
    fns = flight_functions(sym, smap, gpdm)
    nsub = max(1, int(s.flight_substeps))
    tau = np.linspace(0.0, phases.touchdown - phases.takeoff, (len(tf) - 1) * nsub + 1)
    latf = [ca.sparsify(ca.DM(B)) @ Pm for B in _basis(sp, phases.takeoff + tau)]
    bf_fine = ballistic_base(fns, latf[0].T, latf[1].T, latf[2].T, tau, bs[0][:, -1], bs[1][:, -1],
                             lat[0][0][-1, :].T, lat[0][1][-1, :].T)
    bf = [v[:, list(range(0, len(tau), nsub))] for v in bf_fine]

    Xall = [ca.horzcat(lat[0][k].T, lat[1][k].T, lat[2][k].T) for k in range(3)]
    Ball = [ca.horzcat(bs[k], bf[k], bl[k]) for k in range(3)]
    nS, nF, nL = len(ts), len(tf), len(tl)
    W = mass * G
    Lall = W * ca.horzcat(Lam[:, :nS], ca.DM.zeros(6, nF), Lam[:, nS:])  # Lam in body weights
    N = nS + nF + nL
    out = node.map(N)(Xall[0], Xall[1], Xall[2], Ball[0], Ball[1], Ball[2], Lall)
    res, tau, Pp, com, dh = out[:5]

    g, lbg, ubg, names = [], [], [], []

    def add(expr, lo, hi, name):
        expr = ca.vec(expr)
        n = expr.numel()
        g.append(expr)
        lbg.append(np.broadcast_to(lo, (n,)).astype(float))
        ubg.append(np.broadcast_to(hi, (n,)).astype(float))
        names.extend([name] * n)

    contact_cols = list(range(nS)) + list(range(nS + nF, N))
    # base rows where feet touch; in flight they hold by construction (checked by verify)
    add(res[SAGITTAL_ROWS, :][:, contact_cols] / W, 0.0, 0.0, "dynamics")
    # joints whose torque vanishes by symmetry (centre ry/rz) have a zero range: checked in verify
    act = np.where(limits.tau_max - limits.tau_min > 1e-6)[0]
    if s.torque_limits:
        sc = np.maximum(limits.tau_max[act] - limits.tau_min[act], 1.0)  # rows scaled to O(1)
        add(tau[act.tolist(), :] / ca.DM(np.repeat(sc[:, None], N, 1)), np.tile(limits.tau_min[act] / sc, N),
            np.tile(limits.tau_max[act] / sc, N), "torque")
    # tube on a dense grid (the end points are fixed on the training path): at the nodes only,
    # the latent path slips out between them (1 kHz max sigma^2 0.0212 for delta 0.02, measured)
    n_tube = max(2, int(round(T / s.tube_spacing)) + 1)
    t_tube = np.linspace(0.0, T, n_tube)[1:-1]
    X_tube = ca.sparsify(ca.DM(sp.basis(t_tube, 0))) @ Pm
    add(gpdm.variance_function().map(len(t_tube))(X_tube.T), -np.inf, s.tube, "tube")
    heel_z, ball_z = Pp[2, :], Pp[5, :]
    for j, c in enumerate(contact_cols):
        lam = Lam[:, j]
        if s.complementarity:
            add(heel_z[c] * (lam[0] + lam[1]), -np.inf, s.complementarity_eps, "heel_complementarity")
            add(ball_z[c] * (lam[2] + lam[3]), -np.inf, s.complementarity_eps, "ball_complementarity")
        add(ball_z[c], -s.ball_tolerance, np.inf, "ball_height")
    add(ca.vertcat(phis[0], phil[0]), 0.0, np.inf, "heel_up")
    for c in range(nS + 1, nS + nF - 1):  # flight interior: no penetration
        add(Pp[[2, 5, 8], c], 0.0, np.inf, "flight_clearance")
    # touchdown: position continuity and inelastic impact
    add(bf[0][:, -1] - bl[0][:, 0], 0.0, 0.0, "touchdown_position")
    ctd = nS + nF  # first landing column
    qtd = out[6][:, ctd]
    bfun = base_function()
    v_minus = bfun(bl[0][:, 0], bf[1][:, -1], ca.DM.zeros(3))[1]
    v_plus = bfun(bl[0][:, 0], bl[1][:, 0], ca.DM.zeros(3))[1]
    Mbb = sym.mass_matrix(qtd)[:6, :6]
    Ptd = ca.reshape(Pp[:, ctd], 3, 3)
    wimp = toe_wrench(Limp * W * 0.1, Ptd, s.mu)  # impulse in units of 0.1 s of body weight
    Jl, Jr = sym.frame_jacobian("ltoes_end")(qtd), sym.frame_jacobian("rtoes_end")(qtd)
    imp = Mbb @ (v_plus - v_minus) - (Jl.T @ wimp + Jr.T @ wimp)[:6]
    add(imp[SAGITTAL_ROWS] / W, 0.0, 0.0, "impact")
    # landing: ZMP in the polygon at every landing node, COM once settled (Eq. 35, 36)
    for c, tk in zip(range(nS + nF, N), tl):
        P3 = ca.reshape(Pp[:, c], 3, 3)
        rows = symbolic_rows(P3[:2, 0], P3[:2, 2])
        # ZMP = centre of pressure of the total contact wrench on flat ground (see .zmp);
        # equal to the centroidal-momentum formula when the base rows hold (checked in verify)
        wr = dh[:, c]
        px, py = P3[0, 2] - wr[4] / (wr[2] + 1e-9), 0.0
        if s.polygon:
            add(rows(ca.vertcat(px, py)), -np.inf, 0.0, "zmp_polygon")
        if s.polygon and tk >= phases.settle - 1e-9:
            add(rows(com[:2, c]), -np.inf, 0.0, "com_polygon")

    G_ = ca.vertcat(*g)
    x0_pin = 0.0
    # objective weight p: p = 1 maximises the distance (Eq. 33, phase 2); p = 0 is phase 1, the
    # feasibility problem: the point satisfying every hard constraint closest to the initial fit
    # of the training path (squared deviation of the free latent control points)
    pw = ca.MX.sym("p_distance")
    dev = ca.sumsqr(Pfree - ca.DM(Pfix[1:-1])) / max(float(np.mean(np.square(Pfix))), 1e-12)
    f = pw * (-(xL - x0_pin)) + (1 - pw) * dev + 1e-4 * ca.sumsqr(Lam) + 1e-4 * ca.sumsqr(Limp)  # tiny force regularisation

    # bounds and initial guess
    lbx = -np.inf * np.ones(w.numel())
    ubx = np.inf * np.ones(w.numel())
    off = 0
    sizes = {}
    for name, v in blocks:
        sizes[name] = (off, off + v.numel())
        off += v.numel()
    for name in ("lam", "lam_impact"):
        a, b_ = sizes[name]
        lbx[a:b_] = 0.0
    x0 = np.zeros(w.numel())
    x0[slice(*sizes["P"])] = Pfix[1:-1].ravel(order="F")
    x0[slice(*sizes["phi_s"])] = init["phi_s"]
    x0[slice(*sizes["phi_l"])] = init["phi_l"]
    x0[slice(*sizes["x_L"])] = init["x_L"]
    x0[slice(*sizes["lam"])] = init.get("lam", np.full(6 * n_contact, 1.0 / 12.0))
    x0[slice(*sizes["lam_impact"])] = 0.5

    nlp = {"x": w, "p": pw, "f": f, "g": G_}
    opts = {"ipopt.max_iter": s.max_iter, "ipopt.tol": s.tol, "ipopt.print_level": s.print_level,
            "print_time": False, "ipopt.hessian_approximation": s.hessian,
            "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 10,
            "ipopt.constr_viol_tol": 1e-6, "ipopt.mu_strategy": "adaptive"}
    solver = ca.nlpsol("broad_jump", "ipopt", nlp, opts)
    unpack = ca.Function("unpack", [w], [Pm, cs, cl, xL, Lam, Limp],
                         ["w"], ["P", "phi_s", "phi_l", "x_L", "lam", "lam_impact"])
    build = time.perf_counter() - t0
    return JumpNLP(solver, x0, lbx, ubx, np.concatenate(lbg), np.concatenate(ubg), unpack, names, build,
                   {"grid": grid, "splines": (sp, sps, spl), "mass": mass,
                    "g_fun": ca.Function("g", [w], [G_]), "sizes": sizes})
