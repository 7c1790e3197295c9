"""The jump's initial point: the training motion in the NLP's variables.

The path is the setup's smoothed fit of the learned latent points (or of the training joints,
:mod:`.path`); the contact phases'
base splines are least-squares fits of the captured base; the flight's takeoff state and pitch
follow from the stance at takeoff (ballistic, :mod:`.flight`); the contact forces are the
non-negative edge weights of the loaded points that best balance each node's base rows. The
samples' variables (:func:`sample_values`) follow from the rest of a point, so a point can be
carried into an NLP with more samples.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from ..latent.gp_layer import Layer
from .contact import EDGES
from .flight import ballistic_base, flight_functions
from .nlp import JumpNLP
from .robot import JumpRobot

__all__ = ["initial_point", "sample_values", "balanced_forces"]


def _joint_motion(layer: Layer, sp_, P: np.ndarray, t: np.ndarray) -> list[np.ndarray]:
    Z = np.hstack([sp_.evaluate(P, t, k) for k in range(3)])
    m = layer.motion(Z)
    return [m.y.T, m.yd.T, m.ydd.T]  # n x K each


def initial_point(robot: JumpRobot, layer: Layer, nlp: JumpNLP, P: np.ndarray, t: np.ndarray, base: np.ndarray,
                  x_L: float, takeoff: float, touchdown: float) -> np.ndarray:
    """The training start (module doc) of ``nlp`` from the path's control points P, the captured
    base (t, base) and the landing toe point x_L."""
    var = nlp.variables
    sp_, sps, spl = nlp.splines
    st, la = t <= takeoff + 1e-9, t >= touchdown - 1e-9
    base_s = sps.fit(t[st], base[st], fix_ends=False)
    base_l = spl.fit(t[la] - touchdown, base[la], fix_ends=False)
    # flight: the ballistic motion from the stance's state at takeoff
    fns = flight_functions(robot.sym, robot.smap)
    t_to = np.array([takeoff])
    y_to, yd_to, _ = _joint_motion(layer, sp_, P, t_to)
    b_to, bd_to = (sps.evaluate(base_s, t_to, k).T for k in range(2))
    c, cd, L = (np.asarray(v).ravel() for v in fns["momentum"](y_to, yd_to, b_to, bd_to))
    tau_fine = nlp.tau_fine
    Yf = _joint_motion(layer, sp_, P, takeoff + tau_fine)
    bb = ballistic_base(fns, Yf[0], Yf[1], Yf[2], tau_fine, b_to, bd_to, y_to, yd_to)
    nC = var.shapes["lam"][0]
    x0 = var.pack({"P": P[1:-1], "base_stance": base_s, "base_land": base_l, "x_L": x_L,
                   "lam": np.full((nC, EDGES), 1.0 / (2 * EDGES)), "lam_impact": np.full(EDGES, 0.5), "c_to": c, "cd_to": cd,
                   "L_to": L, "pitch_flight": bb[0][2, ::nlp.flight_substeps]})
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
