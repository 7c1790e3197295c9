"""Ballistic flight (latentoc.jump.flight) against numeric Pinocchio: zero base wrench in flight."""
import casadi as ca
import numpy as np
import pinocchio as pin

from latentoc.jump.base import base_to_freeflyer
from latentoc.jump.contact import joint_embedding
from latentoc.jump.flight import ballistic_base, cumulative_trapezoid_matrix, flight_functions

from latentoc.spline import BSpline


def test_cumulative_trapezoid_is_exact_for_linear_functions():
    tau = np.sort(np.random.default_rng(0).uniform(0, 1, 9))
    tau[0] = 0.0
    M = cumulative_trapezoid_matrix(tau)
    assert np.allclose((3 + 2 * tau) @ M, 3 * tau + tau**2)


def test_flight_base_has_zero_base_wrench_and_keeps_momentum(jump_setup):
    js = jump_setup
    ph, tr, gp = js.phases, js.training, js.gpdm
    m = len(js.init["P"])
    sp = BSpline(m, ph.duration)
    tau = np.linspace(0.0, ph.touchdown - ph.takeoff, 41)
    X = [sp.evaluate(js.init["P"], ph.takeoff + tau, k).T for k in range(3)]
    i = int(np.argmin(np.abs(tr.t - ph.takeoff)))
    b_to, bd_to = tr.base[i], np.gradient(tr.base, tr.t, axis=0)[i]  # any takeoff state
    B = [np.array(v).T for v in ballistic_base(flight_functions(js.sym, js.smap, gp), *X, tau, b_to, bd_to,
                                                X[0][:, 0], X[1][:, 0])]
    assert np.allclose(B[0][0], b_to) and np.allclose(B[1][0], bd_to)
    x = ca.SX.sym("x", gp.latent_dim)
    xd, xdd = ca.SX.sym("xd", gp.latent_dim), ca.SX.sym("xdd", gp.latent_dim)
    y = gp.mean_function()(x)
    yd = ca.jtimes(y, x, xd)
    fy = ca.Function("y", [x, xd, xdd], [y, yd, ca.jtimes(y, x, xdd) + ca.jtimes(yd, x, xd)])
    E = joint_embedding(js.smap)
    model, d = js.model, js.model.createData()
    W = sum(I.mass for I in model.inertias) * 9.81
    q7, v6, a6 = base_to_freeflyer(*B)
    hg = []
    for k in range(len(tau)):
        yv, ydv, yddv = (np.array(v).ravel() for v in fy(X[0][:, k], X[1][:, k], X[2][:, k]))
        q, v, a = (np.concatenate([b[k], E @ j]) for b, j in ((q7, yv), (v6, ydv), (a6, yddv)))
        assert np.abs(pin.rnea(model, d, q, v, a)[:6]).max() < 1e-8 * W
        hg.append(pin.computeCentroidalMomentum(model, d, q, v).vector.copy())
    hg = np.array(hg)
    # linear momentum falls at g, angular momentum about the COM is conserved
    mass = W / 9.81
    assert np.allclose(hg[:, 2] - hg[0, 2], -mass * 9.81 * tau, atol=1e-8 * mass)
    assert np.allclose(hg[:, 0], hg[0, 0]) and np.allclose(hg[:, 4], hg[0, 4], atol=1e-8)
