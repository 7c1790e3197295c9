"""The 7-DOF arm of Sect. 4.1 and its user-made training trial."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.robots.human_arm import arm_trial, build_human_arm


@pytest.fixture(scope="module")
def arm():
    return build_human_arm()


def _hand(model, q):
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    return d.oMf[model.getFrameId("lhand_end")].translation.copy()


def test_sizes_and_mass(arm):
    assert (arm.nq, arm.nv) == (7, 7)
    assert all(j.nq == 1 for j in arm.joints[1:])
    assert abs(sum(I.mass for I in arm.inertias) - 8.74) < 1e-12
    for I in arm.inertias[1:]:
        if I.mass > 0:
            assert np.all(np.linalg.eigvalsh(I.inertia) > 0)
    assert np.allclose(arm.gravity.linear, [0, 0, -9.81])
    assert arm.existFrame("lhand_end")
    # human proportions: upper arm heaviest, hand lightest, arm about 0.6 m long
    assert np.isclose(np.linalg.norm(_hand(arm, np.zeros(7))), 0.6166, atol=1e-3)


def test_start_and_goal_poses(arm):
    t, Q = arm_trial()
    start, goal = _hand(arm, Q[0]), _hand(arm, Q[-1])
    assert start[2] < -0.5 and np.hypot(start[0], start[1]) < 0.15  # hanging down
    assert goal[2] > 0.3 and goal[0] > 0.2  # raised forward, above the shoulder (z = 0)


def test_timing_and_smoothness(arm):
    t, Q = arm_trial()
    assert t.shape == (349,) and Q.shape == (349, 7)
    assert t[0] == 0.0 and np.isclose(t[-1], 2.9) and np.allclose(np.diff(t), 1 / 120)
    dt = t[1] - t[0]
    V = np.gradient(Q, dt, axis=0)
    A = np.gradient(V, dt, axis=0)
    assert np.abs(V).max() < 3.0 and np.abs(A).max() < 10.0  # rad/s, rad/s^2
    _, Va = arm_trial(1)
    _, Aa = arm_trial(2)
    assert np.allclose(Va[[0, -1]], 0) and np.allclose(Aa[[0, -1]], 0)
    assert np.allclose(V[1:-1], Va[1:-1], atol=1e-3)  # analytic derivatives consistent
    # no jumps in acceleration (C2): per-sample change bounded by jerk * dt
    assert np.abs(np.diff(Aa, axis=0)).max() < 0.2
    assert np.abs(np.diff(A[2:-2], axis=0)).max() < 0.2
    assert np.allclose(Q[1] - Q[0], 0, atol=1e-5) and np.allclose(Q[-1] - Q[-2], 0, atol=1e-5)


def test_within_limits_and_not_optimal(arm):
    t, Q = arm_trial()
    assert np.all(Q >= arm.lowerPositionLimit) and np.all(Q <= arm.upperPositionLimit)
    _, V = arm_trial(1)
    _, A = arm_trial(2)
    d = arm.createData()
    cost = sum(np.sum(pin.rnea(arm, d, q, v, a) ** 2) for q, v, a in zip(Q, V, A)) * (t[1] - t[0])
    # the straight minimum-jerk blend between the same poses is cheaper: a detour
    s = 10 * (t / 2.9) ** 3 - 15 * (t / 2.9) ** 4 + 6 * (t / 2.9) ** 5
    s1 = 30 * (t / 2.9) ** 2 * (1 - t / 2.9) ** 2 / 2.9
    s2 = 60 * (t / 2.9) * (1 - t / 2.9) * (1 - 2 * t / 2.9) / 2.9**2
    dq = Q[-1] - Q[0]
    plain = sum(np.sum(pin.rnea(arm, d, Q[0] + si * dq, s1i * dq, s2i * dq) ** 2)
                for si, s1i, s2i in zip(s, s1, s2)) * (t[1] - t[0])
    assert cost > 1.1 * plain
