"""The result schema: a folder's round trip, atomic files, versioned and checked on reading."""

import json
import os

import numpy as np
import pinocchio as pin
import pytest
from result_factory import make_result

from latentoc.errors import LatentocError, ResultFileError
from latentoc.results import (GPDM_NAME, RESULT_NAME, SCHEMA_VERSION, TRAJECTORY_KEYS, TRAJECTORY_NAME, Result,
                              atomic_write, load_result)
from latentoc.solve import Solution


def test_round_trip(tmp_path):
    r = make_result(joint_range_deg=None, note=np.float64(1.5))
    paths = r.save(tmp_path / "out")
    assert [p.name for p in paths] == [RESULT_NAME, TRAJECTORY_NAME]
    back = load_result(tmp_path / "out")
    assert back.to_json() == r.to_json() and back.details["note"] == 1.5
    for k in ("t", "q", "v", "a", "tau"):
        assert np.array_equal(back.trajectory[k], r.trajectory[k])
    m = pin.Model()
    m.loadFromString(str(back.trajectory["model"]))
    assert m.nq == 7 and np.isclose(sum(i.mass for i in m.inertias), 8.74)
    assert sorted(os.listdir(tmp_path / "out")) == [RESULT_NAME, TRAJECTORY_NAME]


def test_convergence_round_trip(tmp_path):
    """A kind's ``convergence`` list becomes the result's, every history series as floats; a result.json
    written before the field existed reads as none."""
    from latentoc.results import convergence_entry

    hist = {"iter": [0, 1], "objective": [3, 2.5], "inf_pr": [1e-2, 1e-9], "inf_du": [1, 1e-9], "mu": [0.1, 1e-9],
            "alpha_pr": [0, 1], "alpha_du": [0, 1]}
    sol = Solution(result={**make_result().to_json(), "performance_gain_pct": 1.0, "solve_time_s": 1.0,
                           "tube": None, "convergence": [{"phase": "phase 1", "round": 1, "history": hist}]},
                   trajectory=make_result().trajectory)
    r = Result.from_solution(sol, _Problem())
    assert r.convergence == [convergence_entry("phase 1", 1, hist)] and "convergence" not in r.details
    assert r.convergence[0]["history"]["iter"] == [0.0, 1.0]
    r.save(tmp_path)
    assert load_result(tmp_path).convergence == r.convergence
    data = json.loads((tmp_path / RESULT_NAME).read_text())
    del data["convergence"]
    (tmp_path / RESULT_NAME).write_text(json.dumps(data))
    assert load_result(tmp_path).convergence == []


class _Problem:
    source, settings = "test", {}


def test_result_json_has_the_core_fields_of_every_kind(tmp_path):
    make_result().save(tmp_path)
    data = json.loads((tmp_path / RESULT_NAME).read_text())
    assert data["schema_version"] == SCHEMA_VERSION
    assert {"problem", "kind", "method", "status", "success", "iterations", "cost_initial", "cost", "gain_pct",
            "times", "tube", "violations", "environment", "settings", "details"} <= set(data)
    assert set(data["environment"]) == {"latentoc", "casadi", "pinocchio", "numpy", "scipy", "python", "cpu", "cpu_count",
                                        "threads"}
    assert data["environment"]["pinocchio"] == pin.__version__


def test_gpdm_travels_with_the_result(tmp_path):
    from latentoc.gpdm import GPDMSettings, learn_gpdm

    rng = np.random.default_rng(0)
    Y = np.cumsum(rng.standard_normal((20, 4)), axis=0)
    gp = learn_gpdm(Y, GPDMSettings(latent_dim=2, max_iterations=5))
    names = [p.name for p in make_result(gpdm=gp).save(tmp_path)]
    assert names == [RESULT_NAME, TRAJECTORY_NAME, GPDM_NAME]
    back = load_result(tmp_path).gpdm
    x = gp.X[:3] + 0.1
    assert np.array_equal(back.X, gp.X) and np.allclose(back.variance(x), gp.variance(x), rtol=0, atol=0)


@pytest.mark.parametrize("damage, match", [
    (lambda d: (d / RESULT_NAME).unlink(), "no result.json"),
    (lambda d: (d / TRAJECTORY_NAME).unlink(), "needs result.json and trajectory.npz"),
    (lambda d: (d / RESULT_NAME).write_text("{"), "not JSON"),
    (lambda d: (d / RESULT_NAME).write_text(json.dumps({"problem": "old", "cost": 1.0})),
     "schema_version None; this latentoc reads 1"),
    (lambda d: (d / RESULT_NAME).write_text(json.dumps({"schema_version": SCHEMA_VERSION})), "misses or mistypes"),
    (lambda d: (d / TRAJECTORY_NAME).write_bytes(b"garbage"), "unreadable arrays"),
])
def test_damaged_folders_are_named_errors(tmp_path, damage, match):
    make_result().save(tmp_path)
    damage(tmp_path)
    with pytest.raises(ResultFileError, match=match) as err:
        load_result(tmp_path)
    assert isinstance(err.value, LatentocError)


def test_trajectory_keys_are_the_documented_ones():
    """A kind's trajectory with a key TRAJECTORY_KEYS does not document is a bug, refused."""
    sol = Solution(result={}, trajectory={"t": np.zeros(2), "q_guess": np.zeros(2)})
    with pytest.raises(KeyError, match="q_guess"):
        Result.from_solution(sol, None)
    assert {"t", "q", "v", "a", "tau", "model", "x", "P", "sigma2", "wrench"} <= set(TRAJECTORY_KEYS)


def test_failed_write_leaves_no_file(tmp_path):
    target = tmp_path / "a.json"

    def boom(f):
        f.write("{partial")
        raise RuntimeError("disk full")

    with pytest.raises(RuntimeError):
        atomic_write(target, boom)
    assert os.listdir(tmp_path) == []
    atomic_write(target, lambda f: json.dump({"ok": 1}, f))
    assert json.loads(target.read_text()) == {"ok": 1} and os.listdir(tmp_path) == ["a.json"]
