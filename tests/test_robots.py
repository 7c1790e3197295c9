"""Robots by name: sizes known from the URDFs, root joints, errors."""

import pinocchio as pin
import pytest

from latentoc.robots import UnknownRobotError, example_robot_data_dir, load_robot, robot_names

# (nq, nv) of each robot as its URDF defines it (free-flyer adds 7 / 6)
KNOWN_SIZES = {"panda": (9, 9), "ur5": (6, 6), "talos": (39, 38), "human": (43, 42), "solo12": (19, 18)}


@pytest.mark.parametrize("name", sorted(KNOWN_SIZES))
def test_sizes_and_root_joint(name):
    model = load_robot(name)
    assert (model.nq, model.nv) == KNOWN_SIZES[name]
    has_ff = model.joints[1].shortname() == "JointModelFreeFlyer"
    assert has_ff == (model.nq == model.nv + 1)


def test_free_flyer_override():
    fixed = load_robot("talos", free_flyer=False)
    floating = load_robot("panda", free_flyer=True)
    assert (fixed.nq, fixed.nv) == (32, 32)
    assert (floating.nq, floating.nv) == (16, 15)


def test_every_listed_example_robot_has_its_urdf():
    root = example_robot_data_dir()
    assert (root / "panda_description").is_dir()
    for name in robot_names():
        if name not in ("cmu-humanoid", "human-arm"):
            assert isinstance(load_robot(name), pin.Model)


def test_own_human_models_by_name():
    assert load_robot("human-arm").nq == 7
    humanoid = load_robot("cmu-humanoid")
    assert humanoid.nq == 63 and humanoid.nv == 62


def test_unknown_robot_is_named():
    with pytest.raises(UnknownRobotError, match="unknown robot 'pandaa'.*panda"):
        load_robot("pandaa")
