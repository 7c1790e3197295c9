"""The remaining bad inputs of issue 29, each `latentoc: error: ...` naming the input, exit code 2,
nothing written: a non-UTF-8 problem file, a .npy renamed .npz, `learn --out` a file, a problem
name with '/', sizes with no upper bound, a GPDM of another robot, dimension or motion given with
--gpdm; and `list --verbose | head`."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import latentoc
from latentoc.cli.parser import main
from latentoc.errors import SolveError
from latentoc.gpdm import GPDMSettings, learn_gpdm

REPO = Path(__file__).resolve().parents[1]
SMALL = (REPO / "problems" / "arm-raise-small.toml").read_text()


def _fails(capsys, args, match, out):
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("latentoc: error: ") and match in err and "Traceback" not in err, err
    assert not out.exists()
    return err


def test_a_problem_file_that_is_not_utf8(tmp_path, capsys):
    path = tmp_path / "p.toml"
    path.write_bytes(SMALL.replace('name = "arm-raise-small"', 'name = "arm\xe9"').encode("latin-1"))
    err = _fails(capsys, ["solve", str(path), "--out", str(tmp_path / "o")], "not UTF-8 text", tmp_path / "o")
    assert str(path) in err


@pytest.mark.parametrize("name", ["../escaped", "a/b", "..", "x\ny", "a\\b"])
def test_a_problem_name_that_is_a_path_is_refused(tmp_path, capsys, name):
    """The name makes the default output folder out/<name>-latent: '../x' wrote outside it."""
    path = tmp_path / "p.toml"
    path.write_text(SMALL.replace('name = "arm-raise-small"', f"name = {json.dumps(name)}"))
    _fails(capsys, ["solve", str(path), "--out", str(tmp_path / "o")], "key 'name'", tmp_path / "o")
    with pytest.raises(latentoc.LatentocError, match="must be a plain name"):
        latentoc.load_problem("arm-raise-small").replace(name="../x")


def test_a_npy_renamed_npz(tmp_path, capsys):
    """np.load returns the array of a .npy whatever its name: it was a TypeError traceback."""
    np.save(tmp_path / "m.npy", np.zeros((5, 3)))
    (tmp_path / "m.npy").rename(tmp_path / "m.npz")
    err = _fails(capsys, ["learn", str(tmp_path / "m.npz"), "--robot", "human-arm", "--out", str(tmp_path / "o")],
                 "a single array (.npy), not an NPZ archive", tmp_path / "o")
    assert str(tmp_path / "m.npz") in err
    (tmp_path / "g.npz").write_bytes((tmp_path / "m.npz").read_bytes()[:50])  # a truncated file as --gpdm
    _fails(capsys, ["solve", "arm-raise-small", "--gpdm", str(tmp_path / "g.npz"), "--out", str(tmp_path / "o")],
           "is not a GPDM written by latentoc", tmp_path / "o")


def test_learn_out_a_file_fails_before_any_work(tmp_path, capsys, monkeypatch):
    import latentoc.cli.learn as learn

    monkeypatch.setattr(learn, "demonstration_from_file", lambda *a, **k: pytest.fail("work began"))
    (tmp_path / "f").write_text("mine")
    csv = tmp_path / "m.csv"
    csv.write_text("t,lhumerus_rz\n0,0\n1,0.1\n")
    _fails(capsys, ["learn", str(csv), "--robot", "human-arm", "--out", str(tmp_path / "f" / "sub")],
           "is a file, not a folder", tmp_path / "f" / "sub")
    assert main(["learn", str(csv), "--robot", "human-arm", "--out", str(tmp_path / "f")]) == 2
    assert "--out " + str(tmp_path / "f") + " is a file" in capsys.readouterr().err
    assert (tmp_path / "f").read_text() == "mine"


@pytest.mark.parametrize("old, new, key", [
    ("control_points = 7", "control_points = 100000000", "latent.control_points = 100000000"),
    ("constraint_points = 24", "constraint_points = 10000000000", "transcription.constraint_points = 10000000000"),
    ("duration = 2.9", "duration = 1e12", "duration = 1e+12"),
])
def test_sizes_beyond_the_memory_are_refused_up_front(tmp_path, capsys, old, new, key):
    """control_points = 1e8 was a MemoryError inside the spline basis (71 PiB)."""
    path = tmp_path / "p.toml"
    path.write_text(SMALL.replace(old, new))
    err = _fails(capsys, ["solve", str(path), "--out", str(tmp_path / "o")], key, tmp_path / "o")
    assert "GB of memory; this machine has" in err and str(path) in err


@pytest.fixture(scope="module")
def arm():
    """arm-raise-small and its training frames (what its GPDM is learned from)."""
    from latentoc.min_torque.training import training_frames

    problem = latentoc.load_problem("arm-raise-small")
    return problem, training_frames(problem)[1]


@pytest.mark.parametrize("data, d, match", [
    (lambda Q: np.hstack([Q, Q[:, :2]]), 3, "the given GPDM models 9 joints; problem 'arm-raise-small' moves 7"),
    (lambda Q: Q, 2, "the given GPDM has latent dimension 2; problem 'arm-raise-small' has latent.dim = 3"),
    (lambda Q: Q[:-3], 3, "the given GPDM has 27 latent points, the problem's training motion has 30"),
    (lambda Q: Q + 0.01, 3, "learned from other data than problem 'arm-raise-small'"),
])
def test_a_given_gpdm_must_be_the_problems(arm, data, d, match):
    """A Panda's (D = 9) or a d = 2 GPDM passed with --gpdm to the arm problem was accepted unchecked."""
    problem, Q = arm
    gp = learn_gpdm(data(Q), GPDMSettings(latent_dim=d, max_iterations=2))
    with pytest.raises(SolveError, match=match):
        latentoc.solve(problem, gpdm=gp)


@pytest.mark.slow  # a fresh process
def test_list_verbose_into_a_closed_pipe_ends_quietly():
    p = subprocess.run(f"{sys.executable} -m latentoc list --verbose | head -1", shell=True, cwd=REPO,
                       capture_output=True, text=True, timeout=120)
    assert p.stdout.startswith("# ") and p.stdout.count("\n") == 1
    assert "Traceback" not in p.stderr and "BrokenPipe" not in p.stderr, p.stderr


@pytest.mark.slow  # a solve
def test_a_tube_of_1_7e308x_writes_strict_json(tmp_path):
    """tube = 1.7e308x: delta x beta_3 overflows; result.json holds "Infinity", not the token Infinity
    that JSON readers refuse, and reads back."""
    assert main(["solve", "arm-raise-small", "--tube", "1.7e308x", "--quiet", "--out", str(tmp_path)]) == 0
    json.loads((tmp_path / "result.json").read_text(), parse_constant=lambda c: pytest.fail(c))
    r = latentoc.load_result(tmp_path)
    assert r.tube.delta == pytest.approx(1.7e308 * r.tube.training) and r.tube.relative == float("inf")


def test_an_absolute_tube_that_bounds_nothing_is_refused(tmp_path, capsys):
    """--tube 5 is delta = 5, above beta1 + 1/beta3, the largest sigma^2 (Eq. 19) the GPDM gives
    anywhere (its value far from the data, computed here from the GPDM's variance): refused before
    the solve, showing the 5x spelling and its delta; 0.5 (below the ceiling) is a tube."""
    from latentoc.min_torque.training import problem_gpdm
    from latentoc.latent.tube import tube_delta

    problem = latentoc.load_problem("arm-raise-small")
    gp, _ = problem_gpdm(problem)
    far = float(gp.variance(gp.X.max(axis=0) + 100.0))
    assert far == pytest.approx(gp.prior_variance, rel=1e-12) and 0.5 < far < 5
    err = _fails(capsys, ["solve", "arm-raise-small", "--tube", "5", "--quiet", "--out", str(tmp_path / "o")],
                 "tube delta = 5 is at or above", tmp_path / "o")
    assert f'"5x" is 5 times the training motion\'s own tube (delta = {5 * gp.tube_size():.4g}' in err
    assert tube_delta(0.5, gp) == 0.5 and tube_delta("60x", gp) == pytest.approx(60 * gp.tube_size())
    with pytest.raises(latentoc.LatentocError, match="bound nothing"):
        latentoc.solve(problem.replace(tube=far))
