"""The 1 kHz export (latentoc.jump.export): its motion's derivatives and the contact forces between
the NLP's nodes (balanced_edge_weights)."""
import numpy as np
import pinocchio as pin

from latentoc.jump.contact import FootGeometry, generator_columns, point_jacobians
from latentoc.jump.export import balanced_edge_weights
from latentoc.jump.training import jump_model, training_jumps


def _static():
    model, _ = jump_model()
    q = training_jumps()[0].Q[0]
    d = model.createData()
    z = np.zeros(model.nv)
    tau = pin.rnea(model, d, q, z, z)
    C = generator_columns(point_jacobians(model, d, q, FootGeometry.from_standing(model, q)), 0.4)
    return model, tau, C


def test_static_stance_gets_unilateral_forces_within_the_torque_limits():
    """Standing still: edge weights >= 0 that balance the base rows of numeric rnea exactly, on
    the loaded points only, with the joint torques inside limits around the balanced torques."""
    model, tau, C = _static()
    free = np.array([False, False, True, True, True, True])  # heel unloaded
    lam = balanced_edge_weights(C, tau, np.full(6, 100.0), free, -1e4 * np.ones(model.nv - 6),
                                1e4 * np.ones(model.nv - 6))
    assert np.all(lam >= 0) and np.all(lam[~free] == 0)
    np.testing.assert_allclose(C[[0, 2, 4]] @ lam, tau[[0, 2, 4]], rtol=1e-8, atol=1e-6)
    # tight limits around that solution's torques: still met
    tj = tau[6:] - C[6:] @ lam
    lam2 = balanced_edge_weights(C, tau, np.zeros(6), free, tj - 1.0, tj + 1.0)
    tj2 = tau[6:] - C[6:] @ lam2
    assert np.all(tj2 >= tj - 1.0 - 1e-6) and np.all(tj2 <= tj + 1.0 + 1e-6)
    np.testing.assert_allclose(C[[0, 2, 4]] @ lam2, tau[[0, 2, 4]], rtol=1e-8, atol=1e-6)


def test_a_pulling_wrench_is_balanced_outside_the_cone():
    """A base wrench that needs the ground to pull (gravity reversed): no unilateral forces
    give it, so the fallback balances the rows with a negative edge weight."""
    model, tau, C = _static()
    free = np.ones(6, bool)
    t = tau.copy()
    t[[0, 2, 4]] *= -1.0
    lam = balanced_edge_weights(C, t, np.zeros(6), free, -1e4 * np.ones(model.nv - 6), 1e4 * np.ones(model.nv - 6))
    np.testing.assert_allclose(C[[0, 2, 4]] @ lam, t[[0, 2, 4]], rtol=1e-8, atol=1e-6)
    assert lam.min() < 0


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
    y = small_jump.layer.motion(np.hstack([small_jump.nlp.splines[0].evaluate(tr["control_points"], t[[300]], k)
                                           for k in range(3)])).y[0]
    np.testing.assert_allclose(Q[300], small_jump.js.smap.to_full(y, Q[300][:7]), atol=1e-12)
