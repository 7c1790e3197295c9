"""result.json + trajectory.npz: round trip, atomic writes, rebuildable model."""

import json
import os

import numpy as np
import pinocchio as pin
import pytest

from latentoc.results import RESULT_NAME, TRAJECTORY_NAME, atomic_write, read_solution, write_solution
from latentoc.robots import load_robot
from latentoc.solve import Solution


def _solution():
    model = load_robot("human-arm")
    t = np.linspace(0, 1, 11)
    q = np.tile(pin.neutral(model), (11, 1))
    return Solution(result={"problem": "x", "cost": np.float64(1.5), "success": True, "tube": None},
                    trajectory={"t": t, "q": q, "v": 0 * q, "a": 0 * q, "tau": 0 * q,
                                "model": np.str_(model.saveToString())})


def test_round_trip(tmp_path):
    sol = _solution()
    paths = write_solution(sol, tmp_path / "out")
    assert [p.name for p in paths] == [RESULT_NAME, TRAJECTORY_NAME]
    back = read_solution(tmp_path / "out")
    assert back.result == {"problem": "x", "cost": 1.5, "success": True, "tube": None}
    for k in ("t", "q", "v", "a", "tau"):
        assert np.array_equal(back.trajectory[k], sol.trajectory[k])
    m = pin.Model()
    m.loadFromString(str(back.trajectory["model"]))
    assert m.nq == 7 and np.isclose(sum(i.mass for i in m.inertias), 8.74)
    assert sorted(os.listdir(tmp_path / "out")) == [RESULT_NAME, TRAJECTORY_NAME]


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
