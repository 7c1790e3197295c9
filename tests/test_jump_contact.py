"""Toe-pinned anchoring keeps the toe tip on the ground (numeric FK); pyramid forces."""
import casadi as ca
import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.jump.base import base_to_freeflyer
from latentoc.jump.contact import FootGeometry, anchor_function, point_forces
from latentoc.jump.training import FOOT, TOE, jump_model, training_jumps


def test_anchored_base_keeps_the_toe_fixed_and_symmetric():
    model, smap = jump_model()
    tr = training_jumps()[0]
    geom = FootGeometry.from_standing(model, tr.Q[0])
    anchor = anchor_function(SymbolicModel(model), smap, geom)
    d = model.createData()
    for i, phi in ((0, 0.0), (30, 0.2), (100, 0.05)):
        b = np.array(anchor(tr.Y[i], phi, 0.37)).ravel()
        q = smap.to_full(tr.Y[i], base_to_freeflyer(b)[0][0])
        pin.framesForwardKinematics(model, d, q)
        toe = d.oMf[model.getFrameId(TOE)].translation
        assert np.allclose(toe[[0, 2]], [0.37, 0.0], atol=1e-9)
        rtoe = d.oMf[model.getFrameId("rtoes_end")].translation
        assert np.allclose(rtoe, toe * [1, -1, 1], atol=1e-9)  # mirror image
        M = d.oMf[model.getFrameId(FOOT)]
        heel = M.translation + M.rotation @ geom.heel_offset
        dx, dz = toe[0] - heel[0], heel[2] - toe[2]
        assert np.isclose(np.arctan2(dz, dx), phi, atol=1e-9)


def test_pyramid_forces_are_unilateral_and_in_the_cone():
    rng = np.random.default_rng(1)
    for _ in range(20):
        lam = rng.uniform(0, 100, 6)
        for fx, fz in point_forces(lam, 0.4):
            assert fz >= 0 and abs(fx) <= 0.4 * fz + 1e-12
