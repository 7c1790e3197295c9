"""q, v, a through the GPDM mean (Eq. 26-28) against finite differences; torques vs pinocchio."""

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.latent_motion import gp_grid_function, latent_kinematics, latent_motion_grid, numeric_latent_motion
from latentoc.problem import load_problem
from latentoc.robots import load_robot
from latentoc.solve import problem_gpdm
from latentoc.spline import BSpline
from latentoc.transcription import fit_control_points


@pytest.fixture(scope="module")
def setup():
    p = load_problem("arm-raise-small")
    gp, _ = problem_gpdm(p)
    model = load_robot("human-arm")
    return gp, model, SymbolicModel(model)


def test_kinematics_match_finite_differences_in_time(setup):
    gp, _, _ = setup
    sp = BSpline(7, 2.9)
    t_train = np.linspace(0, 2.9, gp.X.shape[0])
    P = fit_control_points(sp, t_train, gp.X, "rest")
    h = 1e-4
    t = np.array([0.4, 1.1, 2.0])
    kin = latent_kinematics(gp)
    for tk in t:
        x, xd, xdd = (sp.evaluate(P, [tk], r)[0] for r in (0, 1, 2))
        q, v, a = (np.asarray(o).ravel() for o in kin(x, xd, xdd))
        qm, qp = gp.mean(sp.evaluate(P, [tk - h])[0]), gp.mean(sp.evaluate(P, [tk + h])[0])
        assert np.allclose(q, gp.mean(x), atol=1e-12)
        assert np.allclose(v, (qp - qm) / (2 * h), rtol=1e-5, atol=1e-6)
        assert np.allclose(a, (qp - 2 * q + qm) / h**2, rtol=1e-3, atol=1e-3)


def test_grid_function_matches_numpy(setup):
    gp, _, _ = setup
    rng = np.random.default_rng(0)
    X = gp.X[::3] + 0.05 * rng.standard_normal(gp.X[::3].shape)
    s2, Q = gp_grid_function(gp, len(X))(X.T)
    assert np.allclose(np.asarray(s2).ravel(), gp.variance(X), rtol=1e-8, atol=1e-12)
    assert np.allclose(np.asarray(Q).T, gp.mean(X), atol=1e-10)


def test_torques_match_pinocchio_rnea(setup):
    gp, model, sym = setup
    rng = np.random.default_rng(1)
    x = gp.X[[3, 10, 20]]
    xd, xdd = rng.standard_normal(x.shape), rng.standard_normal(x.shape)
    m = numeric_latent_motion(gp, sym, x, xd, xdd)
    data = model.createData()
    for k in range(3):
        tau = pin.rnea(model, data, m["q"][k], m["v"][k], m["a"][k])
        assert np.allclose(m["tau"][k], tau, atol=1e-9)
        assert np.isclose(m["L"][k], tau @ tau)


def test_grid_motion_matches_per_node_autodiff(setup):
    gp, _, _ = setup
    rng = np.random.default_rng(2)
    K = 6
    X = gp.X[::5][:K].T + 0.05 * rng.standard_normal((3, K))
    Xd, Xdd = rng.standard_normal((3, K)), rng.standard_normal((3, K))
    closed = latent_motion_grid(gp, K)(X, Xd, Xdd)
    auto = latent_kinematics(gp).map(K)(X, Xd, Xdd)
    for c, a in zip(closed, auto):
        assert np.allclose(np.asarray(c), np.asarray(a), rtol=1e-10, atol=1e-12)


def test_compiled_node_derivatives_match_sx_and_finite_differences(setup):
    """The compiled per-node L, gradient and Hessian equal the SX ones to 1e-10 (relative),
    and the gradient matches central differences of L."""
    from latentoc.latent_motion import node_derivative_functions
    sym = setup[2]
    jit, ref = node_derivative_functions(sym, jit=True), node_derivative_functions(sym, jit=False)
    rng = np.random.default_rng(3)
    for _ in range(5):
        u = rng.standard_normal(3 * sym.nv)
        for a, b in zip(jit["hess"].call([u]), ref["hess"].call([u])):
            a, b = np.asarray(ca.DM(a)), np.asarray(ca.DM(b))
            assert np.allclose(a, b, rtol=1e-10, atol=1e-10 * max(1.0, np.abs(b).max()))
        L, g = (np.asarray(v).ravel() for v in jit["grad"].call([u]))
        h = 1e-6
        fd = [(float(jit["grad"](u + h * e)[0]) - float(jit["grad"](u - h * e)[0])) / (2 * h) for e in np.eye(u.size)]
        assert np.allclose(g, fd, rtol=1e-5, atol=1e-5 * np.abs(g).max())
