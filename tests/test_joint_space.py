"""Full configuration-space baseline: converges, respects the joint range, same objective."""

import numpy as np
import pytest

from latentoc.problem import load_problem
from latentoc.solve import solve


@pytest.fixture(scope="module")
def solution():
    return solve(load_problem("arm-raise-small"), method="joint-range", joint_range_deg=10.0)


def test_converges_within_range(solution):
    r, tr = solution.result, solution.trajectory
    assert r["success"] and r["cost"] < r["cost_initial"]
    assert r["method"] == "joint-range" and r["joint_range_deg"] == 10.0
    dP = np.degrees(np.abs(tr["P"] - tr["P_initial"]))
    assert dP.max() <= 10.0 + 1e-4  # Ipopt relaxes bounds by ~1e-8 relative
    assert np.allclose(dP[[0, 1, -2, -1]], 0.0)  # boundary rows fixed
    assert r["quadrature_error"] < 2e-3


def test_initial_is_training_motion_fit(solution):
    from latentoc.human_models import arm_training_motion
    t, Q = arm_training_motion()
    tr = solution.trajectory
    qi = np.array([np.interp(t, tr["t"], tr["q_initial"][:, j]) for j in range(7)]).T
    assert np.degrees(np.abs(qi - Q).max()) < 3.0
    assert np.allclose(tr["q"][0], Q[0]) and np.allclose(tr["q"][-1], Q[-1])
