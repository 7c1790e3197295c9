"""The exporter's contact forces between the NLP's nodes (latentoc.jump.problem.balanced_edge_weights)."""
import numpy as np
import pinocchio as pin

from latentoc.jump.contact import FootGeometry, generator_columns, point_jacobians
from latentoc.jump.problem import balanced_edge_weights
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
