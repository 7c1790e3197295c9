"""Motion files (latentoc.motions): CSV, NPZ and ASF + AMC on a robot, joint
order, locked joints, resampling, limits, and every bad input as a MotionFileError naming the file;
the CSV reader fuzzed (only latentoc's error type escapes)."""
import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from latentoc.errors import LatentocError
from latentoc.robots.human_arm import arm_trial
from latentoc.robots.human_models import cmu_configurations
from latentoc.motions.readers import MotionFileError, read_csv
from latentoc.motions import TRAINING, check_frames, demonstration_from_file, load_demonstration
from latentoc.robots import load_robot

CMU = Path(__file__).resolve().parents[1] / "robots" / "cmu"
UR5_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
              "wrist_3_joint"]


@pytest.fixture(scope="module")
def ur5():
    return load_robot("ur5")


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


def write_csv(path: Path, names: list[str], t: np.ndarray, Q: np.ndarray) -> Path:
    rows = [",".join(["t", *names])] + [",".join(repr(float(v)) for v in (ti, *qi)) for ti, qi in zip(t, Q)]
    path.write_text("\n".join(rows) + "\n")
    return path


def motion(n: int = 41, k: int = 6, T: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0.0, T, n)
    return t, 0.3 * np.sin(np.outer(t, np.arange(1, k + 1)) + np.arange(k))


def test_csv_columns_in_any_order_are_put_in_the_model_order(tmp_path, ur5):
    t, Q = motion()
    order = [3, 0, 5, 1, 4, 2]
    f = write_csv(tmp_path / "m.csv", [UR5_JOINTS[i] for i in order], t + 5.0, Q[:, order])
    demo = demonstration_from_file(f, ur5)
    assert demo.joint_names == UR5_JOINTS and not demo.locked and not demo.resampled
    assert np.array_equal(demo.Q, Q) and np.allclose(demo.t, t, atol=1e-12)  # time from 0
    assert demo.model is ur5 and demo.rate_hz == pytest.approx(20.0)


def test_npz_with_and_without_joint_names_equals_the_csv(tmp_path, ur5):
    t, Q = motion()
    a = demonstration_from_file(write_csv(tmp_path / "m.csv", UR5_JOINTS, t, Q), ur5)
    np.savez(tmp_path / "full.npz", t=t, q=Q)
    np.savez(tmp_path / "named.npz", t=t, q=Q[:, ::-1], joint_names=np.array(UR5_JOINTS[::-1]))
    for name in ("full.npz", "named.npz"):
        b = demonstration_from_file(tmp_path / name, ur5)
        assert b.joint_names == a.joint_names and np.array_equal(b.Q, a.Q) and np.array_equal(b.t, a.t)


def test_a_subset_locks_the_other_joints_at_fixed_pose_or_neutral(tmp_path, panda):
    t, Q = motion(k=7)
    Q += np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])  # inside panda_joint4's and _joint6's limits
    names = [f"panda_joint{i}" for i in range(1, 8)]
    f = write_csv(tmp_path / "m.csv", names, t, Q)
    demo = demonstration_from_file(f, panda, fixed_pose={"panda_finger_joint1": 0.03}, locked=["panda_finger_joint2"])
    assert demo.locked == {"panda_finger_joint1": [0.03], "panda_finger_joint2": [0.0]}
    assert demo.model.nq == 7 and list(demo.model.names[1:]) == names
    # the reduced model's torques are the full model's with the fingers held still at the locked pose
    q, v, a = Q[5], np.full(7, 0.3), np.full(7, -0.2)
    full = np.concatenate([q, [0.03, 0.0]]), np.concatenate([v, [0, 0]]), np.concatenate([a, [0, 0]])
    tau_full = pin.rnea(panda, panda.createData(), *full)
    assert np.allclose(pin.rnea(demo.model, demo.model.createData(), q, v, a), tau_full[:7], rtol=1e-12, atol=1e-12)


def test_non_uniform_time_is_resampled_at_the_median_rate_through_the_samples(tmp_path, ur5):
    t = np.cumsum(np.r_[0.0, np.full(20, 0.05), np.full(10, 0.1)])  # 20 Hz then 10 Hz
    Q = np.outer(t ** 3, np.ones(6)) * 0.1  # a cubic: the spline through it reproduces it
    demo = demonstration_from_file(write_csv(tmp_path / "m.csv", UR5_JOINTS, t, Q), ur5)
    assert demo.resampled and demo.rate_hz == pytest.approx(20.0)
    assert np.allclose(np.diff(demo.t), 0.05) and demo.t[-1] == pytest.approx(t[-1])
    assert np.allclose(demo.Q, 0.1 * np.outer(demo.t ** 3, np.ones(6)), atol=1e-12)
    again = demonstration_from_file(tmp_path / "m.csv", ur5, rate=40.0)
    assert again.rate_hz == pytest.approx(40.0) and len(again.t) == 81


def test_amc_frames_on_the_human_arm_are_the_cmu_configurations():
    arm = load_robot("human-arm")
    demo = demonstration_from_file(CMU / "01_01.amc", arm, asf=CMU / "01.asf", start=100, stop=160,
                                   clip_to_limits=True)
    humanoid = load_robot("cmu-humanoid")
    Q = cmu_configurations(humanoid, np.arange(100, 160))
    idx = [humanoid.joints[humanoid.getJointId(n)].idx_q for n in demo.joint_names]
    assert demo.joint_names == list(arm.names[1:]) and len(demo.t) == 60
    assert np.allclose(demo.Q, np.clip(Q[:, idx], arm.lowerPositionLimit, arm.upperPositionLimit))
    assert np.allclose(np.diff(demo.t), 1 / 120)


def test_registered_names_and_tables_load(tmp_path, ur5):
    demo = load_demonstration("human-arm-trial", load_robot("human-arm"))
    t, Q = arm_trial()
    assert np.array_equal(demo.Q, Q) and demo.joint_names[0] == "lhumerus_rz"
    t, Q = motion()
    write_csv(tmp_path / "m.csv", UR5_JOINTS, t, Q)
    table = TRAINING({"file": "m.csv", "rate": 10})
    assert table["rate"] == 10.0 and table["fixed_pose"] == {} and TRAINING(table) == table
    assert load_demonstration(table, ur5, tmp_path).rate_hz == pytest.approx(10.0)
    for bad in ({"file": "m.csv", "color": 1}, {"file": "m.csv", "rate": -1}, {"rate": 1}, "no-such-motion",
                {"file": "m.csv", "fixed_pose": {"a": "x"}}, {"file": "m.csv", "clip_to_limits": 1},
                {"file": "m.csv", "locked": [1]}, {"file": "m.csv", "locked": "panda_finger_joint1"}):
        with pytest.raises(ValueError, match="must be one of 'human-arm-trial'"):
            TRAINING(bad)


def test_clip_to_limits_clips_and_records_the_amount(tmp_path, panda):
    t, Q = motion(k=7)
    Q += np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])
    Q[10, 3] = 0.05  # panda_joint4's upper limit is -0.0698
    f = write_csv(tmp_path / "m.csv", [f"panda_joint{i}" for i in range(1, 8)], t, Q)
    demo = demonstration_from_file(f, panda, clip_to_limits=True, locked=["panda_finger_joint1", "panda_finger_joint2"])
    hi = panda.upperPositionLimit[3]
    assert demo.Q[10, 3] == hi and demo.clipped == {"panda_joint4": pytest.approx(0.05 - hi)}


BAD_CSV = [
    ("t,shoulder_pan_joint\n", "0 samples; a motion needs at least 2"),
    ("", "empty"),
    ("x,shoulder_pan_joint\n0,1\n1,2\n", "no column 't'"),
    ("t,t\n0,1\n", "appears twice"),
    ("t,shoulder_pan_joint\n0,1\n1\n", r"line 3: 1 values, the header has 2"),
    ("t,shoulder_pan_joint\n0,1\n0.1,abc\n", r"line 3, column 'shoulder_pan_joint': not a number: 'abc'"),
    ("t,shoulder_pan_joint\n0,1\n0.1,nan\n", r"line 3, column 'shoulder_pan_joint': NaN"),
    ("t,shoulder_pan_joint\n0,1\n0.1,inf\n", r"line 3, column 'shoulder_pan_joint': Inf"),
    ("t,shoulder_pan_joint\n0,1\ninf,1\n", r"line 3: time t = inf is not finite"),
    ("t,shoulder_pan_joint\n0,1\n0.2,1\n0.1,1\n", r"line 4: time t = 0.1 s does not increase"),
    ("t,shoulder_pan_joint\n0,1\n0,1\n", r"line 3: time t = 0 s does not increase"),
    ("t,elbow,wrist\n0,1,1\n1,1,1\n", r"unknown joint names 'elbow', 'wrist'; the robot 'ur5' has the joints "
                                      r"shoulder_pan_joint, shoulder_lift_joint, elbow_joint"),
    ("t,elbow_joint\n0,0\n1,3.5\n", r"leaves the joint limits of 'ur5': 'elbow_joint' by 0.3584 above its upper "
                                    r"limit 3.14159 at t = 1 s \(line 3\).*clip_to_limits = true"),
    ("t,shoulder_pan_joint\n0,1\n", "1 samples; a motion needs at least 2"),
    ("\ufefft,shoulder_pan_joint\n0,1e999\n1,0\n", r"line 2, column 'shoulder_pan_joint': Inf"),
    ("t,shoulder_pan_joint\n0,0\n1e-9,0\n2e-9,0\n1.1,0\n", r"1e\+09 Hz \(median step\).*times look like another unit than seconds"),
    ("t,shoulder_pan_joint\n0,0\n1e300,0\n2e300,0\n3.1e300,0\n", "times look like another unit than seconds"),
]


@pytest.mark.parametrize("text, match", BAD_CSV)
def test_bad_csv_is_an_error_naming_the_file(tmp_path, ur5, text, match):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    with pytest.raises(MotionFileError, match=match) as err:
        demonstration_from_file(f, ur5)
    assert str(f) in str(err.value)


def test_bad_files_of_every_kind(tmp_path, ur5, panda):
    with pytest.raises(MotionFileError, match=f"motion file {tmp_path / 'nope.csv'} does not exist"):
        demonstration_from_file(tmp_path / "nope.csv", ur5)
    (tmp_path / "m.txt").write_text("t\n")
    with pytest.raises(MotionFileError, match="unknown motion format 'txt'"):
        demonstration_from_file(tmp_path / "m.txt", ur5)
    (tmp_path / "m.npz").write_bytes(b"not a zip")
    with pytest.raises(MotionFileError, match="not a readable NPZ"):
        demonstration_from_file(tmp_path / "m.npz", ur5)
    np.savez(tmp_path / "q.npz", q=np.zeros((3, 6)))
    with pytest.raises(MotionFileError, match="no array 't'"):
        demonstration_from_file(tmp_path / "q.npz", ur5)
    np.savez(tmp_path / "n.npz", t=np.arange(3.0), q=np.zeros((3, 4)))
    with pytest.raises(MotionFileError, match="q has 4 columns, the robot 'ur5' has nq = 6"):
        demonstration_from_file(tmp_path / "n.npz", ur5)
    with pytest.raises(MotionFileError, match="needs its ASF skeleton"):
        demonstration_from_file(CMU / "01_01.amc", ur5)
    with pytest.raises(MotionFileError, match="moves none of the robot's joints"):
        demonstration_from_file(CMU / "01_01.amc", ur5, asf=CMU / "01.asf")
    t, Q = motion()
    f = write_csv(tmp_path / "m.csv", UR5_JOINTS, t, Q)
    with pytest.raises(MotionFileError, match="frame range start = 30, stop = 20 is empty"):
        demonstration_from_file(f, ur5, start=30, stop=20)
    with pytest.raises(MotionFileError, match="fixed_pose/locked name unknown joint 'gripper'"):
        demonstration_from_file(f, ur5, fixed_pose={"gripper": 0.0})
    g = write_csv(tmp_path / "p.csv", [f"panda_joint{i}" for i in (1, 2, 3, 5, 6, 7)], t, Q + [0, 0, 0, 0, 1.5, 0])
    with pytest.raises(MotionFileError, match="joint 'panda_joint4' is not in the file and its neutral value 0 is "
                                              "outside its limits"):
        demonstration_from_file(g, panda, locked=["panda_joint4", "panda_finger_joint1", "panda_finger_joint2"])


def test_too_few_frames_for_the_latent_dimension(tmp_path, ur5):
    t, Q = motion(n=9)
    demo = demonstration_from_file(write_csv(tmp_path / "m.csv", UR5_JOINTS, t, Q), ur5)
    check_frames(demo, 3)
    with pytest.raises(MotionFileError, match=r"m.csv: 3 frames \(every 4th of 9\) are too few for a GPDM of latent "
                                              r"dimension 3: it needs at least d \+ 2 = 5"):
        check_frames(demo, 3, stride=4)
    with pytest.raises(MotionFileError, match="latent dimension 6 must be below the motion's 6 joints"):
        check_frames(demo, 6)


CSV_TEXT = st.lists(st.sampled_from(list("t,0123456789.-e+naifNI \n\r\"#x_") + UR5_JOINTS[:2]), max_size=80).map("".join)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=CSV_TEXT, raw=st.binary(max_size=40))
def test_fuzzed_csv_raises_only_latentoc_errors(tmp_path, ur5, text, raw):
    f = tmp_path / "fuzz.csv"
    for content in (text.encode(), raw, ("t,shoulder_pan_joint\n0,0\n" + text).encode()):
        f.write_bytes(content)
        try:
            read_csv(f)
            demonstration_from_file(f, ur5, clip_to_limits=True)
        except LatentocError as exc:
            assert str(f) in str(exc)


@pytest.mark.parametrize("scale, unit", [(1000.0, "milliseconds"), (1e300, "another unit than seconds"),
                                         (1e-300, "another unit than seconds")])
def test_times_in_another_unit_are_refused_with_the_likely_cause(tmp_path, ur5, scale, unit):
    """t x 1000 (milliseconds) makes a 2 s motion last 2000 s and its grids millions of samples: a
    demonstration longer than 10 min or sampled above 100 kHz is refused naming the unit it looks like."""
    t, Q = motion()
    path = write_csv(tmp_path / "ms.csv", UR5_JOINTS, t * scale, Q)
    with pytest.raises(MotionFileError, match=f"ms.csv: .* s at .* Hz \\(median step\\).* times look like {unit}"):
        demonstration_from_file(path, ur5)
    assert demonstration_from_file(write_csv(tmp_path / "s.csv", UR5_JOINTS, t, Q), ur5).duration == pytest.approx(t[-1] - t[0])


def test_a_joint_without_a_column_must_be_declared(tmp_path, panda, capsys):
    """A missing column is refused, naming the joint and both ways to hold it; the CLI's --hold
    declares it (the same reduced model as fixed_pose and locked)."""
    from latentoc.cli.parser import main

    t, Q = motion(k=7)
    Q += np.array([0.0, 0.0, 0.0, -1.5, 0.0, 1.5, 0.0])
    f = write_csv(tmp_path / "m.csv", [f"panda_joint{i}" for i in range(1, 8)], t, Q)
    with pytest.raises(MotionFileError, match=r"no column for the robot's joint 'panda_finger_joint2'.*"
                                              r"fixed_pose = \{ panda_finger_joint2 = value \}.*--hold"):
        demonstration_from_file(f, panda, fixed_pose={"panda_finger_joint1": 0.03})
    with pytest.raises(MotionFileError, match="in both fixed_pose and locked"):
        demonstration_from_file(f, panda, fixed_pose={"panda_finger_joint1": 0.03},
                                locked=["panda_finger_joint1", "panda_finger_joint2"])
    out = tmp_path / "o"
    assert main(["learn", str(f), "--robot", "panda", "--out", str(out)]) == 2
    assert "panda_finger_joint1', 'panda_finger_joint2'" in capsys.readouterr().err and not out.exists()
    assert main(["learn", str(f), "--robot", "panda", "--hold", "panda_finger_joint1=0.03", "--hold",
                 "panda_finger_joint2", "--latent-dim", "2", "--out", str(out)]) == 0
    summary = json.loads((out / "learn.json").read_text())
    assert summary["demonstration"]["locked_joints"] == {"panda_finger_joint1": [0.03], "panda_finger_joint2": [0.0]}
