"""The user's own robot (latentoc.robots): a URDF by path equals the same robot by name, mesh-less URDFs,
ASF skeleton chains, the problem file's robot table, and bad files as RobotFileError naming the file."""
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from latentoc.robots.human_arm import build_human_arm
from latentoc.robots.human_models import skeleton_chain
from latentoc.robots import (ROBOT, RobotFileError, example_robot_data_dir, load_robot, load_urdf,
                             robot_from_setting)

CMU = Path(__file__).resolve().parents[1] / "robots" / "cmu"

MESHLESS = """<?xml version="1.0"?>
<robot name="two_link">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0 0 0.25"/><mass value="2.0"/>
      <inertia ixx="0.05" ixy="0" ixz="0" iyy="0.05" iyz="0" izz="0.01"/></inertial>
    <visual><geometry><mesh filename="package://nowhere/upper.stl"/></geometry></visual>
  </link>
  <link name="lower">
    <inertial><origin xyz="0 0 0.2"/><mass value="1.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.005"/></inertial>
  </link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="40" velocity="3"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/>
    <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="20" velocity="4"/></joint>
</robot>
"""


def same_dynamics(a: pin.Model, b: pin.Model, seed: int = 0) -> None:
    """Equal sizes, names, limits, and RNEA and frame placements at random states."""
    assert (a.nq, a.nv, a.njoints, a.nframes) == (b.nq, b.nv, b.njoints, b.nframes)
    assert list(a.names) == list(b.names) and [f.name for f in a.frames] == [f.name for f in b.frames]
    for attr in ("lowerPositionLimit", "upperPositionLimit", "velocityLimit", "effortLimit"):
        assert np.array_equal(getattr(a, attr), getattr(b, attr))
    rng = np.random.default_rng(seed)
    da, db = a.createData(), b.createData()
    for _ in range(5):
        q, v, acc = pin.randomConfiguration(a), rng.normal(size=a.nv), rng.normal(size=a.nv)
        assert np.array_equal(pin.rnea(a, da, q, v, acc), pin.rnea(b, db, q, v, acc))
        pin.framesForwardKinematics(a, da, q)
        pin.framesForwardKinematics(b, db, q)
        assert all(np.array_equal(x.homogeneous, y.homogeneous) for x, y in zip(da.oMf, db.oMf))


@pytest.mark.parametrize("name, path", [("ur5", "ur_description/urdf/ur5_robot.urdf"),
                                        ("panda", "panda_description/urdf/panda.urdf")])
def test_a_urdf_by_path_is_the_robot_by_name(tmp_path, name, path):
    urdf = example_robot_data_dir() / path
    same_dynamics(load_urdf(urdf), load_robot(name))
    (tmp_path / "p.toml").write_text("")
    setting = ROBOT({"urdf": str(urdf)})
    assert setting == {"urdf": str(urdf), "free_flyer": False, "package_dirs": []}
    same_dynamics(robot_from_setting(setting, tmp_path), load_robot(name))
    packaged = ROBOT({"urdf": f"package://{path}", "package_dirs": [str(example_robot_data_dir())]})
    same_dynamics(robot_from_setting(packaged, tmp_path), load_robot(name))


def test_a_meshless_urdf_relative_to_the_problem_file(tmp_path):
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "arm.urdf").write_text(MESHLESS)
    model = robot_from_setting(ROBOT({"urdf": "robots/arm.urdf"}), tmp_path)
    assert list(model.names) == ["universe", "shoulder", "elbow"] and model.nq == 2
    assert np.array_equal(model.effortLimit, [40, 20]) and np.array_equal(model.velocityLimit, [3, 4])
    # the arm held out along +x (rotated +90 deg about y): gravity's moment about y is +m g x at each COM,
    # so the shoulder holds it with -g (2.0 * 0.25 + 1.0 * 0.7)
    tau = pin.rnea(model, model.createData(), np.array([np.pi / 2, 0.0]), np.zeros(2), np.zeros(2))
    assert tau[0] == pytest.approx(-9.81 * (2.0 * 0.25 + 1.0 * 0.7), rel=1e-12)
    floating = robot_from_setting(ROBOT({"urdf": "robots/arm.urdf", "free_flyer": True}), tmp_path)
    assert (floating.nq, floating.nv) == (9, 8)


def test_an_asf_chain_is_the_human_arm_up_to_its_masses():
    chain = skeleton_chain(CMU / "01.asf", ["lhumerus", "lradius", "lwrist", "lhand"], mass=63.86)
    arm = build_human_arm()
    assert list(chain.names) == list(arm.names)
    assert np.array_equal(chain.lowerPositionLimit, arm.lowerPositionLimit)
    q = np.linspace(-0.5, 0.5, 7)
    tips = []
    for model in (chain, arm):
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        tips.append(data.oMf[model.getFrameId("lhand_end")].translation.copy())
    assert np.allclose(tips[0], tips[1], atol=1e-12)
    assert 0 < sum(i.mass for i in chain.inertias) < 0.1 * 63.86


BAD_URDFS = [
    ("<robot name='x'><link name='a'/><joint", "is not valid XML"),
    ("<sdf version='1.6'/>", "the root element is <sdf>"),
    ("<robot name='x'><link name='a'/></robot>", "has no movable joint"),
    ("<robot name='x'><link name='a'/><link name='b'/><joint name='j' type='spin'><parent link='a'/>"
     "<child link='b'/></joint></robot>", "does not parse"),
]


@pytest.mark.parametrize("text, match", BAD_URDFS)
def test_a_bad_urdf_names_the_file(tmp_path, text, match):
    f = tmp_path / "bad.urdf"
    f.write_text(text)
    with pytest.raises(RobotFileError, match=match) as err:
        load_urdf(f)
    assert str(f) in str(err.value)


def test_missing_files_and_bad_tables(tmp_path):
    with pytest.raises(RobotFileError, match=f"URDF {tmp_path / 'no.urdf'} does not exist"):
        robot_from_setting(ROBOT({"urdf": "no.urdf"}), tmp_path)
    with pytest.raises(RobotFileError, match="package://x/a.urdf: not found under the package_dirs"):
        load_urdf("package://x/a.urdf", package_dirs=[tmp_path])
    with pytest.raises(RobotFileError, match="no.asf does not exist"):
        robot_from_setting(ROBOT({"asf": "no.asf", "bones": ["lhumerus"]}), tmp_path)
    with pytest.raises(RobotFileError, match="no bone 'lwing'"):
        skeleton_chain(CMU / "01.asf", ["lhumerus", "lwing"])
    for bad in ({"urdf": ""}, {"urdf": "a.urdf", "mass": 1}, {"asf": "a.asf"}, {"asf": "a.asf", "bones": ["x"],
                "mass": -1}, {"urdf": "a.urdf", "free_flyer": "no"}, "r2d2", 3):
        with pytest.raises(ValueError, match="must be one of 'cmu-humanoid'.*'panda'.*urdf"):
            ROBOT(bad)
