"""The jump's initial point: the training motion in the NLP's variables.

The path is the setup's smoothed fit of the learned latent points (or of the training joints,
:mod:`..schedule.path`); the flight's takeoff state and pitch follow from the stance's closed legs and planted
base at takeoff (ballistic, :mod:`..closure.ballistic`, :mod:`..closure.planted_legs`); the contact forces are the
non-negative edge weights of the loaded points that best balance each node's base rows. The
samples' variables (:func:`sample_values`) follow from the rest of a point, so a point can be
carried into an NLP with more samples.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from latentoc.latent.gp_layer import Layer
from latentoc.latent.spline import BSpline
from latentoc.jump.robot.feet import EDGES
from latentoc.jump.closure.ballistic import ballistic_base, flight_functions
from latentoc.jump.transcription.nlp import JumpNLP
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.rows.flight import FLIGHT_SUBSTEPS

__all__ = ["initial_point", "sample_values", "balanced_forces", "takeoff_state"]


def _joint_motion(layer: Layer, sp_, P: np.ndarray, t: np.ndarray) -> list[np.ndarray]:
    Z = np.hstack([sp_.evaluate(P, t, k) for k in range(3)])
    m = layer.motion(Z)
    return [m.y.T, m.yd.T, m.ydd.T]  # n x K each


def takeoff_state(robot: JumpRobot, layer: Layer, spline: BSpline, P: np.ndarray, phases: Phases
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The closed legs (y, yd: n x 1) and the planted base (b, bd: 3 x 1) at takeoff of the path P."""
    assert robot.closure is not None
    t_to = np.array([phases.takeoff])
    y, yd, ydd = _joint_motion(layer, spline, P, t_to)
    yc, ydc, _, b, bd, _ = robot.closure.evaluate(y.T, yd.T, ydd.T, phases.held(t_to), np.zeros(1))
    return yc.T, ydc.T, b.T, bd.T


def initial_point(robot: JumpRobot, layer: Layer, nlp: JumpNLP, phases: Phases, P: np.ndarray, x_L: float) -> np.ndarray:
    """The training start (module doc) of ``nlp`` from the path's control points P and the landing
    toe point x_L."""
    var = nlp.variables
    fns = flight_functions(robot.sym, robot.smap)
    y_to, yd_to, b_to, bd_to = takeoff_state(robot, layer, nlp.spline, P, phases)
    c, cd, L = (np.asarray(v).ravel() for v in fns["momentum"](y_to, yd_to, b_to, bd_to))
    tau_fine = nlp.tau_fine
    Yf = _joint_motion(layer, nlp.spline, P, phases.takeoff + tau_fine)
    bb = ballistic_base(fns, Yf[0], Yf[1], Yf[2], tau_fine, b_to, bd_to, y_to, yd_to)
    nC = var.shapes["lam"][0]
    x0 = var.pack({"P": P[1:-1], "x_L": x_L, "lam": np.full((nC, EDGES), 1.0 / (2 * EDGES)), "c_to": c, "cd_to": cd,
                   "L_to": L, "pitch_flight": bb[0][2, ::FLIGHT_SUBSTEPS]})
    return sample_values(nlp, balanced_forces(nlp, np.clip(x0, nlp.lbx, nlp.ubx)))


def _affine(nlp: JumpNLP, x: np.ndarray, index: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``rows`` (K x r positions in g), affine in the variables ``index`` (K x n, each row of
    them touching only its own variables), as c + A v: c (K x r) and A (K x r x n)."""
    x = np.array(x, float)
    x[index.ravel()] = 0.0
    c = nlp.nlp.constraints(x)[rows]
    A = np.zeros((*rows.shape, index.shape[1]))
    for k in range(index.shape[1]):
        xk = x.copy()
        xk[index[:, k]] = 1.0
        A[:, :, k] = nlp.nlp.constraints(xk)[rows] - c
    return c, A


def _dynamics_rows(nlp: JumpNLP, family: str) -> np.ndarray:
    sl = nlp.family_rows(family)
    return (sl.start + np.flatnonzero(nlp.row_names[sl] == "dynamics")).reshape(-1, 3)


def balanced_forces(nlp: JumpNLP, w: np.ndarray, family: str = "contact", block: str = "lam") -> np.ndarray:
    """``w`` with the edge weights (variables ``block``) that best balance the base rows of
    ``family``: the rows are affine in the weights, so per node a non-negative least-squares fit
    over the loaded edges."""
    lam = nlp.variables.index(block)
    x = np.array(w, float)
    if lam.size == 0:
        return x
    c, A = _affine(nlp, x, lam, _dynamics_rows(nlp, family))
    loaded = nlp.ubx[lam] > 0
    for j in range(c.shape[0]):
        x[lam[j]] = 0.0
        x[lam[j, loaded[j]]] = nnls(A[j][:, loaded[j]], -c[j])[0]
    return x


def sample_values(nlp: JumpNLP, w: np.ndarray) -> np.ndarray:
    """``w`` with the samples' variables following from the rest: the contact samples' balanced
    edge weights; the flight samples' pitch rate from the momentum (the tie rows are pd(y, yd, L)
    - pd_sample) and their base accelerations solving the free-fall rows (affine in them)."""
    x = balanced_forces(nlp, w, "contact_sample", "lam_sample")
    fs = nlp.variables.index("flight_sample")
    if fs.size == 0:
        return x
    tie = nlp.family_rows("flight_pitch")
    x[fs[:, 0]] = 0.0
    x[fs[:, 0]] = nlp.nlp.constraints(x)[tie]
    sl = nlp.family_rows("flight")
    base = (sl.start + np.flatnonzero(nlp.row_names[sl] == "flight_base")).reshape(-1, 3)
    c, A = _affine(nlp, x, fs[:, 1:], base)
    x[fs[:, 1:]] = np.linalg.solve(A, -c[:, :, None])[:, :, 0]
    return x
