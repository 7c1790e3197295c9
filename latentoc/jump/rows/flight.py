"""The flight's rows (:mod:`latentoc.jump.closure.ballistic`): inverse dynamics, foot clearance, pitch rate.

In flight the body falls freely, so the joint torques do not depend on where the body is nor on
its pitch: they are those of RNEA with the base at the origin, unpitched, turning at the pitch
rate pd, and accelerating at (ax, az, pdd) such that the base rows of RNEA vanish (no external
wrench; Crocoddyl's inverse-dynamics form). (pd, ax, az, pdd) are variables of each flight
sample, tied to the conserved momentum by the pitch-rate block, so the torque block's
derivatives hold no ballistic base; it can sit at any time of the flight (the exchange of
:mod:`latentoc.jump.solve.exchange` places it on the 1 kHz grid). The clearance block takes the
pitch and the takeoff COM state to place the feet.
"""
from __future__ import annotations

import casadi as ca
import numpy as np
import scipy.sparse as sp

from latentoc.nlp.assemble import Family
from latentoc.nlp.blocks import RobotBlock
from latentoc.nlp.evaluators import BlockEvaluator
from latentoc.jump.closure.ballistic import GRAVITY, cumulative_trapezoid_matrix, flight_functions
from latentoc.jump.robot.jump_robot import SAGITTAL_ROWS, JumpRobot
from latentoc.jump.transcription.wiring import Rows, Wiring
from latentoc.jump.rows import inputs

DYNAMICS_INPUTS = {"pd": 1, "acc": 3}  # pitch rate; base accelerations (x, z, pitch)
CLEARANCE_INPUTS = {"p": 1, "L": 1, "c_to": 2, "cd_to": 2, "t": 1}
PITCH_RATE_INPUTS = {"L": 1}

FLIGHT_SUBSTEPS = 2  # trapezoid steps of the pitch rate per flight node interval


def ballistic_com(c_to, cd_to, t):
    """COM position and velocity (x, z) at flight time t from the takeoff state."""
    g = ca.DM(GRAVITY)
    return c_to + cd_to * t + 0.5 * g * t ** 2, cd_to + g * t


def flight_base(robot: JumpRobot, y, yd, ydd, p, L, c, cd):
    """Base (b, bd, bdd) of the flight for pitch p, momentum L and the COM at c moving at cd."""
    fns = flight_functions(robot.sym, robot.smap)
    pd, pdd = fns["pitch_rate"](y, yd, ydd, L)
    return fns["base"](y, yd, ydd, p, pd, pdd, c, cd, ca.DM(GRAVITY))


def dynamics_block(robot: JumpRobot, d: int) -> RobotBlock:
    """Free fall by inverse dynamics: the base rows of RNEA (body weights; zero in flight) and the
    joint torques, at zero pitch and position (module doc)."""
    (y, yd, ydd, r), u = inputs(robot, DYNAMICS_INPUTS)
    q, v, a = robot.configuration(ca.DM.zeros(3), ca.vertcat(0, 0, u["pd"]), u["acc"], y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    return RobotBlock.from_parts("jump_flight_dynamics", (y, yd, ydd, r),
                                 {"flight_base": tau[SAGITTAL_ROWS] / robot.weight,
                                  "torque": robot.torque_rows(tau[6:])}, d)


def clearance_block(robot: JumpRobot, d: int) -> RobotBlock:
    """Heel, ball and toe heights at pitch p, the COM on its parabola from the takeoff state."""
    (y, yd, ydd, r), u = inputs(robot, CLEARANCE_INPUTS)
    b, _, _ = flight_base(robot, y, yd, ydd, u["p"], u["L"], ca.DM.zeros(2), ca.DM.zeros(2))
    q, _, _ = robot.configuration(b, ca.DM.zeros(3), ca.DM.zeros(3), y, 0 * yd, 0 * ydd)
    P = robot.points(q, ballistic_com(u["c_to"], u["cd_to"], u["t"])[0])
    return RobotBlock.from_parts("jump_flight_clearance", (y, yd, ydd, r), {"flight_clearance": P[2, :].T}, d)


def pitch_rate_block(robot: JumpRobot, d: int) -> RobotBlock:
    """The pitch rate pd = (L - h) / I of the flight (integrated by the pitch rows)."""
    (y, yd, ydd, r), u = inputs(robot, PITCH_RATE_INPUTS)
    pd, _ = flight_functions(robot.sym, robot.smap)["pitch_rate"](y, yd, ydd, u["L"])
    return RobotBlock.from_parts("jump_pitch_rate", (y, yd, ydd, r), {"pitch_rate": pd}, d)


def wire_pitch(w: Wiring) -> None:
    """The flight nodes' pitch: p_k - p_0 = int_0^tau_k pd, the pitch rate of the conserved momentum
    integrated by the trapezoid rule on :data:`FLIGHT_SUBSTEPS` steps per node interval."""
    tf, var, ph = w.grid["flight"], w.variables, w.phases
    nF, nsub = len(tf), FLIGHT_SUBSTEPS
    tau = pitch_grid(tf - ph.takeoff, nsub)
    ni = w.inputs(len(tau))
    w.latent(ni, ph.takeoff + tau)
    ni.variables(np.full((len(tau), 1), var.index("L_to")[0]))
    A = cumulative_trapezoid_matrix(tau)[:, ::nsub].T[1:]  # (nF - 1) x fine
    pf = var.index("pitch_flight")
    L = sp.csr_matrix((np.concatenate([np.ones(nF - 1), -np.ones(nF - 1)]),
                       (np.concatenate([np.arange(nF - 1)] * 2), np.concatenate([pf[1:], np.full(nF - 1, pf[0])]))),
                      shape=(nF - 1, w.n_w))
    S, s0 = ni.build()
    w.families.append(Family("pitch_integration", BlockEvaluator(w.blocks["pitch_rate"], w.layer), S, s0,
                             Cg=sp.csr_matrix(-A), L=L))
    w.record(["pitch_integration"] * (nF - 1), tf[1:], [0] * (nF - 1))


def pitch_grid(tau_nodes: np.ndarray, substeps: int) -> np.ndarray:
    """Flight times (from takeoff) of the pitch integration: ``substeps`` steps per node interval."""
    return np.linspace(0.0, tau_nodes[-1], (len(tau_nodes) - 1) * substeps + 1)


def wire_samples(w: Wiring) -> None:
    """The flight samples: free fall with the sample's pitch rate and base accelerations, the pitch
    rate tied to the momentum (pd(y, yd, L) - pd_sample = 0), the chosen torque rows."""
    sel, var, robot = w.selection, w.variables, w.robot
    if not len(sel.flight):
        return
    tfs, fs, kept = sel.flight, var.index("flight_sample"), robot.unmirrored
    ni = w.inputs(len(tfs))
    w.latent(ni, tfs)
    ni.variables(fs)
    rows = Rows(w.blocks["flight_dynamics"])
    for k in range(len(tfs)):
        rows.add(k, "flight_base")
        if sel.flight_torque[k].any():
            m = sel.flight_torque[k]
            rows.add(k, "torque", 1.0 / robot.torque_scale[kept[m]], kept[m])
    w.add("flight", ni, rows, tfs)
    ni = w.inputs(len(tfs))
    w.latent(ni, tfs)
    ni.variables(np.full((len(tfs), 1), var.index("L_to")[0]))
    rows = Rows(w.blocks["pitch_rate"])
    for k in range(len(tfs)):
        rows.add(k, "pitch_rate")
    tie = sp.csr_matrix((-np.ones(len(tfs)), (np.arange(len(tfs)), fs[:, 0])), shape=(len(tfs), w.n_w))
    w.add("flight_pitch", ni, rows, tfs, L=tie)


def wire_clearance(w: Wiring) -> None:
    """The feet above the ground at the interior flight nodes."""
    tf, var, ph = w.grid["flight"], w.variables, w.phases
    nF, pf = len(tf), var.index("pitch_flight")
    ni = w.inputs(nF - 2)
    w.latent(ni, tf[1:-1])
    ni.variables(np.column_stack([pf[1:-1], np.tile(np.concatenate([var.index("L_to"), var.index("c_to"),
                                                                     var.index("cd_to")]), (nF - 2, 1))]))
    ni.constant((tf[1:-1] - ph.takeoff)[:, None])
    rows = Rows(w.blocks["flight_clearance"])
    for k in range(nF - 2):
        rows.add(k, "flight_clearance")
    w.add("flight_clearance", ni, rows, tf[1:-1])
