"""Transcription: boundary rows, quadrature vs a fine trapezoid, constraint rows vs numpy."""

import casadi as ca
import numpy as np
import pytest
from derivative_check import check_custom_derivatives

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
    check_custom_derivatives(nlp.nlp, nlp.w0, seed=1, tol={
        "grad_f": (1e-9, 0.0, 1e-9), "g": (1e-10, 1e-12, 0.0), "jac_g": (1e-9, 0.0, 1e-9),
        "hess": (1e-8, 0.0, 1e-8)})


def test_torque_limits_fall_back_to_automatic_derivatives(setup):
    p, gp, t, sym = setup
    st = TranscriptionSettings(duration=2.9, control_points=7, torque_limits=[50.0])
    nlp = build_latent_nlp(gp, sym, st, 0.05, t)
    assert nlp.derivatives is None and "derivatives" not in nlp.nlp
