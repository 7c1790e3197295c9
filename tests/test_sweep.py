"""Sweeps: serial with warm starts, on a Dask LocalCluster, resumed; the Table 2 layout; files."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from latentoc import load_problem, load_result, sweep
from latentoc.errors import SweepError
from latentoc.sweeps import SweepTask, format_table, run_task, write_sweep

REPO = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.slow  # every test here solves


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    out = tmp_path_factory.mktemp("sweep")
    lines = []
    outcome = sweep(load_problem("arm-raise-small"), ["200x"], baseline_ranges=[5.0], out=out,
                    progress=lines.append)
    assert len(lines) == 2 and lines[0].startswith("[1/2] tube 200x") and "joint range" in lines[1]
    return out, outcome


def test_results_and_their_folders(swept):
    out, outcome = swept
    lat, jr = outcome.results
    assert not outcome.failures
    assert lat.method == "latent" and lat.tube.spec == "200x" and lat.success
    assert jr.method == "joint-range" and jr.details["joint_range_deg"] == 5.0 and jr.success
    assert lat.cost < lat.cost_initial and jr.cost < jr.cost_initial
    for r, label in ((lat, "tube-200x"), (jr, "joint-range-5")):
        back = load_result(out / label)
        assert back.to_json() == r.to_json() and np.array_equal(back.trajectory["q"], r.trajectory["q"])


def test_table_and_files(swept, tmp_path):
    _, outcome = swept
    table = format_table(outcome.results)
    assert table.splitlines()[0].startswith("| tube | delta")
    assert "| 200x |" in table and "+-5 deg" in table
    j, md = write_sweep(outcome, tmp_path, {"problem": "arm-raise-small"})
    data = json.loads(j.read_text())
    assert data["meta"]["problem"] == "arm-raise-small" and len(data["rows"]) == 2 and data["failures"] == []
    assert data["rows"][0]["gain_pct"] == outcome.results[0].gain_pct
    assert md.read_text().strip() == table.strip()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sweep.json", "sweep.md"]


def test_resume_skips_the_written_tasks(swept):
    """A resumed sweep solves only the tasks without a complete folder, and returns the others as
    written."""
    out, outcome = swept
    lines = []
    again = sweep(load_problem("arm-raise-small"), ["200x", "50x"], baseline_ranges=[5.0], out=out, resume=True,
                  progress=lines.append)
    assert len(lines) == 1 and "tube 50x" in lines[0]  # only the new tube was solved
    assert [r.to_json() for r in again.results[::2]] == [r.to_json() for r in outcome.results]
    assert (out / "tube-50x" / "result.json").is_file()
    with pytest.raises(SweepError, match="tube-200x was written for other settings .latent_dim"):
        sweep(load_problem("arm-raise-small", latent_dim=2), ["200x"], out=out, resume=True, progress=None)


def test_warm_started_sweep_reaches_the_cold_optima():
    """Each tube starts from the largest smaller tube's optimum (not from a larger one) and
    reaches the same optimum as a cold start from the training fit."""
    p = load_problem("arm-raise-small")
    tubes = ["5x", "20x", "3x", "200x"]
    warm = sweep(p, tubes, progress=None).results
    cold = sweep(p, tubes, progress=None, warm_start=False).results
    assert [r.details["warm_start"] for r in warm] == [False, True, False, True]
    assert not any(r.details["warm_start"] for r in cold)
    for w, c in zip(warm, cold):
        assert w.success and c.success and w.tube.delta == c.tube.delta
        assert abs(w.cost - c.cost) <= 1e-6 * c.cost
        assert w.cost_initial == c.cost_initial


def test_a_task_is_its_problem_as_data():
    """run_task needs only the task: the same result files as a serial cold solve."""
    p = load_problem("arm-raise-small")
    task = SweepTask(p.to_dict(), "latent", tube="20x")
    files = run_task(task)
    serial = sweep(p, ["20x"], progress=None).results[0]
    assert json.loads(files["result.json"])["cost"] == serial.cost


def test_dask_cluster_sweep_equals_the_serial_one_and_reports_failures(tmp_path):
    """On a 2-worker LocalCluster the tasks start cold: the costs equal a serial cold sweep's (to
    rounding: the workers' BLAS runs on one thread, see docs/api.md), a failed task is reported with
    its tube and error, and the others are written."""
    distributed = pytest.importorskip("distributed")
    p = load_problem("arm-raise-small")
    tubes = ["5x", "1e-12", "20x"]
    serial = sweep(p, tubes, warm_start=False, progress=None)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=50) as cluster, distributed.Client(cluster) as client:
        dist = sweep(p, tubes, client, out=tmp_path, progress=None)
    assert [f.label for f in dist.failures] == ["tube-1e-12"] and dist.failures[0].error == "SolveError"
    assert "infeasible" in dist.failures[0].message and dist.failures[0].input_error
    assert [r.tube.spec for r in dist.results] == ["5x", "20x"]
    for a, b in zip(serial.results, dist.results):
        assert abs(a.cost - b.cost) <= 1e-8 * a.cost  # the same optimum; the path (iterations) may differ
        np.testing.assert_allclose(b.trajectory["q"], a.trajectory["q"], rtol=0, atol=1e-8)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["tube-20x", "tube-5x"]


def _cli(*args, env=None, timeout=600):
    return subprocess.run([sys.executable, "-m", "latentoc", *args], capture_output=True, text=True, cwd=REPO,
                          timeout=timeout, env={**os.environ, "LATENTOC_QUIET": "1", **(env or {})})


def test_cli_workers_give_the_serial_files(tmp_path):
    """`sweep --workers 2` writes the same result arrays as the serial cold sweep, bit for bit,
    when both run their BLAS on one thread (as Dask's workers do)."""
    pytest.importorskip("distributed")
    one = {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    a = _cli("sweep", "arm-raise-small", "--tubes", "5x", "--out", str(tmp_path / "serial"), "--quiet", env=one)
    b = _cli("sweep", "arm-raise-small", "--tubes", "5x", "--out", str(tmp_path / "dask"), "--workers", "2",
             "--quiet", env=one)
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    ra, rb = load_result(tmp_path / "serial" / "tube-5x"), load_result(tmp_path / "dask" / "tube-5x")
    assert ra.cost == rb.cost
    for key in ("q", "tau", "x", "P"):
        assert np.array_equal(ra.trajectory[key], rb.trajectory[key]), key
    assert json.loads((tmp_path / "dask" / "sweep.json").read_text())["meta"]["workers"] == 2


def test_workers_without_dask_name_the_extra(tmp_path):
    code = ("import sys; sys.modules['distributed'] = None\n"
            "from latentoc.cli.parser import main\n"
            f"sys.exit(main(['sweep', 'arm-raise-small', '--workers', '2', '--out', {str(tmp_path / 'o')!r}]))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=120)
    assert p.returncode == 2 and "pip install 'latentoc[distributed]'" in p.stderr and "Traceback" not in p.stderr
    assert not (tmp_path / "o").exists()
