"""The 1 kHz export (latentoc.jump.check.export): its motion's derivatives and the contact forces between
the NLP's nodes and samples (corrected_edge_weights)."""
import numpy as np
import pinocchio as pin
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

from latentoc.jump.robot.feet import generator_columns, point_jacobians
from latentoc.jump.check.export import corrected_edge_weights
from latentoc.jump.demonstration.training import training_jumps
from latentoc.robots.cmu_humanoid import symmetric_model


def _static():
    model, _ = symmetric_model()
    q = training_jumps()[0].Q[0]
    d = model.createData()
    z = np.zeros(model.nv)
    tau = pin.rnea(model, d, q, z, z)
    C = generator_columns(point_jacobians(model, d, q, CMU_HUMANOID.geometry(model, q)), 0.4)
    return model, tau, C


def test_correction_balances_the_base_rows_on_the_loaded_edges_least_norm():
    """Standing still from a guess: the corrected edge weights balance the base rows of numeric rnea
    exactly, on the loaded points only, and are the guess plus the least-norm correction (its
    change lies in the row space of the loaded edges' base rows)."""
    model, tau, C = _static()
    free = np.array([False, False, True, True, True, True, True, True])  # heel unloaded
    lam0 = np.full(8, 100.0)
    lam = corrected_edge_weights(C, tau, lam0, free)
    assert np.all(lam >= 0) and np.all(lam[~free] == 0)
    np.testing.assert_allclose(C[[0, 2, 4]] @ lam, tau[[0, 2, 4]], rtol=1e-8, atol=1e-6)
    Cr = C[[0, 2, 4]][:, free]
    change = lam[free] - lam0[free]
    np.testing.assert_allclose(change, Cr.T @ np.linalg.lstsq(Cr.T, change, rcond=None)[0], atol=1e-8)


def test_an_edge_pushed_below_zero_is_held_at_zero():
    """A guess whose least-norm correction would push an edge below zero: that edge is held at
    zero and the others balance the rows, all non-negative."""
    model, tau, C = _static()
    free = np.ones(8, bool)
    lam0 = np.zeros(8)
    lam0[0] = 5e3  # far too much on one heel edge
    lam = corrected_edge_weights(C, tau, lam0, free)
    assert lam.min() >= 0 and np.sum(lam == 0) >= 1
    np.testing.assert_allclose(C[[0, 2, 4]] @ lam, tau[[0, 2, 4]], rtol=1e-8, atol=1e-6)


def test_exported_velocity_and_acceleration_are_derivatives_of_the_motion(small_jump, small_export):
    """On the 1 kHz grid the exported v and a are the time derivatives of q (central differences,
    pinocchio.difference) in the stance, the flight and the landing, and the joint motion is the GP
    layer's along the exported control points."""
    tr, model = small_export, small_jump.js.model
    t, Q, V, A = tr["t"], tr["q"], tr["v"], tr["a"]
    h = t[1] - t[0]
    assert np.isclose(h, 1e-3) and np.isclose(t[-1], small_jump.js.phases.duration)
    for i in (100, 200, 450, 550, 1000, 1250):  # stance, flight, landing
        vd = pin.difference(model, Q[i - 1], Q[i + 1]) / (2 * h)
        np.testing.assert_allclose(vd, V[i], atol=2e-3 * max(1.0, np.abs(V[i]).max()))
        np.testing.assert_allclose((V[i + 1] - V[i - 1]) / (2 * h), A[i], atol=2e-2 * max(1.0, np.abs(A[i]).max()))
    np.testing.assert_array_equal(tr["control_points"], small_jump.js.init["P"])
    cl, smap = small_jump.robot.closure, small_jump.js.smap
    free = np.setdiff1d(np.arange(cl.n), list(cl.dependent) + [cl.hinge])
    for i, joints in ((500, np.arange(cl.n)), (300, free)):  # flight: the GP mean; stance: but the closed joints
        y = small_jump.layer.motion(np.hstack([small_jump.nlp.spline.evaluate(tr["control_points"], t[[i]], k)
                                               for k in range(3)])).y[0]
        np.testing.assert_allclose(smap.to_learned(Q[i])[joints], y[joints], atol=1e-12)


def test_the_toe_tip_stands_at_its_ground_point_in_both_contact_phases(small_jump, small_export):
    """Numeric Pinocchio on the 1 kHz export: the left toe tip stands at its standing x in the stance
    and at the landing's x_L from the touchdown on (Phases.standing/landed with the events' own
    instants, FootGeometry.planted_shift)."""
    from latentoc.jump.schedule.phases import toe_path

    tr, ph, geom = small_export, small_jump.js.phases, small_jump.robot.geom
    t = tr["t"]
    assert ph.standing(ph.takeoff) and not ph.standing(ph.takeoff + 1e-6)
    assert ph.landed(ph.touchdown) and not ph.landed(ph.touchdown - 1e-6)
    assert ph.settled(ph.settle) and not ph.on_ground(0.5 * (ph.takeoff + ph.touchdown))
    toe = toe_path(small_jump.js.model, tr["q"], geom)
    x_L = float(small_jump.nlp.variables.unpack(small_jump.x0)["x_L"][0])
    con = ph.on_ground(t)
    np.testing.assert_allclose(toe[con, 0], geom.toe_x + geom.planted_shift(ph.landed(t[con]), x_L), atol=1e-9)
    np.testing.assert_allclose(toe[ph.landed(t), 0], x_L, atol=1e-9)
