"""End to end on arm-raise-small through the public API: convergence, tube on a 1 kHz grid, physics of
the export, the joint-range baseline, errors; the arm-raise optimum at 5x."""

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

import latentoc
from latentoc import load_problem, solve
from latentoc.errors import ProblemError, SolveError
from latentoc.min_torque.training import problem_gpdm, training_frames
from latentoc.latent.spline import BSpline

pytestmark = pytest.mark.slow  # every test here solves


@pytest.fixture(scope="module")
def problem():
    return load_problem("arm-raise-small")


@pytest.fixture(scope="module")
def solution(problem):
    return solve(problem)  # tube "5x" from the declaration


def test_converges_and_beats_initial(solution):
    r = solution
    assert r.success and r.status == "Solve_Succeeded" and r.iterations > 0
    assert r.cost < r.cost_initial and np.isclose(r.gain_pct, 100 * (r.cost_initial - r.cost) / r.cost_initial)
    assert r.details["quadrature_error"] < 2e-3  # Gauss-Legendre vs the 1 ms trapezoid
    assert r.tube.spec == "5x" and np.isclose(r.tube.delta, 5 * r.tube.training)
    assert r.settings["control_points"] == 7 and r.settings["hessian"] == "exact"
    assert r.times.solve_s > 0 and r.environment.latentoc == latentoc.__version__
    assert r.violations["joint_limits_rad"] == 0.0


def test_convergence_history_of_every_round(solution, tmp_path):
    """result.json's convergence: Ipopt's log of each exchange round, one row per iteration (0 included),
    starting where the previous round ended and ending at the result's cost; read back from the folder."""
    r = solution
    rounds = r.details["exchange_rounds"]
    assert [(c["phase"], c["round"]) for c in r.convergence] == [("latent", k + 1) for k in range(len(rounds))]
    for c, rd in zip(r.convergence, rounds):
        h = c["history"]
        assert h["iter"] == [float(i) for i in range(rd["iterations"] + 1)]
        assert all(len(h[k]) == len(h["iter"]) for k in ("objective", "inf_pr", "inf_du", "mu", "alpha_pr", "alpha_du"))
    assert np.isclose(r.convergence[0]["history"]["objective"][0], r.cost_initial)
    assert np.isclose(r.convergence[-1]["history"]["objective"][-1], r.cost)
    assert r.convergence[-1]["history"]["inf_pr"][-1] < 1e-8
    r.save(tmp_path)
    assert latentoc.load_result(tmp_path).convergence == r.convergence


def test_enforced_limits_are_in_the_trajectory(solution):
    """The arm's joint limits (on in the problem) travel with the motion as the model's limits;
    velocity and torque limits are off there, so they are absent."""
    tr = solution.trajectory
    model = pin.Model()
    model.loadFromString(str(tr["model"]))
    assert np.array_equal(tr["q_min"], model.lowerPositionLimit) and np.array_equal(tr["q_max"], model.upperPositionLimit)
    assert not {"v_max", "tau_min", "tau_max"} & set(tr)


def test_tube_holds_on_1khz_grid(problem, solution):
    gp, _ = problem_gpdm(problem)
    tr = solution.trajectory
    assert np.allclose(np.diff(tr["t"]), 1e-3)
    s2 = gp.variance(tr["x"])
    assert np.allclose(s2, tr["sigma2"]) and np.allclose(solution.gpdm.variance(tr["x"]), s2)
    delta = solution.tube.delta
    assert s2.max() <= delta * 1.02  # the constraint grid is 24 nodes per knot interval
    assert np.isclose(solution.violations["tube"], max(0.0, s2.max() - delta))


def test_exported_physics(problem, solution):
    """q, v, a at 1 kHz equal the GP mean with CasADi's forward-mode derivatives (Eq. 26-28)
    along the exported latent spline, and tau numeric RNEA of those, to 1e-8 relative."""
    tr = solution.trajectory
    model = pin.Model()
    model.loadFromString(str(tr["model"]))
    data = model.createData()
    gp, _ = problem_gpdm(problem)
    x, xd, xdd = ca.SX.sym("x", 3), ca.SX.sym("xd", 3), ca.SX.sym("xdd", 3)
    q = gp.mean_function()(x)
    v = ca.jtimes(q, x, xd)
    kin = ca.Function("kin", [x, xd, xdd], [q, v, ca.jtimes(q, x, xdd) + ca.jtimes(v, x, xd)])
    spline = BSpline(solution.settings["control_points"], solution.settings["duration"])
    for k in range(0, len(tr["t"]), 97):
        z = (spline.evaluate(tr["P"], tr["t"][k:k + 1], r)[0] for r in range(3))
        ref = [np.asarray(o).ravel() for o in kin(*z)]
        ref.append(pin.rnea(model, data, *ref))
        for got, want in zip((tr["q"][k], tr["v"][k], tr["a"][k], tr["tau"][k]), ref):
            assert np.abs(got - want).max() <= 1e-8 * max(1.0, np.abs(want).max())
    dt = tr["t"][1] - tr["t"][0]
    v_fd = np.gradient(tr["q"], dt, axis=0)
    a_fd = np.gradient(tr["v"], dt, axis=0)
    inner = slice(5, -5)
    assert np.abs(v_fd[inner] - tr["v"][inner]).max() < 1e-3 * np.abs(tr["v"]).max()
    assert np.abs(a_fd[inner] - tr["a"][inner]).max() < 1e-2 * np.abs(tr["a"]).max()
    assert np.allclose(tr["v"][[0, -1]], 0.0, atol=1e-9)  # boundary "rest"
    assert np.allclose(tr["q"][[0, -1]], tr["q_initial"][[0, -1]], atol=1e-12)


def test_tube_at_initial_level(problem, solution):
    """delta just above the initial spline's max sigma^2 (the start is feasible): a cost no
    higher than the initial one and a gain no larger than with the wider 5x tube.

    (It does not return the training motion itself: the tube is one number for the whole
    path, and the initial spline reaches it only where it cuts a corner of the learned path.)
    """
    gp, _ = problem_gpdm(problem)
    tube_initial = solution.details["tube_initial"]
    assert tube_initial < solution.tube.delta
    s = solve(problem.replace(tube=1.001 * tube_initial), gpdm=gp)
    assert s.success and s.cost <= s.cost_initial + 1e-9
    assert s.gain_pct <= solution.gain_pct + 1e-6


@pytest.fixture(scope="module")
def arm_raise():
    problem = load_problem("arm-raise")
    gp, _ = problem_gpdm(problem)
    return problem, gp, solve(problem, gpdm=gp)  # tube "5x"


def test_arm_raise_5x_optimum(arm_raise):
    """The packaged arm-raise at 5x: the README's gain (33.08 %) and optimum, the same with numpy 2.0.2 /
    scipy 1.13.1 and 2.4.6 / 1.17.1 (the converged GPDM, docs/gpdm.md)."""
    r = arm_raise[2]
    assert r.success and r.tube.spec == "5x" and r.details["gpdm_converged"]
    assert r.details["gpdm_objective"] == pytest.approx(-3272.72640, abs=1e-4)
    assert abs(r.gain_pct - 33.08) <= 0.05
    assert abs(r.cost - 627.3331) <= 1e-3 and abs(r.cost_initial - 937.4728) <= 1e-3
    # a minimum, not a saddle: the optima form a ring about the latent path's axis (docs/arm-raise.md),
    # so the reduced Hessian's smallest eigenvalue is 0 to rounding (its largest ~ 6.6e3)
    assert abs(r.details["exchange_rounds"][-1]["reduced_hessian_min"]) <= 1e-6


def test_tube_just_above_initial_keeps_the_training_path(arm_raise):
    """arm-raise (its converged GPDM): delta just above tube_initial
    returns nearly the training motion's *path*: every optimised pose lies within 0.5 deg
    (joint-space norm) of the initial spline's path, which follows the training poses
    within 5 deg. The timing along the path is not bounded by the tube (Eq. 29), so the
    cost still drops by re-timing; see problems/arm-raise.toml."""
    problem, gp, first = arm_raise
    assert first.details["tube_initial"] < 2.0 * first.tube.training  # the 9-point spline fits the tube
    s = solve(problem.replace(tube=1.001 * first.details["tube_initial"]), gpdm=gp)
    assert s.success and s.violations["tube"] < 0.02 * s.tube.delta
    q, qi = s.trajectory["q"], s.trajectory["q_initial"]
    dist = np.sqrt(((q[::10, None, :] - qi[None, :, :]) ** 2).sum(-1)).min(axis=1)
    assert np.degrees(dist.max()) < 0.5
    _, Q_train = training_frames(problem)
    d_train = np.sqrt(((qi[::10, None, :] - Q_train[None, :, :]) ** 2).sum(-1)).min(axis=1)
    assert np.degrees(d_train.max()) < 5.0


@pytest.fixture(scope="module")
def joint_range(problem):
    return solve(problem, method="joint-range", joint_range_deg=10.0)


def test_joint_range_converges_within_range(joint_range):
    r, tr = joint_range, joint_range.trajectory
    assert r.success and r.cost < r.cost_initial
    assert r.method == "joint-range" and r.details["joint_range_deg"] == 10.0 and r.tube is None
    assert "tube" not in r.violations and r.gpdm is None
    dP = np.degrees(np.abs(tr["P"] - tr["P_initial"]))
    assert dP.max() <= 10.0 + 1e-4  # Ipopt relaxes bounds by ~1e-8 relative
    assert np.allclose(dP[[0, 1, -2, -1]], 0.0)  # boundary rows fixed
    assert r.details["quadrature_error"] < 2e-3


def test_joint_range_starts_from_the_training_motion(joint_range):
    from latentoc.robots.human_arm import arm_trial
    t, Q = arm_trial()
    tr = joint_range.trajectory
    qi = np.array([np.interp(t, tr["t"], tr["q_initial"][:, j]) for j in range(7)]).T
    assert np.degrees(np.abs(qi - Q).max()) < 3.0
    assert np.allclose(tr["q"][0], Q[0]) and np.allclose(tr["q"][-1], Q[-1])
    spline = BSpline(joint_range.settings["control_points"], joint_range.settings["duration"])
    assert np.allclose(tr["q"], spline.evaluate(tr["P"], tr["t"]), rtol=0, atol=1e-12)  # the spline is the path


def test_joint_range_with_lbfgs_reaches_the_same_optimum(problem, joint_range):
    s = solve(problem.replace(hessian="lbfgs"), method="joint-range", joint_range_deg=10.0)
    assert s.success and s.settings["hessian"] == "lbfgs"
    assert abs(s.cost - joint_range.cost) <= 1e-6 * joint_range.cost


@pytest.mark.parametrize("overrides, kwargs, match", [
    (dict(tube=1e-12), {}, "infeasible.*smallest feasible delta"),
    (dict(latent_dim=7), {}, "1 <= d < D = 7"),
    ({}, dict(method="magic"), "unknown method"),
    ({}, dict(method="joint-range", joint_range_deg=-5), "positive number of degrees"),
])
def test_bad_input_raises_clear_error(problem, overrides, kwargs, match):
    with pytest.raises(SolveError, match=match):
        solve(problem.replace(**overrides), **kwargs)


@pytest.mark.parametrize("overrides, match", [
    (dict(tube=-1.0), "must be a positive number or a relative tube"),
    (dict(tube="abc"), "must be a positive number or a relative tube"),
    (dict(control_points=3), "fewer than spline_degree"),
    (dict(control_points=4), "at least 5"),
    (dict(hessian="newton"), "hessian"),
])
def test_bad_settings_are_refused_before_solving(problem, overrides, match):
    with pytest.raises(ProblemError, match=match):
        problem.replace(**overrides)


def test_warm_start_only_from_a_smaller_tube(problem, solution):
    """A result solved at a larger tube is not a warm start (its optimum may leave this tube):
    the solve starts from the training fit and ends at the cold optimum."""
    cold = solve(problem.replace(tube="20x"))
    warm = solve(problem.replace(tube="20x"), warm_start=solution)
    back = solve(problem, warm_start=cold)
    assert warm.details["warm_start"] and not back.details["warm_start"]
    assert abs(warm.cost - cold.cost) <= 1e-6 * cold.cost and back.cost == solution.cost


@pytest.mark.slow  # a solve with every library "compiled" (slowly) on an empty cache
def test_compile_time_is_reported_where_it_was_spent(tmp_path, monkeypatch):
    """On an empty cache the solve's compile time is the time spent building and compiling the blocks'
    derivatives, taken out of build and solve, and the parts add up to the call's wall (issue 36: the
    Panda's first solve printed compile 0.00 s after compiling three libraries). Each compilation is
    a 0.3 s stand-in that gives no library, so the Functions then run uncompiled."""
    import time

    from latentoc.nlp import jit

    def slow_build(self, label, source, flags, lib):
        time.sleep(0.3)
        self.bar.update(1)

    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.setenv("LATENTOC_JIT", "1")
    monkeypatch.setattr(jit.Compiler, "_build", slow_build)
    r = solve(load_problem("arm-raise-small"))
    t = r.times
    assert r.success and t.compile_s >= 0.3
    parts = t.gpdm_s + t.compile_s + t.build_s + t.solve_s + t.check_s
    assert parts == pytest.approx(t.total_s, abs=0.05 * t.total_s) and t.build_s < t.compile_s
