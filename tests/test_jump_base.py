"""Sagittal base -> free-flyer q, v, a against Pinocchio's Lie-group difference; the contact phases' anchored
bases (latentoc.jump.robot.JumpRobot.anchored, .rolling) against forward kinematics and finite differences."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.jump.base import base_to_freeflyer, freeflyer_to_base


def test_velocity_and_acceleration_match_finite_differences():
    m = pin.Model()
    m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "ff")
    t = np.linspace(0, 1, 2001)
    h = t[1] - t[0]
    b = np.column_stack([np.sin(2 * t), 1 + 0.3 * t ** 2, 0.7 * np.cos(3 * t)])
    bd = np.column_stack([2 * np.cos(2 * t), 0.6 * t, -2.1 * np.sin(3 * t)])
    bdd = np.column_stack([-4 * np.sin(2 * t), 0.6 + 0 * t, -6.3 * np.cos(3 * t)])
    q, v, a = base_to_freeflyer(b, bd, bdd)
    for k in (200, 1000, 1800):
        assert np.allclose(v[k], pin.difference(m, q[k - 1], q[k + 1]) / (2 * h), atol=1e-5)
        assert np.allclose(a[k], (v[k + 1] - v[k - 1]) / (2 * h), atol=1e-4)
    assert np.allclose(freeflyer_to_base(q), b)
    assert np.allclose(q[:, [1, 3, 5]], 0.0)  # symmetric: no lateral position, roll, yaw


# ------------------------------------------------------------------ the anchored base of the contact phases
def _smooth_motion(jump_parts):
    """The GP layer's joint motion along the training fit's latent path, and the times between its
    breakpoints (the path is a polynomial there, so central differences in time hold to rounding)."""
    from jump_reference import joint_motion

    from latentoc.spline import BSpline

    js = jump_parts.js
    spline = BSpline(len(js.init["P"]), js.phases.duration)
    bp = spline.breakpoints
    t = 0.5 * (bp[1:] + bp[:-1])
    return (lambda s: joint_motion(jump_parts.layer, spline, js.init["P"], s)), t


def _base(fn, *args):
    """(b, bd, bdd) of a casadi base Function as numpy vectors."""
    return [np.asarray(u, float).ravel() for u in fn(*args)]


def test_anchored_bases_lay_their_body_flat_on_its_ground_point(jump_parts):
    """At poses along the whole motion (numeric forward kinematics of the full state, Pinocchio):
    robot.anchored("foot") puts the ball on (x_pin - ball_back, 0) and the heel at z = 0;
    robot.anchored("toes") the toe point on (x_pin, 0) and the pad at z = 0; robot.rolling the toe
    point on (x_pin, 0) at the given pitch; each to 1e-9 m. The pitch of each flat body is the one
    that levels its two points (jump_reference.levelling_pitch)."""
    from jump_reference import foot_points, full_state, levelling_pitch

    js, robot = jump_parts.js, jump_parts.robot
    model, data = js.model, js.model.createData()
    motion, _ = _smooth_motion(jump_parts)
    t = np.linspace(0.0, js.phases.duration, 9)
    Y, Yd, Ydd = motion(t)
    heel, ball, toe, pad = range(4)
    rng = np.random.default_rng(7)
    for k in range(len(t)):
        y, yd, ydd = Y[k], Yd[k], Ydd[k]
        x_pin, p = rng.uniform(-0.5, 1.0), rng.uniform(-0.6, 0.6)
        for anchor, front, back, ground in (("foot", ball, heel, x_pin - js.geom.ball_back), ("toes", toe, pad, x_pin)):
            b, bd, bdd = _base(robot.anchored(anchor), y, yd, ydd, x_pin)
            P = foot_points(model, data, full_state(js.smap, b, bd, bdd, y, yd, ydd)[0], js.geom)
            np.testing.assert_allclose(P[[0, 2], front], [ground, 0.0], atol=1e-9)
            np.testing.assert_allclose(P[2, back], 0.0, atol=1e-9)
            assert b[2] == pytest.approx(levelling_pitch(model, data, js.smap, y, front, back, js.geom), abs=1e-12)
        b, bd, bdd = _base(robot.rolling, y, yd, ydd, x_pin, p, 0.3, -2.0)
        P = foot_points(model, data, full_state(js.smap, b, bd, bdd, y, yd, ydd)[0], js.geom)
        np.testing.assert_allclose(P[[0, 2], toe], [x_pin, 0.0], atol=1e-9)
        assert b[2] == p and bd[2] == 0.3 and bdd[2] == -2.0


def test_anchored_base_rates_are_time_derivatives_along_a_smooth_joint_motion(jump_parts):
    """bd and bdd of robot.anchored (both anchors) and robot.rolling equal fourth-order central
    differences in time of b and bd along the GP layer's joint motion (and, rolling, along the pitch
    p(t) = 0.2 sin(7 t) with its derivatives), between the path's breakpoints; the rolling base's
    toe point has no velocity (numeric Pinocchio frame velocities of the full state), and neither
    have a flat body's front point nor its back point's height."""
    from finite_differences import central4
    from jump_reference import full_state, point_velocities

    js, robot = jump_parts.js, jump_parts.robot
    model, data = js.model, js.model.createData()
    motion, times = _smooth_motion(jump_parts)

    def pitch(s):
        return 0.2 * np.sin(7 * s), 1.4 * np.cos(7 * s), -9.8 * np.sin(7 * s)

    def rolling(s):
        y, yd, ydd = (u[0] for u in motion(s))
        return _base(robot.rolling, y, yd, ydd, 0.4, *pitch(s[0]))

    bases = {a: (lambda s, a=a: _base(robot.anchored(a), *(u[0] for u in motion(s)), 0.4)) for a in ("foot", "toes")}
    bases["rolling"] = rolling
    stuck = {"foot": [(1, [0, 2]), (0, [2])], "toes": [(2, [0, 2]), (3, [2])], "rolling": [(2, [0, 2])]}
    for name, fn in bases.items():
        for s in times[::3]:
            b, bd, bdd = fn(np.array([s]))
            h = np.array([1.0])
            scale = max(1.0, np.abs(bd).max())
            np.testing.assert_allclose(central4(lambda u: fn(u)[0], np.array([s]), h, 1e-4), bd, atol=1e-8 * scale)
            np.testing.assert_allclose(central4(lambda u: fn(u)[1], np.array([s]), h, 1e-4), bdd,
                                       atol=1e-7 * max(1.0, np.abs(bdd).max()))
            y, yd, ydd = (u[0] for u in motion(np.array([s])))
            V = point_velocities(model, data, *full_state(js.smap, b, bd, bdd, y, yd, ydd)[:2], js.geom)
            for k, axes in stuck[name]:
                np.testing.assert_allclose(V[axes, k], 0.0, atol=1e-9 * max(1.0, np.abs(yd).max()))


def test_both_anchors_give_the_standing_base_in_the_standing_pose(jump_parts):
    """In the (planted) training jump's first, standing frame every foot point is on the ground and
    the toe point at x = 0: the base on the flat foot and the base on the flat toes (x_pin = 0) are
    both the training base, to 1e-9; ball_back is the ball's distance behind the toe point there."""
    from jump_reference import foot_points

    js, robot = jump_parts.js, jump_parts.robot
    tr = js.training
    data = js.model.createData()
    P = foot_points(js.model, data, tr.Q[0], js.geom)
    np.testing.assert_allclose(P[2], 0.0, atol=1e-9)
    np.testing.assert_allclose(P[0, 2], 0.0, atol=1e-9)
    assert js.geom.ball_back == pytest.approx(P[0, 2] - P[0, 1], abs=1e-12)
    y, z = tr.Y[0], np.zeros_like(tr.Y[0])
    for anchor in ("foot", "toes"):
        np.testing.assert_allclose(_base(robot.anchored(anchor), y, z, z, 0.0)[0], tr.base[0], atol=1e-9)
    k = js.smap.learned_names.index("ltoes_rx")
    assert robot.hinge == k and js.init["hinge_standing"] == tr.Y[0, k]
