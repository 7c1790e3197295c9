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


def test_structured_derivatives_match_automatic_ones():
    """The compiled-node grad_f, jac_g and hess_lag equal CasADi's derivatives of the plain
    NLP expressions at a random point, and without them Ipopt reaches the same optimum."""
    import casadi as ca
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
    der = nlp.nlp["derivatives"]
    w, f, g = nlp.nlp["x"], nlp.nlp["f"], nlp.nlp["g"]
    rng = np.random.default_rng(2)
    w0 = nlp.w0 + 0.05 * rng.standard_normal(nlp.w0.size)
    lam_f, lam_g = 0.7, rng.standard_normal(g.shape[0])
    lf, lg = ca.MX.sym("lf"), ca.MX.sym("lg", g.shape[0])
    ref = ca.Function("ref", [w, lf, lg], [f, ca.gradient(f, w), g, ca.jacobian(g, w),
                                          ca.hessian(lf * f + ca.dot(lg, g), w)[0]])
    f_r, gf_r, g_r, jg_r, h_r = (np.asarray(ca.DM(v)) for v in ref(w0, lam_f, lam_g))
    f_c, gf_c = der["grad_f"](w0, [])
    g_c, jg_c = der["jac_g"](w0, [])
    h_c = np.asarray(ca.DM(der["hess_lag"](w0, [], lam_f, lam_g)))
    assert np.isclose(float(f_c), f_r.item(), rtol=1e-12)
    assert np.allclose(np.asarray(gf_c), gf_r, rtol=1e-10, atol=1e-10 * np.abs(gf_r).max())
    assert np.allclose(np.asarray(g_c), g_r, rtol=1e-12, atol=1e-12)
    assert np.allclose(np.asarray(ca.DM(jg_c)), jg_r, rtol=1e-12, atol=1e-12)
    assert np.allclose(h_c, np.triu(h_r), rtol=1e-10, atol=1e-10 * np.abs(h_r).max())
    plain = dict(nlp.nlp)
    plain.pop("derivatives")
    r1 = solve_nlp(build_solver(nlp.nlp), nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg)
    r2 = solve_nlp(build_solver(plain), nlp.w0, nlp.lbx, nlp.ubx, nlp.lbg, nlp.ubg)
    assert r1.success and r2.success and abs(r1.cost - r2.cost) <= 1e-8 * r2.cost
