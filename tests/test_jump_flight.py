"""Ballistic flight (latentoc.jump.closure.ballistic) against numeric Pinocchio: zero base wrench in flight."""
import numpy as np
import pinocchio as pin

from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.closure.ballistic import ballistic_base, cumulative_trapezoid_matrix, flight_functions
from latentoc.latent.gp_layer import GPLayer
from latentoc.latent.spline import BSpline


def test_cumulative_trapezoid_is_exact_for_linear_functions():
    tau = np.sort(np.random.default_rng(0).uniform(0, 1, 9))
    tau[0] = 0.0
    M = cumulative_trapezoid_matrix(tau)
    assert np.allclose((3 + 2 * tau) @ M, 3 * tau + tau**2)


def test_flight_base_has_zero_base_wrench_and_keeps_momentum(jump_setup):
    """The ballistic base (the pitch rate integrated by the trapezoid rule) of the GP
    layer's joint motion along the training fit, from the captured takeoff state: numeric
    pinocchio.rnea finds no base wrench, the linear momentum falls at g and the angular momentum
    about the COM (pinocchio.computeCentroidalMomentum) stays."""
    js = jump_setup
    ph, tr = js.phases, js.training
    sp = BSpline(len(js.init["P"]), ph.duration)
    tau = np.linspace(0.0, ph.touchdown - ph.takeoff, 41)
    m = GPLayer(js.gpdm).motion(np.hstack([sp.evaluate(js.init["P"], ph.takeoff + tau, k) for k in range(3)]))
    Y = [m.y.T, m.yd.T, m.ydd.T]
    i = int(np.argmin(np.abs(tr.t - ph.takeoff)))
    b_to, bd_to = tr.base[i], np.gradient(tr.base, tr.t, axis=0)[i]  # any takeoff state
    B = [np.array(v).T for v in ballistic_base(flight_functions(js.sym, js.smap), *Y, tau, b_to, bd_to,
                                                Y[0][:, 0], Y[1][:, 0])]
    assert np.allclose(B[0][0], b_to) and np.allclose(B[1][0], bd_to)
    model, d = js.model, js.model.createData()
    W = sum(I.mass for I in model.inertias) * 9.81
    q7, v6, a6 = base_to_freeflyer(*B)
    z7 = np.zeros(7)
    hg = []
    for k in range(len(tau)):
        q = js.smap.to_full(m.y[k], q7[k])
        v = np.concatenate([v6[k], js.smap.to_full(m.yd[k], z7)[7:]])
        a = np.concatenate([a6[k], js.smap.to_full(m.ydd[k], z7)[7:]])
        assert np.abs(pin.rnea(model, d, q, v, a)[:6]).max() < 1e-8 * W
        hg.append(pin.computeCentroidalMomentum(model, d, q, v).vector.copy())
    hg = np.array(hg)
    # linear momentum falls at g, angular momentum about the COM is conserved
    mass = W / 9.81
    assert np.allclose(hg[:, 2] - hg[0, 2], -mass * 9.81 * tau, atol=1e-8 * mass)
    assert np.allclose(hg[:, 0], hg[0, 0]) and np.allclose(hg[:, 4], hg[0, 4], atol=1e-8)
