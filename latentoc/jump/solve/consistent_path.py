"""A start the planted foot can follow: the latent path moved least so that its contacts are physical.

With the base taken from the planted body (:mod:`..closure.planted_legs`), every error of the GP mean's legs
becomes a base motion: along the plain fit of the learned latent points the CMU's closed base
accelerates at several hundred m/s^2 in the last 30 ms before takeoff, while the planted
demonstration's own base accelerates at some tens. Before phase 1, the free control points and the
landing point x_L are fitted by least squares so that the closed base accelerates as the
demonstration's does in the contact phases, the legs meet the GP mean's at the takeoff, the
touchdown and the hinge's switches, the ballistic flight from the takeoff lands on the landing's
planted base at rest, and the path stays inside the tube, each control point moving as little as
that allows.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from latentoc.latent.gp_layer import Layer
from latentoc.latent.spline import BSpline
from latentoc.jump.closure.ballistic import ballistic_base, flight_functions
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.robot.jump_robot import JumpRobot

__all__ = ["consistent_path"]

G = 9.81
SPACING = 0.005  # s between the contact phases' acceleration samples
MOVE = 0.05  # latent units a control point moves at the cost of one unit of residual
TUBE_FILL = 0.95  # the tube is filled to this fraction of delta at the most


def _motion(layer: Layer, spline: BSpline, P: np.ndarray, t: np.ndarray):
    m = layer.motion(np.hstack([spline.evaluate(P, t, k) for k in range(3)]))
    return m.y, m.yd, m.ydd


def consistent_path(robot: JumpRobot, layer: Layer, spline: BSpline, phases: Phases, P0: np.ndarray, x_L0: float,
                    base_acc, delta: float | None, columns: int | None = None, max_nfev: int = 60
                    ) -> tuple[np.ndarray, float, dict]:
    """Control points and landing point of the consistent start (module doc) from the fit ``P0``
    and ``x_L0``; ``base_acc(t)``: the demonstration's base acceleration (K x 3) at contact times t;
    ``delta``: the tube (None for a joint path); ``columns``: the path's leading coordinates fitted
    (the latent ones; None: all). Returns (P, x_L, the residuals' worst parts)."""
    cl, ph = robot.closure, phases
    assert cl is not None
    T = ph.duration
    t = np.arange(0.0, T + 1e-9, SPACING)
    tc = t[ph.on_ground(t)]
    land = ph.landed(tc)
    target = np.asarray(base_acc(tc), float)
    held = ph.held(tc)
    fns = flight_functions(robot.sym, robot.smap)
    i_to, i_td = int(np.argmin(np.abs(tc - ph.takeoff))), int(np.flatnonzero(land)[0])
    tf = np.linspace(0.0, ph.touchdown - ph.takeoff, 41)
    idx = cl.dependent.tolist() + ([cl.hinge] if cl.hinge is not None else [])
    switch = np.array([e for e in ph.events if abs(e - ph.takeoff) > 1e-9 and abs(e - ph.touchdown) > 1e-9])
    free = np.zeros(P0.shape, bool)
    free[1:-1, :P0.shape[1] if columns is None else columns] = True
    n_tube = max(2, int(round(T / SPACING)) + 1)
    t_tube = np.linspace(0.0, T, n_tube)[1:-1]

    def unpack(v):
        P = np.array(P0, float)
        P[free] = v[:-1]
        return P, float(v[-1])

    def parts(v) -> dict[str, np.ndarray]:
        P, x_L = unpack(v)
        y, yd, ydd = _motion(layer, spline, P, tc)
        shift = robot.geom.planted_shift(land, x_L)
        yc, ydc, _, b, bd, bdd = cl.evaluate(y, yd, ydd, held, shift)
        out = {"acc": (bdd - target).ravel() / G / np.sqrt(len(tc))}
        gaps = []
        for i in (i_to, i_td):
            gaps += [(yc[i] - y[i])[idx], 0.1 * (ydc[i] - yd[i])[idx]]
        if cl.hinge is not None and len(switch):
            ys, yds, _ = _motion(layer, spline, P, switch)
            gaps += [ys[:, cl.hinge] - cl.hinge_standing, 0.1 * yds[:, cl.hinge]]
        out["gap"] = np.concatenate(gaps)
        Yf = _motion(layer, spline, P, ph.takeoff + tf)
        bb = ballistic_base(fns, Yf[0].T, Yf[1].T, Yf[2].T, tf, b[i_to], bd[i_to], yc[i_to], ydc[i_to])
        out["flight"] = np.concatenate([10 * (bb[0][:, -1] - b[i_td]), bb[1][:, -1] - bd[i_td]])
        if delta is not None:
            s2 = layer.variance(spline.evaluate(P, t_tube))[0]
            out["tube"] = 10 * np.maximum(s2 / delta - TUBE_FILL, 0.0)
        out["move"] = (v[:-1] - P0[free]) / MOVE * 0.1
        return out

    def residual(v):
        return np.concatenate(list(parts(v).values()))

    def support(times: np.ndarray) -> np.ndarray:
        """Which free control points' coordinates (columns) the path touches at each of the times."""
        near = np.abs(np.stack([spline.basis(times, k, ph.closing(times)) for k in range(3)])).sum(axis=0) > 0
        return np.repeat(near, P0.shape[1], axis=1)[:, free.ravel()]

    # each residual block touches the control points near its times only: the Jacobian's columns are grouped
    v0 = np.concatenate([P0[free], [x_L0]])
    blocks = parts(v0)
    n_v = len(v0)
    rows = [np.repeat(support(tc), 3, axis=0)]
    gap_t = np.concatenate([[ph.takeoff, ph.touchdown], switch if cl.hinge is not None else np.zeros(0)])
    sup = support(gap_t)
    rows.append(np.vstack([np.repeat(sup[[0]], 2 * len(idx), axis=0), np.repeat(sup[[1]], 2 * len(idx), axis=0),
                           np.tile(sup[2:], (2, 1))]))
    fl = np.asarray(support(np.linspace(ph.takeoff, ph.touchdown, 200)).any(axis=0) | support(np.array([ph.takeoff])).any(axis=0))
    rows.append(np.repeat(fl[None], 6, axis=0))
    if delta is not None:
        rows.append(support(t_tube))
    rows = [np.hstack([r, np.zeros((r.shape[0], 1), bool)]) for r in rows]
    rows[2][:, -1] = True  # x_L places the landing's planted base
    rows.append(np.eye(n_v - 1, n_v, dtype=bool))
    sparsity = np.vstack(rows)
    assert sparsity.shape == (sum(b.size for b in blocks.values()), n_v)
    fit = least_squares(residual, v0, max_nfev=max_nfev, x_scale="jac", jac_sparsity=sparsity)
    P, x_L = unpack(fit.x)
    report = {k: float(np.max(np.abs(r))) if r.size else 0.0 for k, r in parts(fit.x).items()}
    report.update({"start_" + k: float(np.max(np.abs(r))) if r.size else 0.0 for k, r in parts(v0).items()})
    report["cost"], report["nfev"] = float(fit.cost), int(fit.nfev)
    return P, x_L, report
