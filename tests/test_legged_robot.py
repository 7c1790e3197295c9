"""The contact kind's robot from a problem file's ``[robot]`` (latentoc.jump.robot.robot_declaration): the CMU
humanoid and the Unitree G1 built from their declarations, the G1's contact rows against numeric
Pinocchio, and bad declarations refused with the key named."""
import tomllib
from pathlib import Path

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.errors import ProblemError
from latentoc.jump.closure.planted_legs import LegClosure
from latentoc.jump.robot.feet import foot_points, point_forces
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID, declaration, robot_model
from latentoc.jump.problem import SCHEMA
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.rows.contact import block
from latentoc.jump.robot.torque_limits import urdf_torque_limits
from latentoc.jump.robot.zmp import G

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
    from latentoc.problem.toml_files import load_problem

    p = load_problem("broad-jump")
    assert declaration(p.settings) == CMU_HUMANOID
    assert declaration(SCHEMA.parse({}, "empty")) == CMU_HUMANOID


def test_g1_contact_rows_from_its_declaration_against_numeric_pinocchio():
    """The G1 (one foot body, four sole points) through the same contact block as the CMU humanoid:
    base rows = (rnea - sum J^T f) / weight with the forces as external forces in numeric rnea, the
    joint torques and the sole points' heights against numeric frame placements, the sole planted
    by the closure."""
    decl = _declared(G1_ROBOT)
    model, smap = robot_model(decl)
    assert smap.n_learned == 16  # the left leg (6), the waist (3) and the left arm (7)
    q0 = _standing(model, decl)
    geom = decl.geometry(model, q0)
    assert geom.side_frame("r", "left_ankle_roll_link") == "right_ankle_roll_link"
    np.testing.assert_allclose(geom.footprint[2], 0.0, atol=1e-9)  # all four sole points on the ground
    mass = sum(i.mass for i in model.inertias)
    sym = SymbolicModel(model)
    closure = LegClosure.of(sym, smap, geom, q0)
    robot = JumpRobot(sym, smap, geom, urdf_torque_limits(model), 0.6, mass, closure=closure)
    blk = block(robot, 3)
    rng = np.random.default_rng(3)
    y, yd, ydd = (smap.to_learned(q0) + rng.normal(0, 0.1, smap.n_learned), rng.normal(0, 1.0, smap.n_learned),
                  rng.normal(0, 5.0, smap.n_learned))
    lam = rng.uniform(0, 0.2, 8)
    shift = 0.05
    F = np.array(blk.rows_sx(y, yd, ydd, np.concatenate([[shift, 0.0], lam]))).ravel()
    # numeric reference: the closed legs on the planted base (latentoc.jump.closure.planted_legs, tested on its own),
    # rnea with the point forces as external forces
    yc, ydc, yddc, b, bd, bdd = (u[0] for u in closure.evaluate(y[None], yd[None], ydd[None], [0.0], [shift]))
    q, v, a = (np.array(ca.evalf(x)).ravel() for x in robot.configuration(b, bd, bdd, yc, ydc, yddc))
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
    np.testing.assert_allclose(F[blk.layout["height"]], left[:, 2], atol=1e-12)  # the planted sole: on the ground
    np.testing.assert_allclose(left[:, 2], 0.0, atol=1e-10)
    np.testing.assert_allclose(left[2, 0], geom.footprint[0, 2] + shift, atol=1e-10)
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
    sunk = _declared(G1_ROBOT.replace("[-0.05, 0.0, -0.03]", "[-0.05, 0.0, -0.04]"))  # the heel 1 cm lower
    with pytest.raises(ProblemError, match=r"robot\.foot.*on the ground; ball 10\.0 mm, toe 10\.0 mm, pad 10\.0 mm"):
        sunk.geometry(g1, _standing(g1, _declared(G1_ROBOT)))
    with pytest.raises(ProblemError, match=r"robot\.foot"):  # the feet's points not all declared
        _declared(G1_ROBOT.split("[robot.foot]")[0] + '[robot.foot]\nheel = { frame = "left_ankle_roll_link" }\n')
    with pytest.raises(ProblemError, match=r"robot\.mirror"):  # the mirror's strings do not name the joints
        robot_model(_declared(G1_ROBOT.replace('mirror = ["left", "right"]', 'mirror = ["L_", "R_"]')))
    with pytest.raises(ProblemError, match=r"robot\.model.*fixed base"):
        robot_model(_declared(G1_ROBOT.replace('model = "g1"', 'model = "panda"')))
    cmu, _ = robot_model(CMU_HUMANOID)
    with pytest.raises(ProblemError, match=r"robot\.limits.*effort"):  # the CMU skeleton has none of its own
        urdf_torque_limits(cmu)


def _g1_problem():
    from latentoc.problem.toml_files import load_problem

    return load_problem("problems/g1-broad-jump.toml")


def test_g1_training_from_its_retargeted_demonstration():
    """problems/g1-broad-jump.toml's motion as the symmetric training: ground and toe tip at 0 standing,
    the sole's four points on the ground within 1 mm, the right foot the left's mirror image, and
    the phases where numeric forward kinematics puts the toe tip (down until takeoff, then up; back
    at touchdown)."""
    from pathlib import Path

    from latentoc.jump.schedule.phases import toe_heights, training_phases
    from latentoc.jump.demonstration.training import motion_training

    p = _g1_problem()
    decl = declaration(p.settings)
    model, smap = robot_model(decl)
    tr = motion_training(Path("problems") / decl.motion, model, smap, decl)
    assert tr.Y.shape == (157, 16) and abs(tr.duration - 1.3) < 1e-9
    geom = decl.geometry(model, tr.Q[0])
    d = model.createData()
    pin.framesForwardKinematics(model, d, tr.Q[0])
    left = foot_points(model, d, geom)
    right = np.column_stack([d.oMf[model.getFrameId(c.frame)].act(c.offset) for c in geom.right_points])
    np.testing.assert_allclose(right, left * np.array([[1.0], [-1.0], [1.0]]), atol=1e-9)
    assert np.abs(left[2]).max() < 1e-3 and abs(left[2].min()) < 1e-12 and abs(left[0, 2]) < 1e-12
    ph = training_phases(model, tr, geom)
    z = toe_heights(model, tr.Q, geom)
    i_to, i_td = (int(np.argmin(np.abs(tr.t - x))) for x in (ph.takeoff, ph.touchdown))
    assert z[:i_to + 1].max() < 0.005 and np.all(np.diff(z[i_to:i_to + 12]) > 0)
    assert z[i_td] <= z[0] + 1e-9 < z[i_td - 1]
    assert 0 < ph.heel_off <= ph.ball_off <= ph.takeoff < ph.touchdown <= ph.ball_strike <= ph.heel_strike


def test_bad_g1_problem_inputs_are_refused_by_name(tmp_path):
    from latentoc.jump.problem import setup
    from latentoc.motions.readers import MotionFileError

    decl = declaration(_g1_problem().settings)
    with pytest.raises(ProblemError, match=r"robot\.motion"):  # a robot other than the CMU humanoid needs one
        setup(robot=dataclasses_replace(decl, motion=""))
    np.savez(tmp_path / "short.npz", t=np.arange(20) / 120.0, q=np.zeros((20, 30)))
    with pytest.raises(MotionFileError, match=r"short\.npz.*36 columns"):
        setup(robot=dataclasses_replace(decl, motion="short.npz"), base_dir=tmp_path)
    with pytest.raises(ProblemError, match=r"training_jumps"):
        setup("all", robot=decl, base_dir=Path("problems"))


def dataclasses_replace(decl, **kw):
    import dataclasses

    return dataclasses.replace(decl, **kw)


def test_g1_joint_bounds_hold_every_urdf_limit_of_both_legs_and_arms():
    """The learned coordinates' bounds (a right joint's limits mirrored onto its left partner) against
    the URDF's XML: the full configurations at the lower and the upper bounds are inside every joint's
    <limit lower upper>, each bound is some joint's limit (tight), and the velocity bound is the
    smaller of the two partners' <limit velocity>."""
    from xml.etree import ElementTree

    from latentoc.robots.catalog import robot_urdf

    decl = _declared(G1_ROBOT)
    model, smap = robot_model(decl)
    robot = JumpRobot(SymbolicModel(model), smap, decl.geometry(model, _standing(model, decl)),
                      urdf_torque_limits(model), 0.4, 35.0, joint_limits=True)
    xml = {j.get("name"): j.find("limit") for j in ElementTree.parse(robot_urdf("g1")).iter("joint")
           if j.find("limit") is not None}
    lo, hi, vmax = robot.joint_bounds
    base = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    for y in (lo, hi):
        q = smap.to_full(y[None], base[None])[0]
        for j in range(2, model.njoints):
            lim = xml[model.names[j]]
            assert float(lim.get("lower")) - 1e-12 <= q[model.joints[j].idx_q] <= float(lim.get("upper")) + 1e-12
    for k, name in enumerate(smap.learned_names):
        partner = name.replace("left", "right")
        limits = {float(xml[n].get(b)) * s for n in {name, partner} for b in ("lower", "upper") for s in (1, -1)}
        assert min(abs(lo[k] - v) for v in limits) < 1e-12 and min(abs(hi[k] - v) for v in limits) < 1e-12
        assert vmax[k] == min(float(xml[n].get("velocity")) for n in {name, partner})
    assert robot.has_joint_limits and not dataclasses_replace(robot, joint_limits=False).has_joint_limits


def test_joint_limit_excess_is_the_worst_overshoot_of_the_recorded_limits():
    from latentoc.jump.check.verify import joint_limit_excess

    q = np.array([[0, 0, 0, 0, 0, 0, 1, 0.5, -0.2], [0, 0, 0, 0, 0, 0, 1, 1.3, -0.1]])
    v = np.array([[0, 0, 0, 0, 0, 0, 2.0, 0.0], [0, 0, 0, 0, 0, 0, -3.5, 1.0]])
    inf = np.inf
    arrays = {"q": q, "v": v, "q_min": np.array([-inf] * 7 + [-1.0, -0.15]), "q_max": np.array([inf] * 7 + [1.0, 1.0]),
              "v_max": np.array([inf] * 6 + [3.0, inf])}
    pos, vel = joint_limit_excess(arrays)
    assert pos == pytest.approx(0.3) and vel == pytest.approx(0.5)
    assert joint_limit_excess({"q": q, "v": v}) == (0.0, 0.0)  # no limits recorded: none held


def _g1_smap():
    return robot_model(declaration(_g1_problem().settings))[1]


def _g1_training():
    from latentoc.jump.demonstration.training import motion_training

    decl = declaration(_g1_problem().settings)
    model, smap = robot_model(decl)
    tr = motion_training(Path("problems") / decl.motion, model, smap, decl)
    return model, tr, decl.geometry(model, tr.Q[0])


def test_a_declared_schedule_replaces_the_detected_times_and_settles_after_its_touchdown():
    from latentoc.jump.schedule.phases import training_phases

    model, tr, geom = _g1_training()
    detected = training_phases(model, tr, geom)
    ph = training_phases(model, tr, geom, declared={"heel_off": 0.2, "takeoff": 0.29, "touchdown": 0.75})
    assert (ph.heel_off, ph.takeoff, ph.touchdown) == (0.2, 0.29, 0.75)
    assert ph.heel_off < ph.ball_off <= ph.takeoff and ph.heel_strike == detected.heel_strike  # the rest re-detected
    assert ph.settle >= ph.touchdown and ph.duration == detected.duration


@pytest.mark.parametrize("declared, key", [({"takeoff": 0.8}, "takeoff"), ({"heel_off": 0.3, "ball_off": 0.25}, "ball_off"),
                                           ({"touchdown": 0.2}, "touchdown"), ({"heel_strike": 1.5}, "heel_strike")])
def test_a_schedule_out_of_order_is_refused_naming_its_key(declared, key):
    from latentoc.jump.schedule.phases import training_phases

    model, tr, geom = _g1_training()
    with pytest.raises(ProblemError, match=rf"schedule\.{key}"):
        training_phases(model, tr, geom, declared=declared)


def test_planting_a_rigid_sole_holds_it_flat_then_pivots_it_on_its_toe_tip():
    """The G1's symmetric demonstration slides its feet 24 mm sideways (the base's sway projected
    away); planted (latentoc.jump.demonstration.planted, a rigid sole: no hinge) every sole point stays at its
    standing place while the heel is loaded and the toe tip alone while the foot pivots, by numeric
    forward kinematics; only the left leg's joints and the sagittal base change."""
    from latentoc.jump.demonstration.planted import foot_bodies, planted_training
    from latentoc.jump.schedule.phases import training_phases

    model, tr, geom = _g1_training()
    assert foot_bodies(model, geom) == ("left_ankle_roll_link", None)
    ph = training_phases(model, tr, geom, declared={"heel_off": 0.2, "ball_off": 0.2, "takeoff": 0.275})
    assert ph.pad_with_ball and not ph.loaded("pad", np.array([0.25]))[0] and ph.loaded("toe", np.array([0.25]))[0]
    pt = planted_training(model, _g1_smap(), tr, ph, geom)
    d = model.createData()
    P = []
    for q in pt.training.Q:
        pin.framesForwardKinematics(model, d, q)
        P.append(foot_points(model, d, geom))
    P = np.array(P)
    flat, pivot = tr.t <= 0.2 + 1e-9, (tr.t > 0.2 + 1e-9) & (tr.t <= 0.275 + 1e-9)
    assert np.abs(P[flat] - P[0]).max() < 1e-6
    assert np.abs(P[pivot, :, 2] - P[0, :, 2]).max() < 1e-6 and np.abs(P[pivot, 2, 0] - P[0, 2, 0]).max() > 0.01
    changed = np.flatnonzero(np.abs(pt.training.Y - tr.Y).max(axis=0) > 1e-9)
    smap = _g1_smap()
    assert {smap.learned_names[k] for k in changed} <= {n for n in smap.learned_names if n.startswith("left_") and
                                                        any(j in n for j in ("hip", "knee", "ankle"))}
