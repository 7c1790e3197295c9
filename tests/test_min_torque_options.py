"""The minimum-torque kind's options (latentoc.min_torque.objectives, .limits, .goal) against independent numbers:
each objective's block against numpy and Pinocchio's numeric RNEA, the goal rows against numeric forward
kinematics, the free end path's tie, the URDF limits, and the assembled rows and their exact Jacobian and
Hessian of the Lagrangian (latent NLP on the UR5) against central differences."""
import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.min_torque.export import sampled_motion
from latentoc.min_torque.goal import EndGoal, FreeEndPath, goal_block, goal_error
from latentoc.min_torque.limits import Limits, torque_limit_vector
from latentoc.min_torque.nlp import joint_range_nlp, latent_nlp
from latentoc.min_torque.objectives import Objective, velocity_block
from latentoc.min_torque.settings import MinTorqueSettings
from latentoc.latent import GPLayer
from latentoc.robots import load_robot
from latentoc.latent.spline import BSpline
from latentoc.latent.spline_path import SplinePath

RNG = np.random.default_rng(7)


@pytest.fixture(scope="module")
def ur5():
    model = load_robot("ur5")
    return model, SymbolicModel(model)


def reach(n: int = 31, T: float = 1.5) -> tuple[np.ndarray, np.ndarray]:
    """A UR5 reach with a detour (minimum-jerk blend plus a bump), n samples over T s."""
    t = np.linspace(0.0, T, n)
    u = t / T
    s, b = 10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5, 64 * u ** 3 * (1 - u) ** 3
    q0, q1 = np.array([0.0, -1.8, 1.6, -1.4, -1.57, 0.0]), np.array([1.2, -1.0, 1.0, -1.6, -1.2, 0.8])
    return t, q0 + np.outer(s, q1 - q0) + np.outer(b, [0.3, -0.4, 0.5, 0.3, 0.3, -0.4])


@pytest.mark.parametrize("name", ["torque", "energy", "acceleration"])
def test_each_objective_block_is_its_integrand_on_numeric_rnea(ur5, name):
    model, sym = ur5
    objective = Objective(name, epsilon=0.05)
    rows = objective.block(sym, 3, with_torques=True).rows_sx
    data = model.createData()
    for _ in range(4):
        q, v, a = pin.randomConfiguration(model), RNG.normal(size=6), RNG.normal(size=6)
        F = np.asarray(rows(q, v, a, np.zeros(0))).ravel()
        tau = pin.rnea(model, data, q, v, a)
        expected = {"torque": tau @ tau, "energy": np.sqrt((tau @ v) ** 2 + 0.05 ** 2) - 0.05, "acceleration": a @ a}
        assert F[0] == pytest.approx(expected[name], rel=1e-12, abs=1e-12)
        assert np.allclose(F[1:], tau, rtol=1e-12, atol=1e-10)
        assert objective.integrand(tau[None], v[None], a[None])[0] == pytest.approx(F[0], rel=1e-12, abs=1e-12)
    if name == "energy":  # within eps of |tau . qdot|
        p = np.linspace(-3, 3, 61)[:, None]
        L = Objective("energy", 0.05).integrand(p, np.ones_like(p), p)
        assert np.all(np.abs(L - np.abs(p[:, 0])) <= 0.05 + 1e-15)
    assert objective.block(sym, 3).n_out == 1
    assert Objective("torque").block(sym, 3).name == "min_torque_L"  # the compiled libraries of before


def test_bad_objectives_are_refused():
    with pytest.raises(ValueError, match="unknown objective 'jerk'"):
        Objective("jerk")
    with pytest.raises(ValueError, match="epsilon must be positive"):
        Objective("energy", 0.0)


def test_velocity_and_goal_blocks_against_numeric_kinematics(ur5):
    model, sym = ur5
    q, v = pin.randomConfiguration(model), RNG.normal(size=6)
    assert np.array_equal(np.asarray(velocity_block(6, 2).rows_sx(q, v, v, np.zeros(0))).ravel(), v)
    target = np.array([0.3, -0.2, 0.5])
    F = np.asarray(goal_block(sym, "tool0", 3).rows_sx(q, v, v, target)).ravel()
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    e = data.oMf[model.getFrameId("tool0")].translation - target
    assert np.allclose(F, np.r_[e, e @ e], rtol=1e-12, atol=1e-12)
    assert goal_error(model, EndGoal("tool0", tuple(target)), q) == pytest.approx(np.linalg.norm(e), rel=1e-12)


def test_the_urdf_limits_and_their_switches(ur5):
    model, _ = ur5
    lim = Limits.of(model, joint_limits=True, velocity_limits=True, torque_limits="urdf")
    assert np.array_equal(lim.q_hi, model.upperPositionLimit) and np.array_equal(lim.v_max, model.velocityLimit)
    assert np.array_equal(lim.tau_max, [150, 150, 150, 28, 28, 28])
    assert Limits.of(model, joint_limits=False) == Limits()
    pendulum = load_robot("double-pendulum")  # its URDF gives no limits (0, 0): unlimited, not q = 0
    free = Limits.of(pendulum, True, True, "urdf")
    assert np.all(np.isinf(free.q_lo)) and np.all(np.isinf(free.v_max)) and np.all(np.isinf(free.tau_max))
    assert np.array_equal(torque_limit_vector([5.0], model), np.full(6, 5.0)) and torque_limit_vector([], model) is None
    with pytest.raises(ValueError, match='a list of numbers or "urdf"'):
        torque_limit_vector("effort", model)
    motion = {"q": np.zeros((3, 6)), "v": np.full((3, 6), 3.2), "tau": np.full((3, 6), 30.0)}
    assert lim.violations(motion) == pytest.approx({"joint_limits_rad": 0.0, "velocity_limits_rad_s": 0.05,
                                                    "torque_limits_nm": 2.0})


@pytest.mark.parametrize("boundary", ["rest", "pose"])
def test_a_free_end_path_ties_the_end_rows(boundary):
    spline = BSpline(8, 2.0)
    t = np.linspace(0, 2, 20)
    path = FreeEndPath.release_end(SplinePath.fit(spline, t, np.c_[np.sin(t), t ** 2], boundary), boundary)
    w = RNG.normal(size=path.n_w)
    P = path.control_points(w)
    assert np.array_equal(path.decision_vector(P), w)
    assert np.array_equal(P[0], path.P_init[0])  # the start stays the demonstration's
    if boundary == "rest":
        assert np.array_equal(P[-2], P[-1]) and np.allclose(spline.evaluate(P, np.array([2.0]), 1), 0)
        assert np.array_equal(path.index[-2], path.index[-1])
        assert np.array_equal(P[1], path.P_init[1])
    assert not np.allclose(P[-1], path.P_init[-1])


def _dense(sparsity: ca.Sparsity, nonzeros: np.ndarray) -> np.ndarray:
    return np.asarray(ca.DM(sparsity, nonzeros).full())


def _central_jacobian(f, w: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = [(f(w + h * e) - f(w - h * e)) / (2 * h) for e in np.eye(len(w))]
    return np.array(cols).T


@pytest.fixture(scope="module")
def goal_nlp(ur5):
    model, sym = ur5
    t, Q = reach()
    gp = learn_gpdm(Q, GPDMSettings(latent_dim=2))
    target = (0.2, 0.4, 0.5)
    settings = MinTorqueSettings(duration=1.5, control_points=7, quadrature_points=3, constraint_points=4,
                                 velocity_limits=True, torque_limits="urdf", objective=Objective("energy", 0.1),
                                 goal=EndGoal("tool0", target, tolerance=0.0))
    return gp, latent_nlp(gp, sym, settings, 10 * gp.tube_size(), t_train=t), settings


def test_the_latent_nlp_rows_of_velocity_limits_and_goal(ur5, goal_nlp):
    model, _ = ur5
    gp, nlp, settings = goal_nlp
    w = nlp.w0 + 0.05 * RNG.normal(size=nlp.w0.size)
    g = nlp.nlp.constraints(w)
    P = nlp.control_points(w)
    assert isinstance(nlp.path, FreeEndPath) and nlp.grid_t[-1] == 1.5  # the free end is on the grid
    layer = GPLayer(gp)
    m = sampled_motion(layer, model, nlp.path.spline, P, nlp.grid_t)
    assert np.allclose(g[nlp.rows["velocity_limits"]], m["v"].ravel(), rtol=1e-10, atol=1e-12)
    q_end = sampled_motion(layer, model, nlp.path.spline, P, np.array([1.5]))["q"][0]
    data = model.createData()
    pin.framesForwardKinematics(model, data, q_end)
    assert np.allclose(g[nlp.rows["goal"]], data.oMf[model.getFrameId("tool0")].translation - [0.2, 0.4, 0.5],
                       rtol=1e-10, atol=1e-12)
    mq = sampled_motion(layer, model, nlp.path.spline, P, nlp.quad_t, settings.objective)
    assert nlp.cost(w) == pytest.approx(nlp.quad_w @ mq["L"], rel=1e-10)
    assert np.allclose(nlp.ubg[nlp.rows["velocity_limits"]], np.tile(model.velocityLimit, len(nlp.grid_t)))
    assert np.array_equal(nlp.lbg[nlp.rows["goal"]], np.zeros(3)) and np.array_equal(nlp.ubg[nlp.rows["goal"]],
                                                                                    np.zeros(3))


def test_the_exact_derivatives_of_the_new_rows(goal_nlp):
    _, nlp, _ = goal_nlp
    w = nlp.w0 + 0.05 * RNG.normal(size=nlp.w0.size)
    rows = np.r_[np.arange(nlp.lbg.size)[nlp.rows["velocity_limits"]], np.arange(nlp.lbg.size)[nlp.rows["goal"]]]
    J = _dense(nlp.nlp.jac_sparsity, nlp.nlp.jacobian(w))[rows]
    Jfd = _central_jacobian(lambda x: nlp.nlp.constraints(x)[rows], w)
    assert np.allclose(J, Jfd, rtol=1e-5, atol=1e-6 * np.abs(Jfd).max())
    assert np.allclose(nlp.nlp.gradient(w), _central_jacobian(lambda x: np.array([nlp.cost(x)]), w)[0],
                       rtol=1e-5, atol=1e-6 * np.abs(nlp.nlp.gradient(w)).max())
    lam = np.zeros(nlp.lbg.size)
    lam[rows] = RNG.normal(size=rows.size)
    H = _dense(nlp.nlp.hess_sparsity, nlp.nlp.hessian(w, 1.0, lam))  # the upper triangle
    H = H + np.triu(H, 1).T

    def lagrangian_gradient(x):
        return nlp.nlp.gradient(x) + _dense(nlp.nlp.jac_sparsity, nlp.nlp.jacobian(x)).T @ lam

    Hfd = _central_jacobian(lagrangian_gradient, w, 1e-5)
    assert np.allclose(H, 0.5 * (Hfd + Hfd.T), rtol=1e-4, atol=1e-5 * np.abs(Hfd).max())


def test_the_joint_range_nlp_frees_the_end_too(ur5):
    _, sym = ur5
    t, Q = reach()
    settings = MinTorqueSettings(duration=1.5, control_points=7, quadrature_points=3, constraint_points=4,
                                 goal=EndGoal("tool0", (0.2, 0.4, 0.5), tolerance=0.02))
    nlp = joint_range_nlp(sym, settings, t, Q, 30.0)
    assert isinstance(nlp.path, FreeEndPath) and nlp.rows["goal"].stop - nlp.rows["goal"].start == 1
    assert nlp.ubg[nlp.rows["goal"]][0] == 1.0  # |e|^2 / tolerance^2 <= 1
    assert nlp.w0.size == 4 * 6  # m = 7, "rest": p3, p4, p5 free and p7 (p6 tied to it)
