"""The left/right mirror of a URDF robot from its joint names (issue 35), checked by forward
kinematics: every right body of the mirrored configuration is the reflection of its left partner."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.mocap.symmetry import MirrorError, SymmetryMap
from latentoc.robots.catalog import load_robot

S = np.diag([1.0, -1.0, 1.0])  # world sagittal reflection (y is left)


@pytest.fixture(scope="module", params=["g1", "talos"])
def robot(request):
    return request.param, load_robot(request.param)


def test_mirrored_configuration_puts_right_bodies_at_the_reflection_of_the_left(robot):
    name, model = robot
    sm = SymmetryMap.from_joint_names(model)
    assert sm.n_learned + len(sm.copied) == model.nq - 7
    rng = np.random.default_rng(3)
    d = model.createData()
    anti = [k for k, n in enumerate(sm.learned_names) if sm.centre_factor.get(n, 1.0) < 0]
    for _ in range(3):
        y = rng.uniform(-0.6, 0.6, sm.n_learned)
        y[anti] = 0.0  # a symmetric motion has none of the centre joints that flip
        base = np.array([0.1, 0.0, 0.8, *pin.Quaternion(pin.rpy.rpyToMatrix(0.0, 0.3, 0.0)).coeffs()])
        pin.framesForwardKinematics(model, d, sm.to_full(y, base))
        # every right joint's frame (it moves with all the joints above it, each with its factor)
        pairs = [(f.name, f.name.replace("right", "left")) for f in model.frames
                 if f.type == pin.FrameType.JOINT and "right" in f.name]
        assert len(pairs) == len(sm.copied)
        for right, left in pairs:
            R, L = d.oMf[model.getFrameId(right)], d.oMf[model.getFrameId(left)]
            assert np.allclose(R.translation, S @ L.translation, atol=2e-3), (name, right)
    # the mirror of a mirrored configuration is itself (left <-> right, centre flips)
    q = sm.to_full(y, base)
    assert np.allclose(sm.mirror(sm.mirror(q)), q)


def test_the_foot_soles_mirror_over_a_motion(robot):
    """Rotations too: each right foot's placement is the reflection of the left foot's at every pose."""
    name, model = robot
    sm = SymmetryMap.from_joint_names(model)
    foot = {"g1": ("left_ankle_roll_link", "right_ankle_roll_link"), "talos": ("leg_left_6_link", "leg_right_6_link")}[name]
    d = model.createData()
    q0 = sm.to_full(np.zeros(sm.n_learned), pin.neutral(model)[:7])
    pin.framesForwardKinematics(model, d, q0)
    C = (S @ d.oMf[model.getFrameId(foot[0])].rotation @ S).T @ d.oMf[model.getFrameId(foot[1])].rotation
    rng = np.random.default_rng(5)
    for _ in range(3):
        y = rng.uniform(-0.5, 0.5, sm.n_learned)
        y[[k for k, n in enumerate(sm.learned_names) if sm.centre_factor.get(n, 1.0) < 0]] = 0.0
        pin.framesForwardKinematics(model, d, sm.to_full(y, pin.neutral(model)[:7]))
        L, R = d.oMf[model.getFrameId(foot[0])], d.oMf[model.getFrameId(foot[1])]
        assert np.allclose(R.translation, S @ L.translation, atol=2e-3)
        assert np.allclose(R.rotation, S @ L.rotation @ S @ C, atol=1e-6)


def test_a_right_joint_whose_axis_is_not_the_mirror_is_refused_by_name():
    model = load_robot("g1")
    j = model.getJointId("right_knee_joint")
    M = model.jointPlacements[j]
    model.jointPlacements[j] = pin.SE3(pin.utils.rotate("z", 0.5) @ M.rotation, M.translation)
    with pytest.raises(MirrorError, match="right_knee_joint"):
        SymmetryMap.from_joint_names(model)


def test_a_joint_without_partner_is_refused_by_name():
    model = load_robot("g1")
    with pytest.raises(MirrorError, match="'left_hip_pitch_joint': no right partner"):
        SymmetryMap.from_joint_names(model, left="left_hip", right="right_knee")


def test_the_leg_of_a_foot_is_the_chain_of_joints_above_it():
    """The joints a planting may change (jump.cleaning.leg_joints): the G1's left leg, base to foot,
    found from the kinematic tree, against its joints named left_hip/knee/ankle."""
    from latentoc.jump.demonstration.planted import leg_joints

    model = load_robot("g1")
    leg = leg_joints(model, "left_ankle_roll_link")
    named = [model.names[j] for j in range(1, model.njoints) if model.names[j].startswith(("left_hip", "left_knee", "left_ankle"))]
    assert list(leg) == named and len(leg) == 6
