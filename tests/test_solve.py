"""End to end on arm-raise-small: convergence, tube on a 1 kHz grid, physics of the export, errors."""

import numpy as np
import pinocchio as pin
import pytest

from latentoc.problem import load_problem, training_motion
from latentoc.solve import SOLVERS, Solution, SolveError, problem_gpdm, solve


@pytest.fixture(scope="module")
def problem():
    return load_problem("arm-raise-small")


@pytest.fixture(scope="module")
def solution(problem):
    return solve(problem)  # tube "5x" from the declaration


def test_converges_and_beats_initial(solution):
    r = solution.result
    assert r["success"] and r["status"] == "Solve_Succeeded"
    assert r["cost"] < r["cost_initial"] and r["performance_gain_pct"] > 5
    assert r["quadrature_error"] < 2e-3  # Gauss-Legendre vs the 1 ms trapezoid
    assert r["tube_spec"] == "5x" and np.isclose(r["tube"], 5 * r["tube_training"])
    for key in ("iterations", "solve_time_s", "build_time_s", "gpdm_time_s", "latentoc_version", "seed",
                "tube_relative", "control_points", "latent_dim", "hessian"):
        assert key in r


def test_tube_holds_on_1khz_grid(problem, solution):
    gp, _ = problem_gpdm(problem)
    tr = solution.trajectory
    assert np.allclose(np.diff(tr["t"]), 1e-3)
    s2 = gp.variance(tr["x"])
    assert np.allclose(s2, tr["sigma2"])
    delta = solution.result["tube"]
    assert s2.max() <= delta * 1.02  # the constraint grid is 24 nodes per knot interval
    assert np.isclose(solution.result["max_tube_violation"], max(0.0, s2.max() - delta))


def test_exported_physics(solution):
    tr = solution.trajectory
    model = pin.Model()
    model.loadFromString(str(tr["model"]))
    data = model.createData()
    for k in range(0, len(tr["t"]), 97):
        tau = pin.rnea(model, data, tr["q"][k], tr["v"][k], tr["a"][k])
        assert np.allclose(tau, tr["tau"][k], atol=1e-8)
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
    tube_initial = solution.result["tube_initial"]
    assert tube_initial < solution.result["tube"]
    s = solve(problem, tube=1.001 * tube_initial, gpdm=gp)
    assert s.success and s.result["cost"] <= s.result["cost_initial"] + 1e-9
    assert s.result["performance_gain_pct"] <= solution.result["performance_gain_pct"] + 1e-6


def test_tube_just_above_initial_keeps_the_training_path():
    """arm-raise (its GPDM with the noise floor beta3_max): delta just above tube_initial
    returns nearly the training motion's *path*: every optimised pose lies within 0.5 deg
    (joint-space norm) of the initial spline's path, which follows the training poses
    within 5 deg. The timing along the path is not bounded by the tube (Eq. 29), so the
    cost still drops by re-timing; see problems/arm-raise.toml."""
    problem = load_problem("arm-raise")
    gp, _ = problem_gpdm(problem)
    first = solve(problem, gpdm=gp)
    r0 = first.result
    assert r0["tube_initial"] < 2.0 * r0["tube_training"]  # the 9-point spline fits the tube
    s = solve(problem, tube=1.001 * r0["tube_initial"], gpdm=gp)
    assert s.success and s.result["max_tube_violation_rel"] < 0.02
    q, qi = s.trajectory["q"], s.trajectory["q_initial"]
    dist = np.sqrt(((q[::10, None, :] - qi[None, :, :]) ** 2).sum(-1)).min(axis=1)
    assert np.degrees(dist.max()) < 0.5
    _, Q_train = training_motion(problem)
    d_train = np.sqrt(((qi[::10, None, :] - Q_train[None, :, :]) ** 2).sum(-1)).min(axis=1)
    assert np.degrees(d_train.max()) < 5.0


@pytest.mark.parametrize("kwargs, match", [
    (dict(tube=-1.0), "must be positive"),
    (dict(tube="abc"), "neither a number"),
    (dict(tube=1e-12), "infeasible.*smallest feasible delta"),
    (dict(latent_dim=7), "1 <= d < D = 7"),
    (dict(control_points=3), "fewer than spline degree"),
    (dict(control_points=4), "at least 5"),
    (dict(hessian="newton"), "hessian"),
    (dict(method="magic"), "unknown method"),
    (dict(method="joint-range", joint_range_deg=-5), "positive number of degrees"),
])
def test_bad_input_raises_clear_error(problem, kwargs, match):
    with pytest.raises(SolveError, match=match):
        solve(problem, **kwargs)


def test_registry_contract(problem):
    assert "latent-min-torque" in SOLVERS
    calls = {}

    def fake(p, **overrides):
        calls.update(overrides)
        return Solution(result={"problem": p.name, "success": True})

    SOLVERS["test-kind"] = fake
    try:
        p = load_problem("arm-raise-small")
        p.kind = "test-kind"
        assert solve(p, tube="3x").result["problem"] == "arm-raise-small"
        assert calls["tube"] == "3x" and "verbose" in calls and "gpdm" in calls
    finally:
        del SOLVERS["test-kind"]
    p.kind = "nonexistent"
    with pytest.raises(SolveError, match="no solver"):
        solve(p)
