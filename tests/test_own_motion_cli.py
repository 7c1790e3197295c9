"""`learn` and `solve` on the user's files: what learn writes (against the GPDM it saved), and every bad input
as `latentoc: error: ...` naming the file, exit code 2, nothing written."""
import json
import re
from pathlib import Path

import numpy as np
import pytest

from latentoc.cli.parser import main
from latentoc.gpdm import GPDM
from latentoc.robots import example_robot_data_dir

UR5 = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
CMU = Path(__file__).resolve().parents[1] / "robots" / "cmu"
UR5_URDF = example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf"


def reach_csv(path: Path, n: int = 41, T: float = 2.0, names: list[str] = UR5, edit=None) -> Path:
    """A UR5 reach (minimum-jerk blend plus a detour) as the CSV a user would write; ``edit(rows)``
    changes the text rows (header first) before writing."""
    t = np.linspace(0.0, T, n)
    u = t / T
    s, b = 10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5, 64 * u ** 3 * (1 - u) ** 3
    q0, q1 = np.array([0.0, -1.8, 1.6, -1.4, -1.57, 0.0]), np.array([1.2, -1.0, 1.0, -1.6, -1.2, 0.8])
    Q = q0 + np.outer(s, q1 - q0) + np.outer(b, [0.3, -0.4, 0.5, 0.3, 0.3, -0.4])
    rows = [",".join(["t", *names])] + [",".join(f"{v:.12g}" for v in (ti, *qi[:len(names)])) for ti, qi in zip(t, Q)]
    if edit is not None:
        edit(rows)
    path.write_text("\n".join(rows) + "\n")
    return path


def test_learn_writes_the_model_its_error_and_tube(tmp_path, capsys):
    f = reach_csv(tmp_path / "reach.csv")
    out = tmp_path / "learned"
    assert main(["learn", str(f), "--robot", "ur5", "--latent-dim", "2", "--stride", "2", "--out", str(out),
                 "--plots"]) == 0
    printed = capsys.readouterr().out
    assert "41 frames at 20 Hz (2 s) of 6 joints" in printed
    summary = json.loads((out / "learn.json").read_text())
    assert "  per joint: " + ", ".join(f"{n} {e:.3g}" for n, e in summary["reconstruction_rmse_per_joint"].items()) \
        in printed.splitlines()
    gp = GPDM.load(out / "gpdm.npz")
    assert gp.latent_dim == 2 and gp.X.shape == (21, 2) and summary["learned_frames"] == 21
    assert np.array_equal(gp.Y, np.loadtxt(f, delimiter=",", skiprows=1)[::2, 1:])
    rms = np.sqrt(np.mean((gp.mean(gp.X) - gp.Y) ** 2, axis=0))
    assert summary["reconstruction_rmse_per_joint"] == pytest.approx(dict(zip(UR5, rms)), rel=1e-9)
    assert summary["tube_training"] == pytest.approx(gp.tube_size(), rel=1e-12)
    assert summary["demonstration"]["joints"] == UR5 and summary["robot"] == "ur5"
    assert sorted(p.name for p in out.iterdir()) == ["gpdm.npz", "latent_tube.png", "learn.json", "reconstruction.png",
                                                      "variance.png"]


def test_learn_from_a_urdf_path_and_an_amc(tmp_path):
    f = reach_csv(tmp_path / "reach.csv")
    assert main(["learn", str(f), "--robot", str(UR5_URDF), "--out", str(tmp_path / "a")]) == 0
    assert json.loads((tmp_path / "a" / "learn.json").read_text())["robot"] == str(UR5_URDF)
    assert main(["learn", str(CMU / "01_01.amc"), "--asf", str(CMU / "01.asf"), "--robot", "human-arm", "--start",
                 "0", "--stop", "120", "--stride", "4", "--clip", "--out", str(tmp_path / "b")]) == 0
    assert json.loads((tmp_path / "b" / "learn.json").read_text())["demonstration"]["frames"] == 120


def _drop_t(rows):
    rows[:] = [r.split(",", 1)[1] for r in rows]


def _swap(i, j):
    def edit(rows):
        rows[i], rows[j] = rows[j], rows[i]
    return edit


def _value(row, col, text):
    def edit(rows):
        cells = rows[row].split(",")
        cells[col] = text
        rows[row] = ",".join(cells)
    return edit


BAD_LEARN = [
    ("unknown", dict(names=["shoulder_pan_joint", "elbow", "wrist"]),
     r"unknown joint names 'elbow', 'wrist'; the robot 'ur5' has the joints shoulder_pan_joint, "),
    ("no-t", dict(edit=_drop_t), r"the header has no column 't' \(time, s\)"),
    ("order", dict(edit=_swap(5, 6)), r"line 7: time t = 0.2 s does not increase \(previous sample t = 0.25 s\)"),
    ("nan", dict(edit=_value(3, 1, "nan")), r"line 4, column 'shoulder_pan_joint': NaN"),
    ("inf", dict(edit=_value(7, 3, "-inf")), r"line 8, column 'elbow_joint': Inf"),
    ("limits", dict(edit=_value(9, 2, "7.0")), r"leaves the joint limits of 'ur5': 'shoulder_lift_joint' by 0.7168 "
                                               r"above its upper limit 6.28319 at t = 0.4 s \(line 10\).*--clip"),
    ("few", dict(n=4), r"4 frames are too few for a GPDM of latent dimension 3: it needs at least d \+ 2 = 5"),
]


@pytest.mark.parametrize("label, kw, match", BAD_LEARN, ids=[b[0] for b in BAD_LEARN])
def test_bad_motion_files_exit_2_naming_the_file_and_write_nothing(tmp_path, capsys, label, kw, match):
    f = reach_csv(tmp_path / f"{label}.csv", **kw)
    out = tmp_path / "out"
    assert main(["learn", str(f), "--robot", "ur5", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"latentoc: error: {f}") and len(err.splitlines()) == 1
    assert re.search(match, err), err
    assert not out.exists()


def test_a_motion_outside_the_limits_is_clipped_on_request(tmp_path, capsys):
    f = reach_csv(tmp_path / "m.csv", edit=_value(9, 2, "7.0"))
    assert main(["learn", str(f), "--robot", "ur5", "--out", str(tmp_path / "out"), "--clip"]) == 0
    assert "clipped {'shoulder_lift_joint': 0.716" in capsys.readouterr().out


def test_bad_robots_and_missing_files(tmp_path, capsys):
    f = reach_csv(tmp_path / "m.csv")
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint")
    out = tmp_path / "out"
    cases = [(["learn", str(f), "--robot", str(bad)], f"latentoc: error: URDF {bad} is not valid XML"),
             (["learn", str(f), "--robot", str(tmp_path / "none.urdf")],
              f"latentoc: error: URDF {tmp_path / 'none.urdf'} does not exist"),
             (["learn", str(tmp_path / "none.csv"), "--robot", "ur5"],
              f"latentoc: error: motion file {tmp_path / 'none.csv'} does not exist"),
             (["learn", str(f), "--robot", "r2d2"], "latentoc: error: unknown robot 'r2d2'"),
             (["solve", "arm-raise-small", "--gpdm", str(tmp_path / "none.npz")],
              f"latentoc: error: GPDM file {tmp_path / 'none.npz'} does not exist")]
    for args, message in cases:
        assert main([*args, "--out", str(out)]) == 2
        assert capsys.readouterr().err.startswith(message)
        assert not out.exists()


def problem_file(tmp_path: Path, robot: str = '"ur5"', training: str = '{ file = "m.csv" }', extra: str = "") -> Path:
    p = tmp_path / f"p{len(list(tmp_path.glob('p*.toml')))}.toml"
    p.write_text(f'kind = "latent-min-torque"\nrobot = {robot}\ntraining = {training}\n{extra}')
    return p


def test_bad_problem_files_exit_2_naming_the_file(tmp_path, capsys):
    reach_csv(tmp_path / "m.csv")
    reach_csv(tmp_path / "u.csv", names=["t0", *UR5[1:]])
    (tmp_path / "bad.urdf").write_text("<robot name='x'><link name='a'/></robot>")
    out = tmp_path / "out"
    cases = [
        (problem_file(tmp_path, training='{ file = "gone.csv" }'),
         f"key 'training': file {tmp_path / 'gone.csv'} does not exist"),
        (problem_file(tmp_path, robot='{ urdf = "gone.urdf" }'), f"key 'robot': file {tmp_path / 'gone.urdf'} does not"),
        (problem_file(tmp_path, robot='{ urdf = "bad.urdf" }'), f"URDF {tmp_path / 'bad.urdf'} has no movable joint"),
        (problem_file(tmp_path, training='{ file = "u.csv" }'), f"{tmp_path / 'u.csv'}: unknown joint name 't0'"),
        (problem_file(tmp_path, training='{ file = "m.csv", colour = 1 }'), "key 'training' must be one of"),
        (problem_file(tmp_path, extra="[goal]\nframe = \"tool0\"\n"), "[goal] needs both 'goal.frame' and"),
        (problem_file(tmp_path, extra="[goal]\nframe = \"hand\"\nposition = [0, 0, 1]\n"),
         "goal frame 'hand' is not a frame of ur5; its frames: universe, "),
        (problem_file(tmp_path, robot=f'{{ urdf = "{UR5_URDF}", free_flyer = true }}'),
         "the robot's free-flyer root 'root_joint' cannot be locked at a pose; use a fixed-base robot"),
        (problem_file(tmp_path, extra="[latent]\ndim = 6\n"), "d = 6 must satisfy 1 <= d < D = 6"),
        (problem_file(tmp_path, extra="[gpdm]\ntraining_stride = 20\n"), "3 frames (every 20th of 41) are too few"),
    ]
    for path, message in cases:
        assert main(["solve", str(path), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("latentoc: error: ") and message in err, err
        assert not out.exists()
