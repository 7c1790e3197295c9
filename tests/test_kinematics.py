"""latentoc.robots.point_kinematics against finite differences of Pinocchio's forward kinematics."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from latentoc.robots.point_kinematics import point_jacobian
from latentoc.robots.catalog import load_robot


def test_point_jacobian_is_the_points_velocity():
    """A point fixed 10 cm off the G1's left ankle frame, at a random pose and velocity: J v equals
    the central difference of its world position along integrate(q, h v)."""
    g = load_robot("g1")
    d = g.createData()
    rng = np.random.default_rng(5)
    q = pin.randomConfiguration(g, np.maximum(g.lowerPositionLimit, -1.0), np.minimum(g.upperPositionLimit, 1.0))
    v = rng.normal(size=g.nv)
    fid = g.getFrameId("left_ankle_roll_link")
    offset = np.array([0.1, -0.02, -0.03])

    def point(qq):
        pin.framesForwardKinematics(g, d, qq)
        return d.oMf[fid].act(offset)

    h = 1e-6
    fd = (point(pin.integrate(g, q, h * v)) - point(pin.integrate(g, q, -h * v))) / (2 * h)
    pin.computeJointJacobians(g, d, q)
    pin.framesForwardKinematics(g, d, q)
    np.testing.assert_allclose(point_jacobian(g, d, fid, d.oMf[fid].act(offset)) @ v, fd, atol=1e-7)


def test_runs_are_the_masks_stretches():
    """latentoc.intervals.runs against a direct scan: every True run, its start and exclusive stop."""
    from latentoc.intervals import runs

    rng = np.random.default_rng(1)
    for n in (0, 1, 7, 50):
        mask = rng.random(n) < 0.5
        expected, start = [], None
        for i, m in enumerate(list(mask) + [False]):
            if m and start is None:
                start = i
            elif not m and start is not None:
                expected.append((start, i))
                start = None
        assert runs(mask) == expected
