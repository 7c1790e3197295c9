"""Foot contact points and pyramid forces against numeric Pinocchio."""
import casadi as ca
import numpy as np
import pinocchio as pin
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

from latentoc.dynamics import SymbolicModel
from latentoc.jump.robot.feet import point_forces
from latentoc.jump.demonstration.training import training_jumps
from latentoc.robots.cmu_humanoid import symmetric_model


def test_pyramid_forces_are_unilateral_and_in_the_cone():
    rng = np.random.default_rng(1)
    for _ in range(20):
        lam = rng.uniform(0, 100, 8)
        for fx, fz in point_forces(lam, 0.4):
            assert fz >= 0 and abs(fx) <= 0.4 * fz + 1e-12


def test_point_forces_act_on_their_own_bodies():
    """Symbolic sum J^T f (heel, ball on the foot, toe and pad on the toes, right foot mirrored) equals
    numeric Pinocchio: rnea with the same forces as external forces on the joints' bodies."""
    from latentoc.jump.robot.feet import generator_columns, point_generalized_force, point_jacobians

    model, smap = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    sym = SymbolicModel(model)
    d = model.createData()
    rng = np.random.default_rng(5)
    q = tr.Q[40]
    lam = rng.uniform(0, 200, 8)
    fs = point_forces(lam, 0.4)
    gen_sym = np.array(point_generalized_force(sym, geom, ca.DM(q), fs)).ravel()
    # reference: external point forces through rnea (f_ext in each joint's local frame)
    pin.framesForwardKinematics(model, d, q)
    M = d.oMf[model.getFrameId("lfoot")]
    T = d.oMf[model.getFrameId("ltoes_end")]
    left = [M.translation + M.rotation @ geom.heel_offset, d.oMf[model.getFrameId("lfoot_end")].translation,
            T.translation, T.translation + T.rotation @ geom.pad_offset]
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    for side in "lr":
        for k, frame in enumerate(("lfoot", "lfoot_end", "ltoes_end", "ltoes_end")):
            j = model.frames[model.getFrameId(side + frame[1:])].parentJoint
            p = left[k] * ([1, 1, 1] if side == "l" else [1, -1, 1])
            f_world = pin.Force(np.array([fs[k][0], 0.0, fs[k][1]]), np.cross(p, [fs[k][0], 0.0, fs[k][1]]))
            fext[j] += d.oMi[j].actInv(f_world)
    z = np.zeros(model.nv)
    ref = pin.rnea(model, d, q, z, z) - pin.rnea(model, d, q, z, z, fext)
    assert np.allclose(gen_sym, ref, atol=1e-9 * np.abs(ref).max())
    num = generator_columns(point_jacobians(model, d, q, geom), 0.4) @ lam
    assert np.allclose(num, ref, atol=1e-9 * np.abs(ref).max())


def test_numeric_foot_points_match_the_symbolic_ones():
    from latentoc.jump.robot.feet import foot_points, points_function

    model, _ = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    sym_points = points_function(SymbolicModel(model), geom)
    d = model.createData()
    for i in (0, 40, 90):
        pin.framesForwardKinematics(model, d, tr.Q[i])
        assert np.allclose(foot_points(model, d, geom), np.array(sym_points(tr.Q[i])), atol=1e-12)


def test_the_pad_lies_behind_the_toe_tip_on_the_ground_when_standing():
    from latentoc.jump.robot.feet import foot_points

    model, _ = symmetric_model()
    q = training_jumps()[0].Q[0]
    geom = CMU_HUMANOID.geometry(model, q)
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    heel, ball, toe, pad = foot_points(model, d, geom).T
    np.testing.assert_allclose(pad - toe, [-0.01, 0.0, min(ball[2], toe[2]) - toe[2]], atol=1e-12)
    assert heel[0] < ball[0] < pad[0] < toe[0]
