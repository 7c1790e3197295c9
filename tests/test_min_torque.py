"""The minimum-torque NLP (latentoc.min_torque.nlp) against the same NLP composed as one CasADi
SX expression: the GP mean and CasADi's forward mode for yd, ydd (Eq. 26-28), SymbolicModel.rnea,
sigma^2 from the GPDM's own variance Function (Eq. 19), differentiated by CasADi."""

from dataclasses import replace

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.min_torque.export import sampled_motion
from latentoc.min_torque.nlp import ipopt_options, joint_range_nlp, latent_nlp
from latentoc.min_torque.settings import MinTorqueSettings
from latentoc.latent import GPLayer, IdentityLayer
from latentoc.min_torque.training import problem_gpdm, training_frames
from latentoc.motions import TRAINING_MOTIONS
from latentoc.problem.toml_files import load_problem
from latentoc.robots import load_robot
from latentoc.latent.spline_path import SplinePath, constraint_times, gauss_legendre_nodes, trapezoid_cost

SETTINGS = MinTorqueSettings(duration=2.9, control_points=7, quadrature_points=4, constraint_points=6)
RTOL = 1e-8  # relative to the largest entry of each compared block


@pytest.fixture(scope="module")
def arm():
    p = load_problem("arm-raise-small")
    gp, _ = problem_gpdm(p)
    t, _ = training_frames(p)
    robot = load_robot(p.robot)
    return gp, robot, SymbolicModel(robot), t


def latent_kinematics(gp) -> ca.Function:
    """(x, xd, xdd) -> (q, v, a): q = mu(x), v = J xd, a = J xdd + (dJ/dt) xd by forward mode."""
    d = gp.latent_dim
    x, xd, xdd = ca.SX.sym("x", d), ca.SX.sym("xd", d), ca.SX.sym("xdd", d)
    q = gp.mean_function()(x)
    v = ca.jtimes(q, x, xd)
    a = ca.jtimes(q, x, xdd) + ca.jtimes(v, x, xd)
    return ca.Function("kin", [x, xd, xdd], [q, v, a])


def joint_kinematics(n: int) -> ca.Function:
    x, xd, xdd = ca.SX.sym("x", n), ca.SX.sym("xd", n), ca.SX.sym("xdd", n)
    return ca.Function("kin", [x, xd, xdd], [x, xd, xdd])


def composed(path: SplinePath, sym: SymbolicModel, kin: ca.Function, variance: ca.Function | None,
             tmax: np.ndarray | None, tube: float = 1.0) -> ca.Function:
    """(w, sigma, lam) -> (f, grad f, g, dg/dw, triu d2(sigma f + lam . g)/dw2), all by CasADi."""
    spline, m = path.spline, path.spline.n_control
    w = ca.SX.sym("w", path.n_w)
    free = list(path.free)
    rows = [w[free.index(r) * path.dim:(free.index(r) + 1) * path.dim].T if r in free else ca.DM(path.P_init[r]).T
            for r in range(m)]
    P = ca.vertcat(*rows)
    tq, wq = gauss_legendre_nodes(spline, SETTINGS.quadrature_points)
    tg = constraint_times(spline, SETTINGS.constraint_points)
    Xq = [ca.mtimes(ca.DM(spline.basis(tq, r)), P) for r in range(3)]
    Xg = [ca.mtimes(ca.DM(spline.basis(tg, r)), P) for r in range(3)]
    f, taus = 0, []
    for k in range(len(tq)):
        tau = sym.rnea(*kin(*(X[k, :].T for X in Xq)))
        f += wq[k] * ca.sumsqr(tau)
        taus.append(tau)
    g = []
    if variance is not None:
        g += [variance(Xg[0][j, :].T) / tube for j in range(len(tg))]
    g += [kin(*(X[j, :].T for X in Xg))[0] for j in range(len(tg))]
    if tmax is not None:
        g += taus
    g = ca.vertcat(*g)
    sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", g.shape[0])
    H = ca.triu(ca.hessian(sigma * f + ca.dot(lam, g), w)[0])
    return ca.Function("ref", [w, sigma, lam], [f, ca.gradient(f, w), g, ca.jacobian(g, w), H])


def _close(got, want, what):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape, what
    err, scale = np.abs(got - want).max(), np.abs(want).max()
    assert err <= RTOL * scale, f"{what}: error {err:.3g}, scale {scale:.3g}"


def check_against_composed(nlp, ref: ca.Function, seed: int) -> None:
    rng = np.random.default_rng(seed)
    w = nlp.w0 + 0.05 * rng.standard_normal(nlp.w0.size)
    sigma, lam = 0.7, rng.standard_normal(nlp.nlp.m)
    f, grad, g, J, H = (np.asarray(ca.DM(v)) for v in ref(w, sigma, lam))
    N = nlp.nlp
    _close(N.objective(w), f.item(), "objective")
    _close(N.gradient(w), grad.ravel(), "gradient")
    g_new = N.constraints(w)
    J_new = ca.DM(N.jac_sparsity, N.jacobian(w)).full()
    for name, rows in nlp.rows.items():  # each family against its own scale (sigma^2 ~ 1e-3, tau ~ 10)
        _close(g_new[rows], g.ravel()[rows], f"{name} rows")
        _close(J_new[rows], J[rows], f"{name} Jacobian")
    _close(ca.DM(N.hess_sparsity, N.hessian(w, sigma, lam)).full(), H, "Hessian of the Lagrangian")


@pytest.mark.slow  # the composed SX Hessian: seconds
@pytest.mark.parametrize("torque_limits", [(), (50.0,)])
def test_latent_nlp_equals_composed_casadi(arm, torque_limits):
    gp, _, sym, t = arm
    settings = replace(SETTINGS, torque_limits=torque_limits)
    nlp = latent_nlp(gp, sym, settings, 0.05, t_train=t)
    Kq, Kg = len(nlp.quad_t), len(nlp.grid_t)
    expected = {"tube": Kg, "joint_limits": 7 * Kg} | ({"torque": 7 * Kq} if torque_limits else {})
    assert {k: s.stop - s.start for k, s in nlp.rows.items()} == expected
    assert np.all(nlp.ubg[nlp.rows["tube"]] == 1.0) and np.all(np.isinf(nlp.lbx))  # sigma^2 / delta <= 1
    if torque_limits:
        assert np.all(nlp.ubg[nlp.rows["torque"]] == 50.0) and np.all(nlp.lbg[nlp.rows["torque"]] == -50.0)
    tmax = np.full(7, 50.0) if torque_limits else None
    ref = composed(nlp.path, sym, latent_kinematics(gp), gp.variance_function(), tmax, tube=0.05)
    check_against_composed(nlp, ref, seed=1)


@pytest.mark.slow
@pytest.mark.parametrize("torque_limits", [(), tuple(range(30, 37))])
def test_joint_range_nlp_equals_composed_casadi(arm, torque_limits):
    _, robot, sym, _ = arm
    t, Q = TRAINING_MOTIONS["human-arm-trial"]()
    settings = replace(SETTINGS, torque_limits=torque_limits)
    nlp = joint_range_nlp(sym, settings, t, Q, 10.0)
    assert "tube" not in nlp.rows and isinstance(nlp.layer, IdentityLayer)
    assert np.allclose(nlp.ubx - nlp.w0, np.radians(10.0)) and np.allclose(nlp.w0 - nlp.lbx, np.radians(10.0))
    assert np.allclose(nlp.lbg[nlp.rows["joint_limits"]], np.tile(robot.lowerPositionLimit, len(nlp.grid_t)))
    tmax = np.asarray(torque_limits, float) if torque_limits else None
    ref = composed(nlp.path, sym, joint_kinematics(7), None, tmax)
    check_against_composed(nlp, ref, seed=2)


def test_rows_are_sigma2_and_mean_at_the_grid(arm):
    gp, _, sym, t = arm
    nlp = latent_nlp(gp, sym, SETTINGS, 0.05, t_train=t)
    g = nlp.nlp.constraints(nlp.w0)
    x = nlp.path.spline.evaluate(nlp.path.P_init, nlp.grid_t)
    assert np.allclose(g[nlp.rows["tube"]], gp.variance(x) / 0.05, rtol=1e-8, atol=0)  # relative to delta
    assert np.allclose(g[nlp.rows["joint_limits"]].reshape(-1, 7), gp.mean(x), rtol=0, atol=1e-10)


def test_gauss_legendre_cost_matches_fine_trapezoid(arm):
    """J at the fit (8 nodes per knot interval) against the 0.1 ms trapezoid of |tau|^2."""
    gp, robot, sym, t = arm
    settings = MinTorqueSettings(duration=2.9, control_points=7, quadrature_points=8)
    nlp = latent_nlp(gp, sym, settings, 0.05, t_train=t)
    tf = np.linspace(0, 2.9, 29001)
    L = sampled_motion(nlp.layer, robot, nlp.path.spline, nlp.path.P_init, tf)["L"]
    ref = trapezoid_cost(L, tf[1] - tf[0])
    assert abs(nlp.cost(nlp.w0) - ref) / ref < 1e-3


def test_sampled_motion_equals_casadi_kinematics_and_rnea(arm):
    gp, robot, _, t = arm
    path = SplinePath.fit(SETTINGS.spline(), t, gp.latent_trajectories()[0], "rest")
    ts = np.linspace(0.0, 2.9, 13)
    m = sampled_motion(GPLayer(gp), robot, path.spline, path.P_init, ts)
    kin = latent_kinematics(gp)
    data = robot.createData()
    for k, tk in enumerate(ts):
        z = (path.spline.evaluate(path.P_init, [tk], r)[0] for r in range(3))
        q, v, a = (np.asarray(o).ravel() for o in kin(*z))
        tau = pin.rnea(robot, data, q, v, a)
        for got, want in ((m["q"][k], q), (m["v"][k], v), (m["a"][k], a), (m["tau"][k], tau)):
            assert np.abs(got - want).max() <= 1e-8 * max(1.0, np.abs(want).max())
        assert np.isclose(m["L"][k], tau @ tau, rtol=1e-12)


def test_ipopt_options():
    for method, scaled in (("latent", True), ("joint-range", False)):
        nlp = type("N", (), {"method": method})()
        o = ipopt_options(nlp, tol=1e-8, max_iter=300)
        assert o["mu_strategy"] == "monotone" and o["acceptable_tol"] == 1e-6 and o["acceptable_iter"] == 10
        assert o["tol"] == 1e-8 and o["max_iter"] == 300 and o["print_level"] == 0
        assert ("nlp_scaling_constr_target_gradient" in o) == scaled
    assert ipopt_options(nlp, tol=1e-5, max_iter=3)["acceptable_tol"] == pytest.approx(1e-3)


def test_model_and_motion_sizes_must_agree(arm):
    gp, _, _, t = arm
    sym6 = SymbolicModel(pin.buildSampleModelManipulator())  # 6 joints, the GPDM gives 7
    with pytest.raises(ValueError, match="nq = nv = D"):
        latent_nlp(gp, sym6, SETTINGS, 0.05, t_train=t)


def test_carried_multipliers_follow_their_rows_into_the_grown_nlp(arm):
    """The exchange's warm start: each old row's multiplier lands on the new row that evaluates to
    the same value at the same point (sigma^2, the GP mean, tau at the same time), new rows at zero."""
    from latentoc.min_torque.exchange import carried_multipliers
    from latentoc.min_torque.nlp import Samples

    gp, _, sym, t = arm
    settings = replace(SETTINGS, torque_limits=(50.0,))
    old = latent_nlp(gp, sym, settings, 0.05, t_train=t)
    extra = Samples(grid=np.array([0.3333, 1.7777]), torque=np.array([0.5555]))
    new = latent_nlp(gp, sym, settings, 0.05, path=old.path, extra=extra)
    lam = np.random.default_rng(3).normal(size=old.nlp.m)
    carried = carried_multipliers(old, new, lam)
    g_old, g_new = old.nlp.constraints(old.w0), new.nlp.constraints(new.w0)
    assert new.nlp.m == old.nlp.m + 2 * 8 + 7  # a tube and 7 joint rows per grid time, 7 torque rows
    hit = carried != 0.0
    assert hit.sum() == old.nlp.m
    order = np.argsort(lam)  # the old rows in the order of their (distinct) multipliers
    new_rows = np.flatnonzero(hit)[np.argsort(carried[hit])]
    np.testing.assert_allclose(g_new[new_rows], g_old[order], rtol=1e-12, atol=1e-12)


def test_curvature_is_the_reduced_hessians_smallest_eigenvalue(arm):
    """The second-order check against central differences of the NLP's gradient: with no active
    row the objective's Hessian, with variables at their bounds its block of the free ones."""
    from latentoc.nlp.curvature import curvature

    gp, _, sym, t = arm
    nlp = latent_nlp(gp, sym, SETTINGS, 1e3, t_train=t)  # a tube that does not bind at the start
    w, n, m = nlp.w0, nlp.w0.size, nlp.nlp.m
    h = 1e-5
    H = np.array([(nlp.nlp.gradient(w + h * e) - nlp.nlp.gradient(w - h * e)) / (2 * h) for e in np.eye(n)])
    H = (H + H.T) / 2
    c = curvature(nlp.nlp, w, np.zeros(m), nlp.lbg, nlp.ubg, np.zeros(n), nlp.lbx, nlp.ubx)
    e = np.linalg.eigvalsh(H)
    assert c.active == 0 and abs(c.smallest - e[0]) <= 1e-6 * np.abs(e).max()
    np.testing.assert_allclose(H @ c.direction, c.smallest * c.direction, atol=1e-5 * np.abs(e).max())
    held = np.arange(n) % 3 == 0  # these variables at their (lower) bounds
    lbx = np.where(held, w, -np.inf)
    c = curvature(nlp.nlp, w, np.zeros(m), nlp.lbg, nlp.ubg, np.zeros(n), lbx, nlp.ubx)
    free = ~held
    assert c.active == held.sum() and np.all(c.direction[held] == pytest.approx(0.0, abs=1e-12))
    assert abs(c.smallest - np.linalg.eigvalsh(H[np.ix_(free, free)])[0]) <= 1e-6 * np.abs(e).max()
