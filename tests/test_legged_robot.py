"""The contact kind's robot from a problem file's ``[robot]`` (latentoc.jump.legged_robot): the CMU
humanoid and the Unitree G1 built from their declarations, the G1's contact rows against numeric
Pinocchio, and bad declarations refused with the key named."""
import tomllib

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.errors import ProblemError
from latentoc.jump.contact import foot_points, point_forces
from latentoc.jump.legged_robot import CMU_HUMANOID, declaration, robot_model
from latentoc.jump.problem import SCHEMA
from latentoc.jump.robot import JumpRobot
from latentoc.jump.rows.contact import block
from latentoc.jump.torque_limits import urdf_torque_limits
from latentoc.jump.zmp import G

G1_ROBOT = """
[robot]
model = "g1"
mirror = ["left", "right"]
limits = "urdf"
[robot.foot]
heel = { frame = "left_ankle_roll_link", offset = [-0.05, 0.0, -0.03] }
ball = { frame = "left_ankle_roll_link", offset = [0.08, 0.0, -0.03] }
toe = { frame = "left_ankle_roll_link", offset = [0.12, 0.0, -0.03] }
pad = { frame = "left_ankle_roll_link", offset = [0.11, 0.0, -0.03] }
"""


def _declared(text: str):
    return declaration(SCHEMA.parse(tomllib.loads(text), "test.toml"))


def _standing(model: pin.Model, decl) -> np.ndarray:
    """The neutral pose lowered until the foot's lowest point touches z = 0."""
    q = pin.neutral(model)
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    q[2] -= foot_points(model, d, decl.geometry(model, q))[2].min()
    return q


def test_the_default_robot_is_the_cmu_humanoid_and_its_problem_file_declares_the_same():
    """problems/broad-jump.toml's [robot] is the built-in declaration (its points, mirror, limits)."""
    from latentoc.problem_files import load_problem

    p = load_problem("broad-jump")
    assert declaration(p.settings) == CMU_HUMANOID
    assert declaration(SCHEMA.parse({}, "empty")) == CMU_HUMANOID


def test_g1_contact_rows_from_its_declaration_against_numeric_pinocchio():
    """The G1 (one foot body, four sole points) through the same contact block as the CMU humanoid:
    base rows = (rnea - sum J^T f) / weight with the forces as external forces in numeric rnea, the
    joint torques, the toe tip's placement and the heel height against numeric frame placements."""
    decl = _declared(G1_ROBOT)
    model, smap = robot_model(decl)
    assert smap.n_learned == 16  # the left leg (6), the waist (3) and the left arm (7)
    q0 = _standing(model, decl)
    geom = decl.geometry(model, q0)
    assert geom.side_frame("r", "left_ankle_roll_link") == "right_ankle_roll_link"
    np.testing.assert_allclose(geom.footprint[2], 0.0, atol=1e-9)  # all four sole points on the ground
    mass = sum(i.mass for i in model.inertias)
    robot = JumpRobot(SymbolicModel(model), smap, geom, urdf_torque_limits(model), 0.6, mass)
    blk = block(robot, 3)
    rng = np.random.default_rng(3)
    y, yd, ydd = (rng.normal(0, s, smap.n_learned) for s in (0.2, 1.0, 5.0))
    b, bd, bdd = np.array([0.1, 0.02, 0.1]), rng.normal(0, 0.5, 3), rng.normal(0, 2.0, 3)
    lam = rng.uniform(0, 0.2, 8)
    x_pin = 0.05
    F = np.array(blk.rows_sx(y, yd, ydd, np.concatenate([b, bd, bdd, [x_pin], lam]))).ravel()
    # numeric reference: the full state, rnea with the point forces as external forces
    q, v, a = (np.array(ca.evalf(x)).ravel() for x in robot.configuration(b, bd, bdd, y, yd, ydd))
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    left = foot_points(model, d, geom).T
    W = mass * G
    fs = point_forces(lam * W, 0.6)
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for side in "lr":
        for k, c in enumerate(geom.points):
            j = model.frames[model.getFrameId(geom.side_frame(side, c.frame))].parentJoint
            p = left[k] * np.array([1.0, 1.0 if side == "l" else -1.0, 1.0])
            f = np.array([fs[k][0], 0.0, fs[k][1]])
            fext[j] += d.oMi[j].actInv(pin.Force(f, np.cross(p, f)))
    net = pin.rnea(model, d, q, v, a, fext)  # rnea - sum J^T f
    np.testing.assert_allclose(F[blk.layout["dynamics"]], net[[0, 2, 4]] / W, atol=1e-9)
    np.testing.assert_allclose(F[blk.layout["torque"]], net[6:][robot.active], atol=1e-8 * np.abs(net).max())
    np.testing.assert_allclose(F[blk.layout["toe_position"]], [left[2, 0] - x_pin, left[2, 2]], atol=1e-12)
    np.testing.assert_allclose(F[blk.layout["heel_height"]], left[0, 2], atol=1e-12)
    # the limits are the URDF's <limit effort>, read here from its XML
    from xml.etree import ElementTree

    from latentoc.robots.catalog import robot_urdf

    effort = {j.get("name"): float(j.find("limit").get("effort")) for j in ElementTree.parse(robot_urdf("g1")).iter("joint")
              if j.find("limit") is not None}
    for j in range(2, model.njoints):
        i = model.joints[j].idx_v - 6
        assert robot.limits.tau_max[i] == -robot.limits.tau_min[i] == effort[model.names[j]]


def test_bad_robot_declarations_are_refused_with_the_key_named():
    g1, _ = robot_model(_declared(G1_ROBOT))
    bad_frame = _declared(G1_ROBOT.replace('heel = { frame = "left_ankle_roll_link"', 'heel = { frame = "left_heel"'))
    with pytest.raises(ProblemError, match=r"robot\.foot\.heel.*'left_heel'"):
        bad_frame.geometry(g1, pin.neutral(g1))
    swapped = _declared(G1_ROBOT.replace("[0.08, 0.0, -0.03]", "[0.115, 0.0, -0.03]"))  # the ball before the pad
    with pytest.raises(ProblemError, match=r"robot\.foot.*heel, ball, pad, toe"):
        swapped.geometry(g1, pin.neutral(g1))
    with pytest.raises(ProblemError, match=r"robot\.foot"):  # the feet's points not all declared
        _declared(G1_ROBOT.split("[robot.foot]")[0] + '[robot.foot]\nheel = { frame = "left_ankle_roll_link" }\n')
    with pytest.raises(ProblemError, match=r"robot\.mirror"):  # the mirror's strings do not name the joints
        robot_model(_declared(G1_ROBOT.replace('mirror = ["left", "right"]', 'mirror = ["L_", "R_"]')))
    with pytest.raises(ProblemError, match=r"robot\.model.*fixed base"):
        robot_model(_declared(G1_ROBOT.replace('model = "g1"', 'model = "panda"')))
    cmu, _ = robot_model(CMU_HUMANOID)
    with pytest.raises(ProblemError, match=r"robot\.limits.*effort"):  # the CMU skeleton has none of its own
        urdf_torque_limits(cmu)
