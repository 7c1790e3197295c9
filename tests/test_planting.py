"""Planted feet (latentoc.motions.planting, latentoc.jump.demonstration.planted): the planted frames sit exactly at
their targets, the other frames keep the capture, and each frame's change is the least one (its
weighted change lies in the row space of the constraint Jacobian: no move along the constraint's
null space makes it smaller)."""
from __future__ import annotations
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

import numpy as np
import pinocchio as pin
import pytest

from latentoc.motions.planting import Plant, PlantingError, plant, taper


@pytest.fixture(scope="module")
def captured():
    from latentoc.jump.demonstration.training import training_jumps
    from latentoc.robots.cmu_humanoid import symmetric_model

    model, smap = symmetric_model()
    return model, smap, training_jumps(0)[0]


def _leg_v(model):
    from latentoc.jump.demonstration.planted import leg_joints

    return np.array([model.joints[model.getJointId(n)].idx_v for n in leg_joints(model, "ltoes")])


def test_planted_frame_reaches_its_target_with_the_least_change(captured):
    model, _, tr = captured
    d = model.createData()
    Q = tr.Q[20:26]  # late stance: the captured toes moved
    pin.framesForwardKinematics(model, d, tr.Q[0])
    target = d.oMf[model.getFrameId("ltoes")].copy()
    free = _leg_v(model)
    on = np.array([True, True, False, True, True, True])
    Qp = plant(model, Q, free, [Plant("ltoes", target, on)])
    for i in range(len(Q)):
        pin.framesForwardKinematics(model, d, Qp[i])
        err = np.max(np.abs(pin.log6(target.actInv(d.oMf[model.getFrameId("ltoes")])).vector))
        if on[i]:
            assert err < 1e-9
            # least change: the change lies in the row space of the 6 x 7 constraint Jacobian
            pin.computeJointJacobians(model, d, Qp[i])
            J = pin.getFrameJacobian(model, d, model.getFrameId("ltoes"), pin.LOCAL)[:, free]
            dq = pin.difference(model, Q[i], Qp[i])[free]
            null = np.linalg.svd(J)[2][6:]  # the joints' moves that keep the frame
            assert np.max(np.abs(null @ dq)) < 1e-6 * max(1.0, np.linalg.norm(dq))
            assert np.linalg.norm(dq) > 1e-4  # the capture did move there
        else:
            np.testing.assert_array_equal(Qp[i], Q[i])
    untouched = np.setdiff1d(np.arange(model.nv), free)
    for i in range(len(Q)):
        np.testing.assert_allclose(pin.difference(model, Q[i], Qp[i])[untouched], 0.0, atol=1e-12)


def test_point_plant_holds_only_the_point(captured):
    model, _, tr = captured
    d = model.createData()
    fid = model.getFrameId("ltoes")
    pin.framesForwardKinematics(model, d, tr.Q[0])
    local = np.array([0.06, 0.0, -0.01])
    goal = d.oMf[fid].act(local) + np.array([0.004, -0.003, 0.002])
    Qp = plant(model, tr.Q[:1], _leg_v(model), [Plant("ltoes", pin.SE3(np.eye(3), goal), np.array([True]), local)])
    pin.framesForwardKinematics(model, d, Qp[0])
    np.testing.assert_allclose(d.oMf[fid].act(local), goal, atol=1e-9)


def test_unreachable_plant_is_refused(captured):
    model, _, tr = captured
    target = pin.SE3(np.eye(3), np.array([0.0, 0.2, -3.0]))  # three metres under the floor
    with pytest.raises(PlantingError, match="cannot be reached"):
        plant(model, tr.Q[:1], _leg_v(model), [Plant("ltoes", target, np.array([True]))])


def test_taper_fades_smoothly_to_zero():
    t = np.linspace(0.0, 0.2, 21)
    on = t <= 0.1
    delta = np.where(on, 1.0, 0.0)[:, None]
    out = taper(delta, on, t, 0.05)[:, 0]
    np.testing.assert_array_equal(out[on], 1.0)
    assert np.all(np.diff(out[~on]) <= 0) and out[t >= 0.15].max() == 0.0
    assert 0.0 < out[11] < 1.0


def test_cleaned_training_keeps_the_feet_on_their_ground_points():
    """The planted training jump (what the GPDM learns): in every contact frame the toe and pad
    points (the toes flat) are on their standing (or landing) ground points to 1e-9 m, also while
    the captured toes rolled on their tip; while the heel is loaded the heel too."""
    from latentoc.jump.demonstration.planted import planted_training
    from latentoc.jump.robot.feet import POINTS, foot_points
    from latentoc.jump.schedule.phases import training_phases
    from latentoc.jump.demonstration.training import training_jumps
    from latentoc.robots.cmu_humanoid import symmetric_model

    model, smap = symmetric_model()
    tr = training_jumps(0)[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    ph = training_phases(model, tr, geom)
    pt = planted_training(model, smap, tr, ph, geom)
    d = model.createData()
    P = []
    for q in pt.training.Q:
        pin.framesForwardKinematics(model, d, q)
        P.append(foot_points(model, d, geom))
    P = np.array(P)  # n x 3 x 4
    t = tr.t
    heel, toe, pad = (POINTS.index(k) for k in ("heel", "toe", "pad"))
    assert ((t > ph.ball_off + 1e-9) & (t <= ph.takeoff)).any()  # the captured toes roll on their tip before the takeoff
    for phase in (t <= ph.takeoff + 1e-9, t >= ph.touchdown - 1e-9):
        ref = P[np.flatnonzero(phase)[0]]
        for k in (toe, pad):
            np.testing.assert_allclose(P[phase, :, k], np.broadcast_to(ref[:, k], P[phase, :, k].shape), atol=1e-9)
        np.testing.assert_allclose(P[phase, 2, pad], 0.0, atol=1e-9)  # the toes flat on the ground
        flat = phase & ph.flat(t)
        np.testing.assert_allclose(P[flat, 2, heel], 0.0, atol=1e-9)
    assert set(pt.change_deg) == {"lfemur_rz", "lfemur_ry", "lfemur_rx", "ltibia_rx", "lfoot_rz", "lfoot_rx", "ltoes_rx"}
