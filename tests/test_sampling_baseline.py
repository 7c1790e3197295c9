"""The sampling-based baseline (latentoc.baselines.sampling): boundary poses, joint limits, and
its cost against an independent numeric-Pinocchio recomputation; the missing-extra error."""
from __future__ import annotations

import builtins
import json
import subprocess
import sys

import numpy as np
import pinocchio as pin
import pytest

from latentoc.baselines import sampling
from latentoc.min_torque.training import training_frames
from latentoc.problem.toml_files import load_problem
from latentoc.robots import load_robot

try:
    import ompl  # noqa: F401
    HAVE_OMPL = True
except ImportError:
    HAVE_OMPL = False
needs_ompl = pytest.mark.skipif(not HAVE_OMPL, reason="ompl not installed (pip install latentoc[sampling])")


def _trapezoid(L: np.ndarray, dt: float) -> float:
    return float(dt * (L.sum() - 0.5 * (L[0] + L[-1])))


@pytest.fixture(scope="module")
def problem():
    return load_problem("arm-raise")


@pytest.fixture(scope="module")
def task(problem):
    return sampling.ArmTask.from_problem(problem)


@pytest.fixture(scope="module")
def result(problem):
    """A small plan: 150 RRT* iterations (a few seconds)."""
    return sampling.plan(problem, iterations=[150])[0]


def test_missing_ompl_names_the_extra(monkeypatch):
    real_import = builtins.__import__

    def no_ompl(name, *args, **kwargs):
        if name == "ompl" or name.startswith("ompl."):
            raise ImportError("No module named 'ompl'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_ompl)
    with pytest.raises(sampling.OmplUnavailable, match=r"latentoc\[sampling\]"):
        sampling.require_ompl()
    from latentoc.benchmarks import sampling_bench
    with pytest.raises(sampling.OmplUnavailable, match=r"latentoc\[sampling\]"):
        sampling_bench.main(["--budgets", "1", "--no-solves"])
    from latentoc.errors import LatentocError
    assert issubclass(sampling.OmplUnavailable, LatentocError)  # the CLI shows it as an error, not a traceback


def test_task_boundary_from_training_motion(task, problem):
    _, Q = training_frames(problem)
    np.testing.assert_array_equal(task.q_start, Q[0])
    np.testing.assert_array_equal(task.q_goal, Q[-1])
    assert task.duration == pytest.approx(2.9)
    assert task.tau_max is None  # arm-raise has no torque limits
    model = load_robot("human-arm")
    np.testing.assert_array_equal(task.q_lower, model.lowerPositionLimit)
    np.testing.assert_array_equal(task.q_upper, model.upperPositionLimit)


def test_edge_cost_against_fine_trapezoid(task):
    edges = sampling.HermiteEdges(task)
    rng = np.random.default_rng(3)
    n = task.nv
    x1 = np.concatenate([task.q_start, 0.3 * rng.normal(size=n), [0.4]])
    x2 = np.concatenate([task.q_goal, 0.3 * rng.normal(size=n), [2.1]])
    t = np.linspace(0.4, 2.1, 17001)
    q, v, a = sampling.hermite_samples(np.stack([x1, x2]), t, n)
    np.testing.assert_allclose(q[[0, -1]], [x1[:n], x2[:n]], atol=1e-12)
    np.testing.assert_allclose(v[[0, -1]], [x1[n:2 * n], x2[n:2 * n]], atol=1e-12)
    model = load_robot("human-arm")
    data = model.createData()
    L = np.array([np.sum(np.asarray(pin.rnea(model, data, *z)) ** 2) for z in zip(q, v, a)])
    assert edges.cost(x1, x2) == pytest.approx(_trapezoid(L, t[1] - t[0]), rel=1e-6)
    assert edges.cost(x2, x1) == np.inf  # backward in time


def test_edge_feasibility(task):
    edges = sampling.HermiteEdges(task)
    n = task.nv
    rest = np.zeros(n)
    x1 = np.concatenate([task.q_start, rest, [0.0]])
    x2 = np.concatenate([task.q_goal, rest, [2.9]])
    assert edges.feasible(x1, x2)
    assert not edges.feasible(x2, x1)  # backward in time
    assert not edges.feasible(x1, np.concatenate([task.q_goal, rest, [0.005]]))  # shorter than the minimum
    # joint 0 starts 2 deg below its upper limit: a fast start upwards overshoots it between the end points
    v = rest.copy()
    v[0] = 1.0
    assert not edges.feasible(np.concatenate([task.q_start, v, [0.0]]), x2)
    assert edges.feasible(np.concatenate([task.q_start, -v, [0.0]]), x2)


@needs_ompl
def test_plan_reaches_the_boundary_poses(result, task):
    assert result.solved
    n, tol = task.nv, sampling.SamplingSettings().goal_tolerance
    start = np.concatenate([task.q_start, np.zeros(n), [0.0]])
    goal = np.concatenate([task.q_goal, np.zeros(n), [task.duration]])
    assert np.linalg.norm(result.knots[0] - start) <= tol
    assert np.linalg.norm(result.knots[-1] - goal) <= tol
    tr = result.trajectory
    assert tr["t"][0] == 0.0 and tr["t"][-1] == pytest.approx(task.duration, abs=1e-12)
    np.testing.assert_allclose(tr["q"][[0, -1]], [task.q_start, task.q_goal], atol=tol)
    np.testing.assert_allclose(tr["v"][[0, -1]], 0.0, atol=tol)
    assert all(v <= tol for k, v in result.checks.items() if k.endswith("_error"))
    assert np.all(np.diff(result.knots[:, 2 * n]) > 0)  # forward in time


@needs_ompl
def test_plan_respects_joint_limits(result):
    model = load_robot("human-arm")
    q = result.trajectory["q"]
    assert np.all(q >= model.lowerPositionLimit - 1e-12) and np.all(q <= model.upperPositionLimit + 1e-12)
    assert result.checks["max_joint_violation"] == 0.0


@needs_ompl
def test_reported_cost_recomputed_with_rnea(result):
    """The exported q, v, a are one motion, and its reported J is rnea + trapezoid on them."""
    tr = result.trajectory
    t, q, v, a = tr["t"], tr["q"], tr["v"], tr["a"]
    dt = t[1] - t[0]
    np.testing.assert_allclose(np.diff(t), 1e-3, atol=1e-12)
    # central differences where t - dt and t + dt lie on the same edge (q cubic, v quadratic there)
    seg = np.searchsorted(result.knots[:, -1], t, side="right")
    inner = np.flatnonzero(seg[:-2] == seg[2:]) + 1
    assert len(inner) > 0.9 * len(t)
    dq, dv = (q[2:] - q[:-2]) / (2 * dt), (v[2:] - v[:-2]) / (2 * dt)
    jerk = np.abs(a[inner + 1] - a[inner - 1]).max() / (2 * dt)
    np.testing.assert_allclose(dq[inner - 1], v[inner], atol=dt**2 * jerk / 6 + 1e-9)
    np.testing.assert_allclose(dv[inner - 1], a[inner], atol=1e-7 * (1 + np.abs(a).max()))
    model = load_robot("human-arm")
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *z) for z in zip(q, v, a)])
    np.testing.assert_allclose(tr["tau"], tau, rtol=1e-12, atol=1e-9)
    J = _trapezoid(np.sum(tau**2, axis=1), dt)
    assert result.cost == pytest.approx(J, rel=1e-12)
    assert result.cost_planner == pytest.approx(J, rel=2e-3)  # Gauss panels against the 1 kHz trapezoid
    assert result.improvements[-1][2] == pytest.approx(result.cost_planner)
    assert [c for _, _, c in result.improvements] == sorted((c for _, _, c in result.improvements), reverse=True)


_REPRO = """
import json, sys
from latentoc.baselines.sampling import plan, SamplingSettings
from latentoc.problem.toml_files import load_problem
r = plan(load_problem("arm-raise"), iterations=[60], settings=SamplingSettings(seed=int(sys.argv[1])))[0]
print(json.dumps({"cost": r.cost_planner, "knots": r.knots.tolist(), "seeded": r.seeded}))
"""


@needs_ompl
@pytest.mark.slow  # two processes
def test_same_seed_same_plan_in_a_fresh_process():
    def run(seed: int) -> dict:
        out = subprocess.run([sys.executable, "-c", _REPRO, str(seed)], capture_output=True, text=True, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    a, b = run(7), run(7)
    assert a["seeded"] and a == b


@needs_ompl
def test_bench_prints_checkpoints(capsys, tmp_path):
    from latentoc.benchmarks import sampling_bench
    out = tmp_path / "rows.json"
    assert sampling_bench.main(["--iterations", "20", "40", "--no-solves", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "J 1 kHz" in text and "paper Table 3" in text
    rows = json.loads(out.read_text())["sampling"]
    assert [r["budget"] for r in rows] == [20, 40] and all(r["solved"] for r in rows)
    assert rows[1]["cost_planner"] <= rows[0]["cost_planner"]


@needs_ompl
@pytest.mark.slow
def test_longer_plan_improves_and_rechecks(problem):
    r1, r2 = sampling.plan(problem, seconds=[5.0, 25.0])
    assert r1.solved and r2.solved and r2.iterations > r1.iterations
    assert r2.cost_planner <= r1.cost_planner
    for r in (r1, r2):
        assert r.checks["max_joint_violation"] == 0.0
        assert r.cost == pytest.approx(r.cost_planner, rel=2e-3)
