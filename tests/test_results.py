"""The result schema: a folder's round trip, atomic files, versioned and checked on reading."""

import json
import os
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from result_factory import make_result

from latentoc.errors import LatentocError, ResultFileError
from latentoc.problem.kinds import Solution
from latentoc.results import (GPDM_NAME, RESULT_NAME, SCHEMA_VERSION, TRAJECTORY_KEYS, TRAJECTORY_NAME, Result,
                              load_result)
from latentoc.runtime.files import atomic_write
from latentoc.latent.tube import TubeResult


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
    (lambda d: (d / RESULT_NAME).write_text(json.dumps({"schema_version": SCHEMA_VERSION})),
     "result.json: misses the field 'problem'"),
    (lambda d: (d / TRAJECTORY_NAME).write_bytes(b"garbage"), "trajectory.npz is not the file result.json was"),
    (lambda d: (d / TRAJECTORY_NAME).write_bytes(b""), "trajectory.npz is not the file result.json was"),
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


# ---------------------------------------------------------------- issue 29: results you can trust
def _edit_json(folder, **changes):
    data = json.loads((folder / RESULT_NAME).read_text())
    data.update(changes)
    (folder / RESULT_NAME).write_text(json.dumps(data))


@pytest.mark.parametrize("key, value, match", [
    ("cost", "lots", "key 'cost' must be a number, got 'lots'"),
    ("success", "yes", "key 'success' must be true or false"),
    ("iterations", 7.5, "key 'iterations' must be an integer"),
    ("times", {"solve_s": [1]}, "key 'times.solve_s' must be a number"),
    ("violations", {"tube": None}, "key 'violations.tube' must be a number"),
    ("tube", {"spec": "5x", "delta": "big", "relative": 1, "training": 1, "max_sigma2": 1},
     "key 'tube.delta' must be a number"),
    ("environment", {"latentoc": 1}, "key 'environment.latentoc' must be a string"),
    ("convergence", {"a": 1}, "key 'convergence' must be a list"),
])
def test_field_types_are_checked_on_load(tmp_path, key, value, match):
    """A result.json whose field has the wrong type is an error naming the file and the key, not a
    Result holding a string where a cost should be."""
    make_result().save(tmp_path)
    _edit_json(tmp_path, **{key: value})
    with pytest.raises(ResultFileError, match=match) as err:
        load_result(tmp_path)
    assert str(tmp_path / RESULT_NAME) in str(err.value)


def test_json_is_strict_and_non_finite_numbers_round_trip(tmp_path):
    """A tube of 1e308 gives an infinite delta x beta_3: result.json stays strict JSON (no Infinity
    or NaN token, which other JSON readers refuse) and the numbers read back as they were."""
    r = make_result(note=float("nan"))
    r.tube = TubeResult(spec=1e308, delta=1e308, relative=float("inf"), training=0.1, max_sigma2=0.5)
    r.gain_pct = float("-inf")
    r.save(tmp_path)
    text = (tmp_path / RESULT_NAME).read_text()
    json.loads(text, parse_constant=lambda c: pytest.fail(f"{c} in result.json"))
    back = load_result(tmp_path)
    assert back.tube.relative == float("inf") and back.tube.delta == 1e308 and back.gain_pct == float("-inf")
    assert back.details["note"] == "NaN"
    (tmp_path / RESULT_NAME).write_text(text.replace('"-Infinity"', "-Infinity"))
    with pytest.raises(ResultFileError, match="not JSON: -Infinity is not strict JSON"):
        load_result(tmp_path)


def test_arrays_of_another_solve_are_refused(tmp_path):
    """result.json records the checksums of the arrays: a trajectory.npz of another solve beside it
    (a write that failed midway, a copy) is refused, not read as this result's."""
    make_result(gain=10.0).save(tmp_path / "a")
    make_result(gain=20.0, n=5).save(tmp_path / "b")
    (tmp_path / "b" / TRAJECTORY_NAME).replace(tmp_path / "a" / TRAJECTORY_NAME)
    with pytest.raises(ResultFileError, match="trajectory.npz is not the file result.json was written with"):
        load_result(tmp_path / "a")


def test_a_write_that_fails_midway_leaves_no_mixed_folder(tmp_path, monkeypatch):
    """Saving over an earlier result: a failure while the new files move in leaves a folder with no
    result.json (incomplete, resumed by a sweep), never the old result.json over new arrays; saving
    into a new folder that fails leaves no folder and no temporary one."""
    import latentoc.runtime.files as files

    make_result(gain=10.0).save(tmp_path / "r")
    real = os.replace

    def fail_on_result(src, dst):
        if str(dst).endswith(RESULT_NAME) and not str(src).endswith(".tmp"):
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(files.os, "replace", fail_on_result)
    with pytest.raises(LatentocError, match="cannot write .*No space left"):
        make_result(gain=20.0, n=5).save(tmp_path / "r")
    assert not (tmp_path / "r" / RESULT_NAME).exists()
    with pytest.raises(ResultFileError, match="no result.json"):
        load_result(tmp_path / "r")
    monkeypatch.setattr(files, "atomic_write", lambda *a, **k: (_ for _ in ()).throw(OSError(5, "I/O error")))
    with pytest.raises(LatentocError, match="cannot write .*I/O error"):
        make_result().save(tmp_path / "new")
    assert sorted(os.listdir(tmp_path)) == ["r"]
    monkeypatch.undo()
    make_result(gain=20.0, n=5).save(tmp_path / "r")
    assert load_result(tmp_path / "r").gain_pct == 20.0


def test_saving_over_a_result_keeps_other_files_and_drops_stale_ones(tmp_path):
    """Saving into an existing result folder replaces the result's files (an old gpdm.npz the new
    result lacks goes) and leaves the user's other files, e.g. plots, alone."""
    from latentoc.gpdm import GPDMSettings, learn_gpdm

    Y = np.cumsum(np.random.default_rng(0).standard_normal((12, 3)), axis=0)
    make_result(gpdm=learn_gpdm(Y, GPDMSettings(latent_dim=2, max_iterations=3))).save(tmp_path)
    (tmp_path / "plots").mkdir()
    make_result(gain=30.0).save(tmp_path)
    assert sorted(os.listdir(tmp_path)) == ["plots", RESULT_NAME, TRAJECTORY_NAME]
    assert load_result(tmp_path).gain_pct == 30.0


def test_out_must_be_a_writable_folder(tmp_path):
    from latentoc.runtime.files import OutputError, check_out_dir

    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputError, match="is a file, not a folder"):
        make_result().save(tmp_path / "file")
    with pytest.raises(OutputError, match="file is a file, not a folder"):
        check_out_dir(tmp_path / "file" / "sub")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if not os.access(ro, os.W_OK):  # root may write anywhere
            with pytest.raises(OutputError, match="is not writable"):
                check_out_dir(ro / "new")
    finally:
        ro.chmod(0o700)
    assert check_out_dir(tmp_path / "a" / "b") == tmp_path / "a" / "b"


def _save(out, writer: int, pause: float) -> None:
    """Save a folder whose every file names the writer, pausing ``pause`` s before its marker."""
    import time

    from latentoc.runtime.files import write_folder

    replace = os.replace

    def slow_marker(a, b):
        if os.path.basename(b) == "result.json" and os.path.dirname(b) == str(out):  # the move into out
            time.sleep(pause)
        replace(a, b)

    os.replace = slow_marker  # this forked writer's only
    files = {name: bytes([writer]) * 1000 for name in ("gpdm.npz", "trajectory.npz", "result.json")}
    write_folder(files, out, "result.json", owned=("gpdm.npz", "trajectory.npz"))


def test_concurrent_writers_never_mix_a_folder(tmp_path):
    """Two processes saving into one result folder take turns: the first pauses between its arrays and
    its result.json while the second saves whole; the folder then holds one writer's files (without
    the lock: the second's arrays beside the first's result.json, as issue 36 saw 1 trial in 40)."""
    import multiprocessing
    import time

    ctx = multiprocessing.get_context("fork")
    out = tmp_path / "r"
    _save(out, 9, 0.0)  # the folder exists: the writers move their files into it
    first = ctx.Process(target=_save, args=(out, 1, 1.0))
    second = ctx.Process(target=_save, args=(out, 2, 0.0))
    first.start()
    time.sleep(0.4)
    second.start()
    for p in (first, second):
        p.join()
    assert first.exitcode == second.exitcode == 0
    held = {f.name: f.read_bytes()[:1] for f in out.iterdir()}
    assert sorted(held) == ["gpdm.npz", "result.json", "trajectory.npz"] and len(set(held.values())) == 1, held
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize("change, match", [
    ({"model": np.str_("not a model")}, "'model' is not a Pinocchio model string"),
    ({"model": np.zeros(3)}, "'model' must be one string"),
    ({"q": np.zeros((11, 3))}, r"'q' has shape \(11, 3\), the model and t need \(11, 7\)"),
    ({"q": np.zeros((10, 7))}, r"'q' has shape \(10, 7\)"),
    ({"v": np.full((11, 7), np.nan)}, "'v' has values that are not finite"),
    ({"t": np.r_[0.0, np.ones(10)]}, "'t' must be finite, increasing"),
])
def test_arrays_that_match_their_checksums_but_not_the_model_are_named(tmp_path, change, match):
    """Files written whole (their checksums hold) whose arrays cannot be the model's motion: the load
    names the file and the array instead of a traceback later or a silent drawing."""
    make_result(trajectory=change).save(tmp_path / "r")
    with pytest.raises(ResultFileError, match=f"r: trajectory.npz: {match}"):
        load_result(tmp_path / "r")


def test_out_is_checked_before_any_work(tmp_path):
    """--out: a dangling link, a name the file system cannot take, a folder nothing can be made in
    are refused up front, naming the path (issue 36: they failed after the solve)."""
    from latentoc.runtime.files import OutputError, check_out_dir

    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    for bad, match in [(tmp_path / "dangling", "is a symbolic link to .*nowhere, which does not exist"),
                       (tmp_path / "dangling" / "r", "is a symbolic link"),
                       (tmp_path / ("n" * 250), "bytes; this file system takes"),
                       (Path("/proc/latentoc-result"), "/proc is not writable")]:
        with pytest.raises(OutputError, match=match):
            check_out_dir(bad)
    assert check_out_dir(tmp_path / "a" / "b") == tmp_path / "a" / "b" and not (tmp_path / "a").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling"]  # the probe left nothing


def test_a_killed_writers_temporary_folder_is_removed_by_the_next_save(tmp_path):
    import subprocess
    import sys

    from latentoc.runtime.files import write_folder

    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    left = tmp_path / f".r.{int(gone.stdout)}.abcd1234.tmp"  # what a SIGTERM while writing leaves
    left.mkdir()
    (left / "trajectory.npz").write_bytes(b"half")
    alive = tmp_path / f".r.{os.getppid()}.efgh5678.tmp"  # a writer still running: left alone
    alive.mkdir()
    write_folder({"result.json": b"{}"}, tmp_path / "r", "result.json")
    assert not left.exists() and alive.exists() and (tmp_path / "r" / "result.json").read_bytes() == b"{}"
