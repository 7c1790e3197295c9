"""The jump's initial point: the training motion in the NLP's variables.

The latent path is the setup's smoothed fit of the learned latent points; the contact phases'
base splines are least-squares fits of the captured base; the flight's takeoff state and pitch
follow from the stance at takeoff (ballistic, :mod:`.flight`); the contact forces are the
non-negative edge weights of the loaded points that best balance each node's base rows.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from ..latent.gp_layer import GPLayer
from .flight import ballistic_base, flight_functions
from .nlp import JumpNLP
from .robot import JumpRobot

__all__ = ["initial_point"]


def _joint_motion(layer: GPLayer, sp_, P: np.ndarray, t: np.ndarray) -> list[np.ndarray]:
    Z = np.hstack([sp_.evaluate(P, t, k) for k in range(3)])
    m = layer.motion(Z)
    return [m.y.T, m.yd.T, m.ydd.T]  # n x K each


def initial_point(robot: JumpRobot, layer: GPLayer, nlp: JumpNLP, P: np.ndarray, t: np.ndarray, base: np.ndarray,
                  x_L: float, takeoff: float, touchdown: float) -> np.ndarray:
    """The training start (module doc) of ``nlp`` from the latent control points P, the captured
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
    tau_fine = nlp.meta["tau_fine"]
    Yf = _joint_motion(layer, sp_, P, takeoff + tau_fine)
    bb = ballistic_base(fns, *Yf, tau_fine, b_to, bd_to, y_to, yd_to)
    nC = var.shapes["lam"][0]
    x0 = var.pack({"P": P[1:-1], "base_stance": base_s, "base_land": base_l, "x_L": x_L,
                   "lam": np.full((nC, 6), 1.0 / 12.0), "lam_impact": np.full(6, 0.5), "c_to": c, "cd_to": cd,
                   "L_to": L, "pitch_flight": bb[0][2, ::nlp.meta["flight_substeps"]]})
    return balanced_forces(nlp, np.clip(x0, nlp.lbx, nlp.ubx))


def balanced_forces(nlp: JumpNLP, w: np.ndarray) -> np.ndarray:
    """``w`` with the contact nodes' edge weights that best balance their base rows: the rows are
    affine in the weights, so per node a non-negative least-squares fit over the loaded edges."""
    var = nlp.variables
    lam = var.index("lam")
    dyn = nlp.row_names == "dynamics"
    x = np.array(w, float)
    x[lam.ravel()] = 0.0
    c = nlp.nlp.constraints(x)[dyn].reshape(-1, 3)
    A = np.zeros((c.shape[0], 3, 6))
    for k in range(6):
        xk = x.copy()
        xk[lam[:, k]] = 1.0
        A[:, :, k] = nlp.nlp.constraints(xk)[dyn].reshape(-1, 3) - c
    loaded = nlp.ubx[lam] > 0
    for j in range(c.shape[0]):
        x[lam[j, loaded[j]]] = nnls(A[j][:, loaded[j]], -c[j])[0]
    return x
