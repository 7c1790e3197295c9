"""The planted foot by construction (latentoc.jump.closure.planted_legs): the closed legs and the planted base put
the planted body at its ground pose with zero velocity and acceleration, checked with numeric
Pinocchio (frame placement, velocity and spatial acceleration) on the CMU humanoid and the G1, and the
closure's velocities and accelerations against finite differences of its positions."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.dynamics import SymbolicModel
from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.closure.planted_legs import LegClosure
from latentoc.latent.spline import BSpline


def _motion(closure: LegClosure, Y, Yd, Ydd, held, shift):
    """Numeric q, v, a of the closed legs on the planted base, and the closed learned coordinates."""
    yc, ydc, yddc, b, bd, bdd = closure.evaluate(Y, Yd, Ydd, held, shift)
    q7, v6, a6 = base_to_freeflyer(b, bd, bdd)
    E = closure.E
    return np.hstack([q7, yc @ E.T]), np.hstack([v6, ydc @ E.T]), np.hstack([a6, yddc @ E.T]), yc


def _planted_body(model, q, v, a, frame):
    """World placement, LOCAL_WORLD_ALIGNED velocity and LOCAL spatial acceleration of ``frame``."""
    d = model.createData()
    fid = model.getFrameId(frame)
    out = []
    for qi, vi, ai in zip(q, v, a):
        pin.forwardKinematics(model, d, qi, vi, ai)
        pin.updateFramePlacements(model, d)
        out.append((d.oMf[fid].copy(), pin.getFrameVelocity(model, d, fid, pin.LOCAL_WORLD_ALIGNED).vector,
                    pin.getFrameAcceleration(model, d, fid, pin.LOCAL).vector))
    return out


def _path(Y: np.ndarray, t: np.ndarray, n_control: int = 12):
    """A smooth joint path through the frames Y at times t: (t, Y, Yd, Ydd) of its least-squares spline."""
    sp = BSpline(n_control, float(t[-1] - t[0]))
    P = sp.fit(t - t[0], Y)
    tt = np.linspace(0.0, sp.duration, 41)[1:-1]
    return tt, *(sp.evaluate(P, tt, k) for k in range(3))


@pytest.fixture(scope="module")
def cmu(jump_setup):
    js = jump_setup
    return js, LegClosure.of(js.sym, js.smap, js.geom, js.training.Q[0])


def test_cmu_closure_names_the_out_of_plane_joints_and_the_toe_hinge(cmu):
    js, cl = cmu
    names = [js.smap.learned_names[k] for k in cl.dependent]
    assert sorted(names) == ["lfemur_ry", "lfemur_rz", "lfoot_rz"]
    assert cl.anchor == "ltoes" and js.smap.learned_names[cl.hinge] == "ltoes_rx"


@pytest.mark.parametrize("held", [0.0, 1.0])
def test_cmu_planted_toes_hold_their_ground_pose_with_zero_velocity_and_acceleration(cmu, held):
    """Over the captured stance's legs, perturbed sideways by up to 0.1 rad, the closed legs on the planted
    base put the toes at the standing pose moved 0.3 m forward, still (numeric Pinocchio)."""
    js, cl = cmu
    tr = js.training
    stance = tr.t <= js.phases.takeoff
    t, Y, Yd, Ydd = _path(tr.Y[stance], tr.t[stance])
    Y = Y.copy()
    Y[:, cl.dependent] += 0.1 * np.sin(np.outer(np.arange(len(t)), [1.0, 2.0, 3.0]))
    K = len(t)
    q, v, a, yc = _motion(cl, Y, Yd, Ydd, np.full(K, held), np.full(K, 0.3))
    target = pin.SE3(cl.R_ground, cl.p_ground + np.array([0.3, 0.0, 0.0]))
    for M, vel, acc in _planted_body(js.model, q, v, a, cl.anchor):
        assert np.max(np.abs(pin.log6(target.actInv(M)).vector)) < 1e-10
        assert np.max(np.abs(vel)) < 1e-9
        assert np.max(np.abs(acc)) < 1e-8
    if held:
        np.testing.assert_allclose(yc[:, cl.hinge], cl.hinge_standing, atol=1e-15)
    others = np.setdiff1d(np.arange(cl.n), np.concatenate([cl.dependent, [cl.hinge] if held else []]).astype(int))
    np.testing.assert_array_equal(yc[:, others], Y[:, others])  # only the dependent (and held) joints change


def test_closure_velocity_and_acceleration_are_the_time_derivatives_of_its_positions(cmu):
    """yd and ydd of the closed legs (implicit-function theorem) against central differences of the
    closed positions along a flight path, where the GP mean's feet turn sideways."""
    js, cl = cmu
    sp = BSpline(12, 0.4)
    tr = js.training
    fl = (tr.t >= js.phases.takeoff) & (tr.t <= js.phases.takeoff + 0.4)
    P = sp.fit(tr.t[fl] - tr.t[fl][0], tr.Y[fl])
    h, tt = 1e-5, np.linspace(0.05, 0.35, 7)
    Yt = [sp.evaluate(P, tt + s, k) for s in (-h, 0.0, h) for k in range(3)]
    K = len(tt)
    closed = [cl.evaluate(Yt[3 * i], Yt[3 * i + 1], Yt[3 * i + 2], np.zeros(K), np.zeros(K)) for i in range(3)]
    ym, y0, yp = (c[0] for c in closed)
    np.testing.assert_allclose(closed[1][1], (yp - ym) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(closed[1][2], (yp - 2 * y0 + ym) / h ** 2, atol=2e-3 * max(1.0, np.abs(closed[1][2]).max()))
    assert np.degrees(np.abs(y0 - Yt[1]).max()) > 1.0  # the closure did change the flight's legs


def test_g1_sole_held_flat_by_its_hip_roll_yaw_and_ankle_roll():
    """The G1 (a rigid sole, no hinge): its dependent joints and the planted sole's pose, still, for
    sideways-perturbed crouching legs."""
    from latentoc.jump.robot.robot_declaration import robot_model
    from tests.test_legged_robot import G1_ROBOT, _declared, _standing

    decl = _declared(G1_ROBOT)
    model, smap = robot_model(decl)
    q0 = _standing(model, decl)
    cl = LegClosure.of(SymbolicModel(model), smap, decl.geometry(model, q0), q0)
    names = sorted(smap.learned_names[k] for k in cl.dependent)
    assert names == ["left_ankle_roll_joint", "left_hip_roll_joint", "left_hip_yaw_joint"] and cl.hinge is None
    y0 = smap.to_learned(q0)
    leg = [smap.learned_names.index(f"left_{j}_joint") for j in ("hip_pitch", "knee", "ankle_pitch")]
    K = 9
    s = np.linspace(0.0, 1.0, K)[:, None]
    Y = np.tile(y0, (K, 1))
    Y[:, leg] += s * np.array([-0.6, 1.0, -0.5])
    Y[:, cl.dependent] += 0.08 * np.sin(7 * s)
    Yd = np.tile([0.0] * len(y0), (K, 1))
    Yd[:, leg] = [-1.2, 2.0, -1.0]
    Ydd = np.zeros_like(Y)
    Ydd[:, leg] = [3.0, -4.0, 1.0]
    q, v, a, _ = _motion(cl, Y, Yd, Ydd, np.zeros(K), np.full(K, -0.2))
    target = pin.SE3(cl.R_ground, cl.p_ground + np.array([-0.2, 0.0, 0.0]))
    for M, vel, acc in _planted_body(model, q, v, a, cl.anchor):
        assert np.max(np.abs(pin.log6(target.actInv(M)).vector)) < 1e-10
        assert np.max(np.abs(vel)) < 1e-9 and np.max(np.abs(acc)) < 1e-8
