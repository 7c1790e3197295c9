"""Full configuration-space baseline: converges, respects the joint range, same objective."""

import numpy as np
import pytest
from derivative_check import check_custom_derivatives

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


def test_structured_derivatives_match_automatic_ones():
    """The compiled-node grad_f, jac_g and hess_lag equal CasADi's derivatives of the plain
    NLP expressions at a random point, and without them Ipopt reaches the same optimum."""
    from latentoc.dynamics import SymbolicModel
    from latentoc.human_models import arm_training_motion
    from latentoc.joint_space import build_joint_nlp
    from latentoc.robots import load_robot
    from latentoc.solver import build_solver, solve_nlp
    from latentoc.transcription import TranscriptionSettings
    t, Q = arm_training_motion()
    sym = SymbolicModel(load_robot("human-arm"))
    st = TranscriptionSettings(duration=2.9, control_points=7, quadrature_points=4, constraint_points=6)
    nlp = build_joint_nlp(sym, st, t, Q, 10.0)
    check_custom_derivatives(nlp.nlp, nlp.w0, seed=2, tol={
        "grad_f": (1e-10, 0.0, 1e-10), "g": (1e-12, 1e-12, 0.0), "jac_g": (1e-12, 1e-12, 0.0),
        "hess": (1e-10, 0.0, 1e-10)})
    plain = dict(nlp.nlp)
    plain.pop("derivatives")
    r1 = solve_nlp(build_solver(nlp.nlp), nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg)
    r2 = solve_nlp(build_solver(plain), nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg)
    assert r1.success and r2.success and abs(r1.cost - r2.cost) <= 1e-8 * r2.cost
