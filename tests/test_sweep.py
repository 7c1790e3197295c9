"""Sweeps: rows per tube and joint range, the Table 2 layout, atomic files."""

import json

import pytest

from latentoc.problem import load_problem
from latentoc.sweep import format_table, sweep, write_sweep


@pytest.fixture(scope="module")
def rows():
    lines = []
    out = sweep(load_problem("arm-raise-small"), ["200x"], [5.0], progress=lines.append)
    assert len(lines) == 2 and lines[0].startswith("[1/2] tube 200x") and "joint range" in lines[1]
    return out


def test_rows(rows):
    lat, jr = rows
    assert lat["method"] == "latent" and lat["tube_spec"] == "200x" and lat["success"]
    assert jr["method"] == "joint-range" and jr["joint_range_deg"] == 5.0 and jr["success"]
    assert lat["cost"] < lat["cost_initial"] and jr["cost"] < jr["cost_initial"]
    assert "max_friction_ratio" not in lat  # 1 kHz contact checks only when the result has them


def test_rows_keep_the_contact_checks(monkeypatch):
    """A contact problem's 1 kHz verification travels into its sweep row."""
    import latentoc.sweep as sw

    class Sol:
        result = {"method": "latent", "tube": 0.02, "tube_spec": 0.02, "cost": 0.4, "cost_initial": 0.7,
                  "performance_gain_pct": -40.0, "solve_time_s": 1.0, "status": "Solve_Succeeded", "success": True,
                  "max_friction_ratio": 0.38, "cop_margin": 0.01,
                  "toe_slip": 0.02, "other_start": {"warm_start": True, "distance": 0.35}}
        trajectory: dict = {}
        warm = None

    monkeypatch.setattr(sw, "solve", lambda *a, **k: Sol())
    monkeypatch.setattr(sw, "problem_gpdm", lambda *a, **k: (None,))
    (row,) = sw.sweep(load_problem("broad-jump"), [0.02], progress=None)
    assert row["max_friction_ratio"] == 0.38 and row["cop_margin"] == 0.01
    assert row["toe_slip"] == 0.02 and "toe_displacement" not in row
    assert row["cost"] == 0.4 and "zmp_margin" not in row
    assert row["other_start"] == {"warm_start": True, "distance": 0.35}  # the start not kept


def test_table_and_files(rows, tmp_path):
    table = format_table(rows)
    assert table.splitlines()[0].startswith("| tube | delta")
    assert "| 200x |" in table and "+-5 deg" in table
    j, md = write_sweep(rows, tmp_path, {"problem": "arm-raise-small"})
    data = json.loads(j.read_text())
    assert data["meta"]["problem"] == "arm-raise-small" and len(data["rows"]) == 2
    assert md.read_text().strip() == table.strip()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.json", "sweep.md"]


def test_warm_started_sweep_reaches_the_cold_optima():
    """Each tube starts from the largest smaller tube's optimum (not from a larger one) and
    reaches the same optimum as a cold start from the training fit."""
    p = load_problem("arm-raise-small")
    tubes = ["5x", "20x", "3x", "200x"]
    warm = sweep(p, tubes, progress=None)
    cold = sweep(p, tubes, progress=None, warm_start=False)
    assert [r["warm_start"] for r in warm] == [False, True, False, True]
    assert not any(r["warm_start"] for r in cold)
    for w, c in zip(warm, cold):
        assert w["success"] and c["success"] and w["tube"] == c["tube"]
        assert abs(w["cost"] - c["cost"]) <= 1e-6 * c["cost"]
        assert w["cost_initial"] == c["cost_initial"]
