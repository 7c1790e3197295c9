"""ZMP formula: a static pose has its ZMP at the projected COM; a known dynamic case."""
import numpy as np
import pinocchio as pin

from latentoc.jump.demonstration.training import training_jumps

from latentoc.robots.cmu_humanoid import symmetric_model
from latentoc.jump.robot.zmp import G, zmp


def test_static_pose_zmp_is_projected_com():
    model, _ = symmetric_model()
    q = training_jumps()[0].Q[0]
    d = model.createData()
    z = np.zeros(model.nv)
    dh = pin.computeCentroidalMomentumTimeVariation(model, d, q, z, z).vector
    c = pin.centerOfMass(model, d, q)
    px, py = zmp(c, dh, sum(i.mass for i in model.inertias))
    assert np.allclose([px, py], c[:2], atol=1e-9)


def test_point_mass_accelerating_forward():
    # point mass at height h accelerating with ax: p_x = c_x - h ax / g (linear inverted pendulum)
    m, h, ax = 10.0, 0.8, 2.0
    px, py = zmp(np.array([0.1, 0.0, h]), np.array([m * ax, 0, 0, 0, 0, 0]), m)
    assert np.isclose(px, 0.1 - h * ax / G) and py == 0.0
