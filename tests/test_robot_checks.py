"""Bad robot physics is refused (issue 29): a URDF's NaN, negative or infinite mass, an inertia that
is not positive semi-definite or breaks the triangle inequality, limits with lower > upper, each a
RobotFileError naming the file and the link or joint; continuous joints take one angle each."""
import numpy as np
import pinocchio as pin
import pytest
from test_own_robot import MESHLESS

from latentoc.cli.parser import main
from latentoc.motions import demonstration_from_file
from latentoc.robots import RobotFileError, continuous_as_revolute, example_robot_data_dir, load_robot, load_urdf

UPPER_INERTIA = '<inertia ixx="0.05" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.01"/>'
SHOULDER_LIMIT = '<limit lower="-2" upper="2" effort="40" velocity="3"/>'


def _urdf(tmp_path, old, new):
    assert old in MESHLESS
    path = tmp_path / "r.urdf"
    path.write_text(MESHLESS.replace(old, new, 1))
    return path


@pytest.mark.parametrize("old, new, match", [
    ('<mass value="2.0"/>', '<mass value="nan"/>', "link 'upper': mass value='nan' is not a finite number"),
    ('<mass value="2.0"/>', '<mass value="inf"/>', "link 'upper': mass value='inf' is not a finite number"),
    ('<mass value="2.0"/>', '<mass value="heavy"/>', "link 'upper': mass value='heavy' is not a finite number"),
    ('<mass value="2.0"/>', '<mass value="-2.0"/>', "link 'upper': mass -2 is not a finite number >= 0"),
    (UPPER_INERTIA, UPPER_INERTIA.replace('iyy="0.05"', 'iyy="-0.05"'), "link 'upper': the inertia is not positive"),
    (UPPER_INERTIA, UPPER_INERTIA.replace('ixy="0"', 'ixy="0.2"'), "link 'upper': the inertia is not positive"),
    (UPPER_INERTIA, UPPER_INERTIA.replace('izz="0.01"', 'izz="0.2"'), "link 'upper': the principal moments .* "
                                                                      "break the triangle inequality"),
    (UPPER_INERTIA, UPPER_INERTIA.replace('ixz="0"', 'ixz="nan"'), "link 'upper': inertia ixz='nan' is not"),
    (SHOULDER_LIMIT, SHOULDER_LIMIT.replace('lower="-2"', 'lower="3"'),
     "joint 'shoulder': limit lower=3 is above upper=2"),
    (SHOULDER_LIMIT, SHOULDER_LIMIT.replace('upper="2"', 'upper="nan"'), "joint 'shoulder': limit upper='nan'"),
    (SHOULDER_LIMIT, SHOULDER_LIMIT.replace('effort="40"', 'effort="-40"'), "joint 'shoulder': limit effort=-40"),
])
def test_bad_physics_is_a_robot_file_error_naming_the_file_and_link(tmp_path, old, new, match):
    path = _urdf(tmp_path, old, new)
    with pytest.raises(RobotFileError, match=match) as err:
        load_urdf(path)
    assert str(path) in str(err.value)


def test_nan_mass_through_the_cli_exits_2_and_writes_nothing(tmp_path, capsys):
    """pinocchio reads mass="nan" as 0 and the motion solved "successfully" with it."""
    path = _urdf(tmp_path, '<mass value="2.0"/>', '<mass value="nan"/>')
    csv = tmp_path / "m.csv"
    csv.write_text("t,shoulder,elbow\n" + "".join(f"{i / 10},{0.1 * i},{0.05 * i}\n" for i in range(10)))
    assert main(["learn", str(csv), "--robot", str(path), "--latent-dim", "1", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("latentoc: error: URDF") and "link 'upper': mass value='nan'" in err
    assert not (tmp_path / "o").exists()


def test_good_urdfs_and_massless_links_pass(tmp_path):
    load_urdf(_urdf(tmp_path, "<link name=\"base\"/>", '<link name="base"><inertial><mass value="0"/>'
                                                      '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>'
                                                      "</inertial></link>"))
    for path in ("ur_description/urdf/ur5_robot.urdf", "panda_description/urdf/panda.urdf",
                 "kinova_description/robots/kinova.urdf"):
        load_urdf(example_robot_data_dir() / path)


def test_continuous_joints_take_one_angle_each():
    """The kinova arm's continuous joints (pinocchio: cos and sin) become revolute joints of the same
    axis with unbounded limits: the same RNEA and frames at the same angles."""
    kinova = load_robot("kinova")
    assert (kinova.nq, kinova.nv) == (9, 6)
    m = continuous_as_revolute(kinova)
    assert (m.nq, m.nv) == (6, 6) and list(m.names) == list(kinova.names)
    assert np.isinf(m.lowerPositionLimit[[0, 3, 5]]).all() and np.isinf(m.upperPositionLimit[[0, 3, 5]]).all()
    assert m.lowerPositionLimit[1] == kinova.lowerPositionLimit[2]
    rng = np.random.default_rng(1)
    da, db = kinova.createData(), m.createData()
    for _ in range(3):
        th, v, a = rng.uniform(-3, 3, 6), rng.normal(size=6), rng.normal(size=6)
        q = np.concatenate([[np.cos(th[j]), np.sin(th[j])] if kinova.joints[j + 1].nq == 2 else [th[j]]
                            for j in range(6)])
        np.testing.assert_allclose(pin.rnea(m, db, th, v, a), pin.rnea(kinova, da, q, v, a), atol=1e-12)
        pin.framesForwardKinematics(kinova, da, q)
        pin.framesForwardKinematics(m, db, th)
        assert all(np.allclose(x.homogeneous, y.homogeneous, atol=1e-12) for x, y in zip(da.oMf, db.oMf))
    assert continuous_as_revolute(load_robot("ur5")) is not None


def test_a_csv_of_the_kinova_arm_has_one_angle_per_joint(tmp_path):
    """Before: "unknown joint names 'j2s6s200_joint_1', ...; the robot 'kinova' has the joints"."""
    names = [f"j2s6s200_joint_{i}" for i in range(1, 7)]
    t = np.linspace(0, 1, 11)
    Q = np.column_stack([0.1 * t + 1.5 + 0.1 * i for i in range(6)])  # joints 2, 3, 5 within their limits
    Q[:, 0] = np.linspace(-4.0, 4.0, 11)  # a continuous joint beyond +-pi: no limit
    (tmp_path / "k.csv").write_text("t," + ",".join(names) + "\n" + "".join(
        f"{ti}," + ",".join(map(str, q)) + "\n" for ti, q in zip(t, Q)))
    demo = demonstration_from_file(tmp_path / "k.csv", load_robot("kinova"))
    assert demo.joint_names == names and demo.Q.shape == (11, 6) and demo.model.nq == 6
    np.testing.assert_array_equal(demo.Q, Q)
    np.savez(tmp_path / "k.npz", t=t, q=Q)  # no joint_names: the robot's configuration, one angle per joint
    np.testing.assert_array_equal(demonstration_from_file(tmp_path / "k.npz", load_robot("kinova")).Q, Q)
