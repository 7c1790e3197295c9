"""Transcription: boundary rows, quadrature vs a fine trapezoid, constraint rows vs numpy."""

import casadi as ca
import numpy as np
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.latent_motion import numeric_latent_motion
from latentoc.problem import load_problem, training_motion
from latentoc.robots import load_robot
from latentoc.solve import problem_gpdm
from latentoc.spline import BSpline
from latentoc.transcription import (TranscriptionSettings, build_latent_nlp, constraint_times,
                                    fit_control_points, gauss_legendre_nodes, trapezoid_cost)


@pytest.fixture(scope="module")
def setup():
    p = load_problem("arm-raise-small")
    gp, _ = problem_gpdm(p)
    t, _ = training_motion(p)
    return p, gp, t, SymbolicModel(load_robot("human-arm"))


def test_rest_boundary_fixes_poses_and_zero_end_velocity(setup):
    _, gp, t, _ = setup
    sp = BSpline(7, 2.9)
    P = fit_control_points(sp, t, gp.X, "rest")
    assert np.allclose(sp.evaluate(P, [0.0, 2.9]), gp.X[[0, -1]])
    assert np.allclose(sp.evaluate(P, [0.0, 2.9], 1), 0.0, atol=1e-12)
    P2 = fit_control_points(sp, t, gp.X, "pose")
    assert np.allclose(P2[[0, -1]], gp.X[[0, -1]])


def test_gauss_legendre_matches_fine_trapezoid(setup):
    p, gp, t, sym = setup
    sp = BSpline(7, 2.9)
    P = fit_control_points(sp, t, gp.X, "rest")
    tq, wq = gauss_legendre_nodes(sp, 8)
    assert np.isclose(wq.sum(), 2.9)
    Lq = numeric_latent_motion(gp, sym, *(sp.evaluate(P, tq, r) for r in (0, 1, 2)))["L"]
    tf = np.linspace(0, 2.9, 29001)  # 0.1 ms trapezoid as the reference
    Lf = numeric_latent_motion(gp, sym, *(sp.evaluate(P, tf, r) for r in (0, 1, 2)))["L"]
    ref = trapezoid_cost(Lf, tf[1] - tf[0])
    assert abs(Lq @ wq - ref) / ref < 1e-3


def test_constraint_rows_are_sigma2_and_q(setup):
    p, gp, t, sym = setup
    st = TranscriptionSettings(duration=2.9, control_points=7, constraint_points=6)
    nlp = build_latent_nlp(gp, sym, st, 0.05, t)
    grid = constraint_times(nlp.spline, 6)
    assert grid[0] > 0 and grid[-1] < 2.9 and len(grid) == 4 * 6 - 1
    g = np.asarray(ca.Function("g", [nlp.nlp["x"]], [nlp.nlp["g"]])(nlp.w0)).ravel()
    x = nlp.spline.evaluate(nlp.P_init, grid)
    K = len(grid)
    assert np.allclose(g[:K], gp.variance(x), rtol=1e-8)
    assert np.allclose(g[K:].reshape(K, 7), gp.mean(x), atol=1e-10)
    assert np.all(nlp.ubg[:K] == 0.05) and nlp.w0.size == 3 * 3


@pytest.mark.parametrize("closed_form,joint_limits,jit", [(True, True, True), (True, False, True),
                                                         (False, True, True), (True, True, False)])
def test_lifted_derivatives_match_automatic_ones(setup, closed_form, joint_limits, jit):
    """The structured grad_f, jac_g and hess_lag (lifted to the quadrature/grid nodes, with the
    closed-form grid derivatives or CasADi's, compiled node derivatives or SX) equal CasADi's
    derivatives of the plain NLP expressions."""
    p, gp, t, sym = setup
    st = TranscriptionSettings(duration=2.9, control_points=7, quadrature_points=4, constraint_points=6,
                               closed_form_grid=closed_form, joint_limits=joint_limits, jit=jit)
    nlp = build_latent_nlp(gp, sym, st, 0.05, t)
    der = nlp.nlp["derivatives"]
    assert der is nlp.derivatives and set(der) == {"grad_f", "jac_g", "hess_lag"}
    w, f, g = nlp.nlp["x"], nlp.nlp["f"], nlp.nlp["g"]
    rng = np.random.default_rng(1)
    w0 = nlp.w0 + 0.05 * rng.standard_normal(nlp.w0.size)
    lam_f, lam_g = 0.7, rng.standard_normal(g.shape[0])
    lg = ca.MX.sym("lg", g.shape[0])
    lf = ca.MX.sym("lf")
    ref = ca.Function("ref", [w, lf, lg], [f, ca.gradient(f, w), g, ca.jacobian(g, w),
                                          ca.hessian(lf * f + ca.dot(lg, g), w)[0]])
    f_r, gf_r, g_r, jg_r, h_r = (np.asarray(ca.DM(v)) for v in ref(w0, lam_f, lam_g))
    f_c, gf_c = der["grad_f"](w0, [])
    g_c, jg_c = der["jac_g"](w0, [])
    h_c = np.asarray(ca.DM(der["hess_lag"](w0, [], lam_f, lam_g)))
    assert np.isclose(float(f_c), f_r.item(), rtol=1e-12)
    assert np.allclose(np.asarray(gf_c), gf_r, rtol=1e-9, atol=1e-9 * np.abs(gf_r).max())
    assert np.allclose(np.asarray(g_c), g_r, rtol=1e-10, atol=1e-12)
    assert np.allclose(np.asarray(ca.DM(jg_c)), jg_r, rtol=1e-9, atol=1e-9 * np.abs(jg_r).max())
    assert np.allclose(h_c, np.triu(h_r), rtol=1e-8, atol=1e-8 * np.abs(h_r).max())


def test_torque_limits_fall_back_to_automatic_derivatives(setup):
    p, gp, t, sym = setup
    st = TranscriptionSettings(duration=2.9, control_points=7, torque_limits=[50.0])
    nlp = build_latent_nlp(gp, sym, st, 0.05, t)
    assert nlp.derivatives is None and "derivatives" not in nlp.nlp
