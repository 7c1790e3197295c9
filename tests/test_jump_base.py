"""Sagittal base -> free-flyer q, v, a against Pinocchio's Lie-group difference."""
import numpy as np
import pinocchio as pin

from latentoc.jump.robot.sagittal_base import base_to_freeflyer, freeflyer_to_base


def test_velocity_and_acceleration_match_finite_differences():
    m = pin.Model()
    m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "ff")
    t = np.linspace(0, 1, 2001)
    h = t[1] - t[0]
    b = np.column_stack([np.sin(2 * t), 1 + 0.3 * t ** 2, 0.7 * np.cos(3 * t)])
    bd = np.column_stack([2 * np.cos(2 * t), 0.6 * t, -2.1 * np.sin(3 * t)])
    bdd = np.column_stack([-4 * np.sin(2 * t), 0.6 + 0 * t, -6.3 * np.cos(3 * t)])
    q, v, a = base_to_freeflyer(b, bd, bdd)
    for k in (200, 1000, 1800):
        assert np.allclose(v[k], pin.difference(m, q[k - 1], q[k + 1]) / (2 * h), atol=1e-5)
        assert np.allclose(a[k], (v[k + 1] - v[k - 1]) / (2 * h), atol=1e-4)
    assert np.allclose(freeflyer_to_base(q), b)
    assert np.allclose(q[:, [1, 3, 5]], 0.0)  # symmetric: no lateral position, roll, yaw
