"""The broad jump's row families (latentoc.jump.rows) against numeric Pinocchio.

Every row family is read from the assembled NLP (so the node inputs are checked with the
blocks) at the training start of a jump with few nodes: the joint motion of the GP layer along
the training fit's latent path, the contact phases' base anchored on the flat foot, the flat toes
or the rolling toes (robot.anchored and robot.rolling, themselves checked against forward
kinematics and finite differences in test_jump_base), the rolling pitch from the start's roll
splines. The flight samples are placed at times of the 1 kHz export of that start and checked on
its exported motion. References: ``pinocchio.rnea`` (with the point forces as external forces),
frame placements and Jacobians, the COM, the centroidal momentum and its rate, the mass matrix
(:mod:`jump_reference`).
"""
import dataclasses

import numpy as np
import pinocchio as pin
from scipy.integrate import cumulative_trapezoid

from finite_differences import central4
from jump_reference import (SAGITTAL, flight_base, foot_points, full_state, generalized_force, joint_motion,
                            levelling_pitch, mass_of, momentum, pitch_rate_for, point_forces, polygon_rows)
from latentoc.jump.base import base_to_freeflyer, freeflyer_to_base
from latentoc.jump.contact import TOE_PAD
from latentoc.jump.nlp import build_nlp
from latentoc.jump.zmp import G

GRAVITY = np.array([0.0, -9.81])
HEEL, BALL, TOE, PAD = range(4)


def family(jn, name: str) -> slice:
    """The rows of row family ``name`` in the NLP's constraint vector."""
    off = jn.nlp.row_offset[name]
    return slice(off, off + next(f.n_rows for f in jn.nlp.families if f.name == name))


def parts_of(g, names, part, n):
    """The rows named ``part`` in order, as (nodes x n)."""
    return g[names == part].reshape(-1, n)


def contact_mode(ph, t: float) -> str:
    """The contact mode at time t: "foot" (flat, the heel loaded), "rolling" (the toes on the toe
    point) or "toes" (flat)."""
    at = np.array([t])
    return "foot" if ph.flat(at)[0] else "rolling" if ph.pivot(at)[0] else "toes"


def ground_x(sj, x, t: float) -> float:
    """The toe point's ground point at contact time t of point x: 0 in the stance, x_L in the landing."""
    return 0.0 if t < sj.js.phases.touchdown - 1e-12 else float(sj.nlp.variables.unpack(x)["x_L"][0])


def ground_y_shift(sj, x, t: float) -> float:
    """The feet's sideways shift from their standing ground points at contact time t of point x: 0 in
    the stance, y_L in the landing."""
    return 0.0 if t < sj.js.phases.touchdown - 1e-12 else float(sj.nlp.variables.unpack(x)["y_L"][0])


def contact_base(sj, x, t: float):
    """(b, bd, bdd) of the anchored base at contact time t of point x (module doc)."""
    jn, robot = sj.nlp, sj.robot
    y, yd, ydd = (u[0] for u in joint_motion(sj.layer, jn.splines[0], jn.control_points(x), t))
    mode, x_pin = contact_mode(sj.js.phases, t), ground_x(sj, x, t)
    if mode == "rolling":
        out = robot.rolling(y, yd, ydd, x_pin, *jn.roll_pitch(x, np.array([t]))[0])
    else:
        out = robot.anchored(mode)(y, yd, ydd, x_pin)
    return [np.asarray(u, float).ravel() for u in out]


def state_at(sj, x, t: float):
    """Numeric q, v, a of a contact time of point x: the GP layer's joint motion and the anchored base."""
    y, yd, ydd = (u[0] for u in joint_motion(sj.layer, sj.nlp.splines[0], sj.nlp.control_points(x), t))
    return full_state(sj.js.smap, *contact_base(sj, x, t), y, yd, ydd)


def _contact_family_against_pinocchio(sj, family_name: str, times: np.ndarray, block: str) -> set[str]:
    """A contact family's rows (nodes or samples) at random edge weights against numeric Pinocchio,
    on the anchored base (whose loaded points are checked on their ground points here): base rows =
    rnea's minus sum J^T f (body weights), torques over their range, the loaded points' sideways
    offsets from their standing ground points (shifted by y_L in the landing), the unloaded points' heights (the
    heel's off the flat foot; the toe point's and the pad's on it; the heel's and the pad's while the
    toes roll), the centre of pressure on the ground in the loaded support (none while rolling), the COM
    in the feet's polygon once settled; with balanced edge weights the ZMP rows are the normal force
    times the polygon rows of the ZMP of the centroidal momentum rate on the ground. The nodes inside
    a rolling window carry no rows. Returns the contact modes checked."""
    model, js, robot = sj.js.model, sj.js, sj.robot
    data = model.createData()
    jn, ph, W = sj.nlp, js.phases, robot.weight
    K = len(times)
    act, scale = robot.active, robot.torque_scale
    lam = np.random.default_rng(0).uniform(0.0, 0.2, (K, 8)) * (jn.ubx[jn.variables.index(block)] > 0)
    x = np.array(sj.x0, float)
    x[jn.variables.index(block)] = lam
    x[jn.variables.index("y_L")] += 0.003  # not the start's: the landing's rows follow it
    sl = family(jn, family_name)
    g, names, times_r = jn.nlp.constraints(x)[sl], jn.row_names[sl], jn.row_times[sl]
    comps = jn.row_components[sl]
    lam_bal, states, modes = np.zeros((K, 8)), [], set()
    for k, t in enumerate(times):
        at = np.isclose(times_r, t, atol=1e-12)
        mode = contact_mode(ph, t)
        states.append(None)
        if mode == "rolling" and family_name == "contact":
            assert not at.any(), t  # the rolling toes' nodes: their samples hold the rows
            continue
        modes.add(mode)
        q, v, a = state_at(sj, x, t)
        states[k] = (q, v, a)
        heel, ball, toe, pad = P = foot_points(model, data, q, js.geom).T
        x_pin = ground_x(sj, x, t)
        if mode == "foot":  # the loaded points on their ground points
            np.testing.assert_allclose([ball[0], ball[2], heel[2]], [x_pin - js.geom.ball_back, 0.0, 0.0], atol=1e-9)
        else:
            np.testing.assert_allclose([toe[0], toe[2]], [x_pin, 0.0], atol=1e-9)
            if mode == "toes":
                assert abs(pad[2]) < 1e-9
        loaded = np.array([ph.loaded(p, np.array([t]))[0] for p in ("heel", "ball", "toe", "pad")])
        np.testing.assert_array_equal(comps[at & (names == "lateral")], np.flatnonzero(loaded))
        np.testing.assert_allclose(g[at & (names == "lateral")],
                                   P[loaded, 1] - js.geom.ground_y[loaded] - ground_y_shift(sj, x, t), atol=1e-10)
        tau = pin.rnea(model, data, q, v, a)
        gen = generalized_force(model, data, q, js.geom, point_forces(lam[k] * W, robot.mu))
        np.testing.assert_allclose(g[at & (names == "dynamics")], (tau - gen)[SAGITTAL] / W, atol=1e-9)
        tq = at & (names == "torque")
        tj = (tau - gen)[6:][act[comps[tq]]]
        np.testing.assert_allclose(g[tq], tj / scale[comps[tq]], atol=1e-9 * max(1.0, np.abs(tj).max(initial=0.0)))
        F = point_forces(lam[k] * W, robot.mu)
        my0 = sum(p[2] * f[0] - (p[0] - toe[0]) * f[1] for p, f in zip(P, F)) / W
        fz = F[:, 1].sum() / W
        heights = {"foot": {"toes_height": [toe[2], pad[2]]}, "toes": {"heel_height": [heel[2]]},
                   "rolling": {"heel_height": [heel[2]], "toes_height": [pad[2]]}}[mode]
        assert set(names[at]) & {"heel_height", "toes_height"} == set(heights)
        for part, z in heights.items():
            np.testing.assert_allclose(g[at & (names == part)], z, atol=1e-10)
        if mode == "rolling":
            np.testing.assert_array_equal(comps[at & (names == "toes_height")], [1])  # the pad
            assert not np.isin(names[at], ["cop_front", "cop_front_ball", "cop_heel", "cop_ball", "cop_pad"]).any()
        else:
            front = ("cop_front_ball", my0 - (toe[0] - ball[0]) * fz) if mode == "foot" else ("cop_front", my0)
            assert set(names[at]) & {"cop_front", "cop_front_ball"} == {front[0]}
            np.testing.assert_allclose(g[at & (names == front[0])], front[1], atol=1e-10)
            back = g[at & np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
            rear = heel[0] if ph.loaded("heel", np.array([t]))[0] else ball[0] if ph.loaded("ball", np.array([t]))[0] \
                else toe[0] - TOE_PAD
            np.testing.assert_allclose(back, (toe[0] - rear) * fz - my0, atol=1e-10)
        com_rows = at & (names == "com_polygon")
        if com_rows.any():
            assert t >= ph.settle - 1e-9
            com = pin.centerOfMass(model, data, q)
            np.testing.assert_allclose(g[com_rows], polygon_rows(heel, toe, com)[comps[com_rows]], atol=1e-10)
        C = np.column_stack([generalized_force(model, data, q, js.geom, point_forces(e * W, robot.mu))
                             for e in np.eye(8)])[SAGITTAL]
        lam_bal[k] = np.linalg.lstsq(C, tau[SAGITTAL], rcond=None)[0]
    xb = np.array(x, float)
    xb[jn.variables.index(block)] = lam_bal
    gb = jn.nlp.constraints(xb)[sl]
    np.testing.assert_allclose(gb[names == "dynamics"], 0.0, atol=1e-10)
    checked = 0
    for k, t in enumerate(times):
        rows = np.isclose(times_r, t, atol=1e-12) & (names == "zmp_polygon")
        if not rows.any():
            continue
        q, v, a = states[k]
        heel, _, toe, _ = foot_points(model, data, q, js.geom).T
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a).vector
        c = pin.centerOfMass(model, data, q)
        fz = dh[2] + mass_of(model) * G  # both feet
        zmp_x = c[0] - (c[2] * dh[0] + dh[4]) / fz
        assert np.isclose(2 * lam_bal[k].sum() * W, fz)  # each pyramid edge carries its weight in fz
        np.testing.assert_allclose(gb[rows], fz / (2 * W) * polygon_rows(heel, toe, [zmp_x, 0.0])[comps[rows]], atol=1e-9)
        checked += 1
    assert checked > 0
    return modes


def test_contact_node_rows_match_numeric_pinocchio(small_jump):
    """The contact nodes' rows (stance and landing; the flat foot and the flat toes: the two nodes in
    the rolling windows, at takeoff and touchdown, carry none) against numeric Pinocchio."""
    jn, ph = small_jump.nlp, small_jump.js.phases
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    assert (jn.row_names[family(jn, "contact")] == "com_polygon").any()
    np.testing.assert_array_equal(ph.pivot(tc), np.isin(tc, [ph.takeoff, ph.touchdown]))
    modes = _contact_family_against_pinocchio(small_jump, "contact", tc, "lam")
    assert modes == {"foot", "toes"}
    np.testing.assert_array_equal(np.unique(jn.row_times[family(jn, "contact")]), tc[~ph.pivot(tc)])


def test_contact_sample_rows_match_numeric_pinocchio(small_jump):
    """The contact samples' rows (their own edge weights; every contact mode) against numeric
    Pinocchio, and their times: the packaged grid (every ``sample_spacing`` on the 1 kHz grid, at
    the latent spline's breakpoints and just inside each unloaded interval of the schedule), in
    contact, none within 1 ms of a node, and every ``roll_spacing`` while the toes roll (always added
    by build_nlp, whatever the selection)."""
    from latentoc.jump.nlp import contact_sample_grid, rolling_samples

    sj = small_jump
    jn, ph = sj.nlp, sj.js.phases
    tc = jn.selection.contact
    modes = _contact_family_against_pinocchio(sj, "contact_sample", tc, "lam_sample")
    assert modes == {"foot", "toes", "rolling"}
    nodes = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    assert np.allclose(tc * 1000, np.round(tc * 1000)) and np.all(np.diff(tc) > 0)
    assert np.all(((tc > 0) & (tc < ph.takeoff)) | ((tc > ph.touchdown) & (tc < ph.duration)))
    roll = rolling_samples(sj.settings, ph)
    np.testing.assert_allclose(roll, [0.26, 0.27, 0.28, 0.29, 0.30, 0.70], atol=1e-12)  # 10 ms apart, on the 1 kHz grid
    assert ph.pivot(roll).all() and np.all(np.min(np.abs(tc[:, None] - roll[None]), axis=0) < 1e-9)
    np.testing.assert_array_equal(np.union1d(contact_sample_grid(sj.settings, ph), roll), tc)
    grid = contact_sample_grid(sj.settings, ph)
    assert np.min(np.abs(grid[:, None] - nodes[None]), axis=1).min() > 1e-3 - 1e-9
    sw = ph.switch_samples(eps=1e-3)
    assert len(sw) == 4 and not any(ph.loaded(p, np.array([tk]))[0] for tk, p in zip(sw, ("heel", "ball", "ball", "heel")))
    (sp_,) = jn.splines
    knots = np.concatenate([sp_.breakpoints, sw])
    knots = knots[((knots > 0) & (knots < ph.takeoff)) | ((knots > ph.touchdown) & (knots < ph.duration))]
    for tk in np.round(knots * 1000) / 1000:  # at a sample, or within 1 ms of a node
        assert np.min(np.abs(tc - tk)) < 1e-9 or np.min(np.abs(nodes - tk)) <= 1e-3 + 1e-9


def test_anchor_switch_rows_hold_the_toe_joint_at_its_standing_angle_and_at_rest(small_jump):
    """Where the heel leaves and strikes the ground (Phases.switches) the rows are the toe joint's
    angle minus its standing angle (the planted training jump's first frame) and its rate, of the GP
    layer's joint motion; with the toe joint there, in the standing pose, the base on the flat foot
    is the base on the flat toes (test_jump_base)."""
    sj = small_jump
    jn, ph, js = sj.nlp, sj.js.phases, sj.js
    sl = family(jn, "anchor_switch")
    np.testing.assert_allclose(jn.row_times[sl], np.repeat([ph.heel_off, ph.heel_strike], 2), atol=1e-12)
    k = js.smap.learned_names.index("ltoes_rx")
    rng = np.random.default_rng(8)
    x = np.array(sj.x0)
    x[jn.variables.index("P")] += 0.05 * rng.standard_normal(jn.variables.index("P").shape)
    Y, Yd, _ = joint_motion(sj.layer, jn.splines[0], jn.control_points(x), ph.switches())
    expected = np.column_stack([Y[:, k] - js.training.Y[0, k], Yd[:, k]]).ravel()
    np.testing.assert_allclose(jn.nlp.constraints(x)[sl], expected, atol=1e-12)


def test_roll_switch_rows_meet_the_flat_toes_pitch_and_rate(small_jump):
    """Where the toes start and stop rolling (the ball's rise and strike, Phases.roll_switches) the
    rows are the rolling pitch and rate (the roll splines) minus those of the flat toes: the pitch
    that levels the toe point and the pad by forward kinematics (Pinocchio; checked to level them)
    and its rate by central differences in time along the joint motion."""
    from jump_reference import foot_points

    sj = small_jump
    jn, ph, js = sj.nlp, sj.js.phases, sj.js
    model, data = js.model, js.model.createData()
    sl = family(jn, "roll_switch")
    ts = ph.roll_switches()
    np.testing.assert_allclose(ts, [ph.ball_off, ph.ball_strike], atol=1e-12)
    np.testing.assert_allclose(jn.row_times[sl], np.repeat(ts, 2), atol=1e-12)
    x = np.array(sj.x0)
    x[jn.variables.index("roll")] += 0.1 * np.random.default_rng(9).standard_normal(jn.variables.index("roll").shape)
    P = jn.control_points(x)

    def flat_pitch(t):
        y = joint_motion(sj.layer, jn.splines[0], P, t[0])[0][0]
        return np.array([levelling_pitch(model, data, js.smap, y, TOE, PAD, js.geom)])

    rows = jn.nlp.constraints(x)[sl].reshape(-1, 2)
    roll = jn.roll_pitch(x, ts)
    for i, t in enumerate(ts):
        p = flat_pitch(np.array([t]))[0]
        pd = central4(flat_pitch, np.array([t]), np.array([1.0]), 1e-4)[0]
        np.testing.assert_allclose(rows[i], [roll[i, 0] - p, roll[i, 1] - pd], atol=1e-8)
        y, yd, ydd = (u[0] for u in joint_motion(sj.layer, jn.splines[0], P, t))
        Pf = foot_points(model, data, full_state(js.smap, np.array([0.0, 0.0, p]), np.zeros(3), np.zeros(3), y, yd,
                                                 ydd)[0], js.geom)
        assert abs(Pf[2, TOE] - Pf[2, PAD]) < 1e-12


def test_takeoff_rows_are_the_stance_momentum(small_jump):
    """The takeoff rows are the stance state's COM, COM velocity and angular momentum about the COM
    (pinocchio.computeCentroidalMomentum) and pitch at takeoff (the toes rolling on the toe point,
    at the roll spline's pitch and rate) minus the flight's takeoff variables; the training start's
    flight variables are that state."""
    sj = small_jump
    model, jn, ph = sj.js.model, sj.nlp, sj.js.phases
    data = model.createData()
    var = jn.variables
    x = np.array(sj.x0)
    rng = np.random.default_rng(3)
    for name in ("c_to", "cd_to", "L_to", "pitch_flight", "roll"):
        x[var.index(name)] += 0.1 * rng.standard_normal(var.index(name).shape)
    parts = var.unpack(x)
    assert contact_mode(ph, ph.takeoff) == "rolling"
    q, v, _ = state_at(sj, x, ph.takeoff)
    c, cd, L = momentum(model, data, q, v)
    pitch = contact_base(sj, x, ph.takeoff)[0][2]
    assert pitch == jn.roll_pitch(x, np.array([ph.takeoff]))[0, 0]
    expected = np.concatenate([c - parts["c_to"], cd - parts["cd_to"], [L - parts["L_to"][0]],
                               [pitch - parts["pitch_flight"][0]]])
    np.testing.assert_allclose(jn.nlp.constraints(x)[family(jn, "takeoff")], expected, atol=1e-10)
    np.testing.assert_allclose(jn.nlp.constraints(sj.x0)[family(jn, "takeoff")], 0.0, atol=1e-10)


def test_pitch_rate_keeps_the_angular_momentum(small_jump):
    """The pitch-rate block gives the base pitch rate at which the centroidal angular momentum
    (numeric Pinocchio) is its input L; the pitch-integration rows are the flight pitches minus
    the takeoff pitch minus the trapezoid integral (scipy) of that pitch rate on the fine grid."""
    sj = small_jump
    model, jn, ph, smap = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap
    data = model.createData()
    P = jn.control_points(sj.x0)
    block = sj.blocks["pitch_rate"].function("rows")
    rng = np.random.default_rng(4)
    for t in np.linspace(0.05, 1.25, 5):
        y, yd, ydd = (u[0] for u in joint_motion(sj.layer, jn.splines[0], P, t))
        b, bd = rng.standard_normal(3), rng.standard_normal(3)
        q, v, _ = full_state(smap, b, bd, np.zeros(3), y, yd, ydd)
        L = momentum(model, data, q, v)[2]
        assert np.isclose(float(block(y, yd, ydd, [L])), bd[2], rtol=1e-10, atol=1e-10)
    parts = jn.variables.unpack(sj.x0)
    tau, nsub = jn.tau_fine, jn.flight_substeps
    Y, Yd, _ = joint_motion(sj.layer, jn.splines[0], P, ph.takeoff + tau)
    pd = np.array([pitch_rate_for(model, data, smap, Y[i], Yd[i], parts["L_to"][0]) for i in range(len(tau))])
    integral = cumulative_trapezoid(pd, tau, initial=0.0)[::nsub]
    pf = parts["pitch_flight"]
    rows = jn.nlp.constraints(sj.x0)[family(jn, "pitch_integration")]
    np.testing.assert_allclose(rows, pf[1:] - pf[0] - integral[1:], atol=1e-10)
    np.testing.assert_allclose(rows, 0.0, atol=1e-10)  # the start integrates the same pitch rate


def test_touchdown_rows_match_numeric_momentum_and_impact(small_jump):
    """The touchdown rows: the flight's base pose at touchdown (the COM on its parabola, the angular
    momentum kept; base from numeric COM and momentum) minus the landing's (the toes rolling on the
    toe point at x_L, at the roll spline's pitch and rate), and the inelastic
    impact M_bb (v+ - v-) - (sum J^T Pi)_base in body weights, with Pinocchio's mass matrix
    (crba) and the impulses as external forces through rnea."""
    sj = small_jump
    model, jn, ph, smap, robot = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap, sj.robot
    data = model.createData()
    var = jn.variables
    x = np.array(sj.x0)
    rng = np.random.default_rng(5)
    x[var.index("lam_impact")] = rng.uniform(0.0, 1.0, 8)
    x[var.index("roll")] += 0.1 * rng.standard_normal(var.index("roll").shape)
    x[var.index("x_L")] += 0.1
    parts = var.unpack(x)
    assert contact_mode(ph, ph.touchdown) == "rolling"
    y, yd, _ = (u[0] for u in joint_motion(sj.layer, jn.splines[0], jn.control_points(x), ph.touchdown))
    T = ph.touchdown - ph.takeoff
    c = parts["c_to"] + parts["cd_to"] * T + 0.5 * GRAVITY * T ** 2
    cd = parts["cd_to"] + GRAVITY * T
    bm, bdm = flight_base(model, data, smap, y, yd, parts["pitch_flight"][-1], parts["L_to"][0], c, cd)
    bp, bdp, _ = contact_base(sj, x, ph.touchdown)
    q = full_state(smap, bp, bdp, np.zeros(3), y, yd, np.zeros_like(y))[0]
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    v_plus, v_minus = (base_to_freeflyer(bp, bd)[1][0] for bd in (bdp, bdm))
    W = robot.weight
    gen = generalized_force(model, data, q, sj.js.geom, point_forces(parts["lam_impact"] * W * 0.1, robot.mu))
    impact = (M[:6, :6] @ (v_plus - v_minus) - gen[:6])[SAGITTAL] / W
    rows = jn.nlp.constraints(x)[family(jn, "touchdown")]
    names = jn.row_names[family(jn, "touchdown")]
    np.testing.assert_allclose(rows[names == "touchdown_position"], bm - bp, atol=1e-10)
    np.testing.assert_allclose(rows[names == "impact"], impact, atol=1e-9)
    assert np.abs(impact).max() > 1e-2  # a non-trivial impact


def test_flight_rows_are_numeric_pinocchio_on_the_exported_flight(small_jump, small_export):
    """Flight samples at 1 kHz times of the exported ballistic flight, their variables following
    from the rest of the point (jump.warm): the pitch-rate rows hold, the free-fall rows (base rows
    of RNEA) vanish, and the torque rows are numeric pinocchio.rnea's joint torques of the exported
    (q, v, a) over their range (the block computes the motion about the base at zero pitch and
    position); the exported flight is ballistic (no base wrench), its base continuous at takeoff
    and off the landing's by the touchdown rows at touchdown."""
    from latentoc.jump.warm import carried_point

    sj, tr = small_jump, small_export
    model, ph, robot = sj.js.model, sj.js.phases, sj.robot
    data = model.createData()
    flight = np.where((tr["t"] > ph.takeoff) & (tr["t"] < ph.touchdown))[0]
    assert len(flight) > 300
    idx = flight[[0, 2, len(flight) // 3, len(flight) // 2, -3, -1]]
    kept = robot.unmirrored
    sel = dataclasses.replace(sj.nlp.selection, flight=tr["t"][idx], flight_torque=np.ones((len(idx), len(kept)), bool))
    jn = build_nlp(robot, sj.layer, sj.blocks, ph, sj.settings, sj.js.init["P"], sj.js.init["hinge_standing"], "distance",
                   sel)
    x, _ = carried_point(sj.nlp, jn, sj.x0)
    g = jn.nlp.constraints(x)
    np.testing.assert_allclose(g[family(jn, "flight_pitch")], 0.0, atol=1e-12)
    sl = family(jn, "flight")
    names = jn.row_names[sl]
    np.testing.assert_allclose(np.unique(jn.row_times[sl]), tr["t"][idx], atol=1e-12)
    np.testing.assert_allclose(g[sl][names == "flight_base"], 0.0, atol=1e-10)
    rows = g[sl][names == "torque"].reshape(len(idx), len(kept))
    for k, i in enumerate(idx):
        tau = pin.rnea(model, data, tr["q"][i], tr["v"][i], tr["a"][i])
        assert np.abs(tau[:6]).max() < 1e-9 * robot.weight
        tj = tau[6:][robot.active[kept]]
        np.testing.assert_allclose(rows[k] * robot.torque_scale[kept], tj, atol=1e-8 * max(1.0, np.abs(tau).max()))
    # continuous at takeoff; at touchdown the start's landing base is off the flight's by the
    # touchdown rows (it is not a solution)
    base = freeflyer_to_base(tr["q"][:, :7])
    i = int(np.searchsorted(tr["t"], ph.takeoff))
    assert np.max(np.abs(base[i + 1] - base[i - 1])) < 1e-2
    i = int(np.searchsorted(tr["t"], ph.touchdown))
    td = sj.nlp.nlp.constraints(sj.x0)[family(sj.nlp, "touchdown")][:3]
    assert np.max(np.abs(td)) > 0.05
    np.testing.assert_allclose(base[i] - base[i - 1], -td, atol=1e-2)


def test_flight_clearance_rows_are_the_foot_heights_of_the_ballistic_flight(small_jump):
    """At the interior flight nodes the clearance rows are the heel, ball, toe and pad heights by
    forward kinematics of the flight state: the node's pitch, the COM on the parabola of the
    takeoff state, the base placed from the numeric COM."""
    sj = small_jump
    model, jn, ph, smap = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap
    data = model.createData()
    parts = jn.variables.unpack(sj.x0)
    tf = jn.grid["flight"][1:-1]
    sl = family(jn, "flight_clearance")
    np.testing.assert_array_equal(np.unique(jn.row_times[sl]), tf)
    rows = jn.nlp.constraints(sj.x0)[sl].reshape(len(tf), 4)
    Y, Yd, _ = joint_motion(sj.layer, jn.splines[0], jn.control_points(sj.x0), tf)
    for k, t in enumerate(tf):
        T = t - ph.takeoff
        c = parts["c_to"] + parts["cd_to"] * T + 0.5 * GRAVITY * T ** 2
        cd = parts["cd_to"] + GRAVITY * T
        b, _ = flight_base(model, data, smap, Y[k], Yd[k], parts["pitch_flight"][k + 1], parts["L_to"][0], c, cd)
        q = full_state(smap, b, np.zeros(3), np.zeros(3), Y[k], Yd[k], np.zeros_like(Y[k]))[0]
        np.testing.assert_allclose(rows[k], foot_points(model, data, q, sj.js.geom)[2], atol=1e-10)
    assert rows.min() > 0.0  # the training start's feet are off the ground in flight


def test_right_torque_rows_left_out_are_mirror_copies_of_the_left(small_jump, small_export):
    """The NLP keeps the torque rows of the centre and left joints only: on the exported motion,
    numeric pinocchio.rnea (and the exported torques with the contact forces) give every right
    joint its left partner's torque times the mirror factor, and the training limits are mirror
    images, so the right rows would repeat the left. Limits that are not mirror images keep every
    row."""
    sj, tr = small_jump, small_export
    js, robot, jn = sj.js, sj.robot, sj.nlp
    pairs = [(r - 7, int(js.smap.learned_q[y]) - 7, f) for r, y, f in js.smap.copied]
    right = {r for r, _, _ in pairs}
    assert len(pairs) == 19 and sorted(set(robot.active[robot.unmirrored]) & right) == []
    assert len(robot.unmirrored) == len(robot.active) - len(right & set(robot.active))
    # every chosen time has the torque rows of the kept joints (the fixture chooses all; the rolling
    # toes' nodes have no rows, the rolling samples build_nlp adds no torque rows)
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    sel = jn.selection
    n_rows = (~js.phases.pivot(tc)).sum() + sel.contact_torque.any(axis=1).sum() + len(sel.flight)
    assert sel.contact_torque.any(axis=1).sum() == len(sel.contact) - 4  # 0.26, 0.27, 0.28 and 0.70 s
    assert (jn.row_names == "torque").sum() == n_rows * len(robot.unmirrored)
    d = js.model.createData()
    checked = 0
    for i in range(0, len(tr["t"]), 97):
        tau = pin.rnea(js.model, d, tr["q"][i], tr["v"][i], tr["a"][i])[6:]
        for r, left, f in pairs:
            assert abs(tau[r] - f * tau[left]) <= 1e-9 * max(1.0, np.abs(tau).max())
            assert abs(tr["tau"][i][r] - f * tr["tau"][i][left]) <= 1e-9 * max(1.0, np.abs(tr["tau"][i]).max())
        checked += bool(tr["contact"][i])
    assert checked > 5
    lo, hi = js.limits.tau_min, js.limits.tau_max
    for r, left, f in pairs:
        assert np.allclose((lo[r], hi[r]), (lo[left], hi[left]) if f > 0 else (-hi[left], -lo[left]))
    skewed = dataclasses.replace(robot, limits=dataclasses.replace(js.limits, tau_max=hi + np.eye(len(hi))[pairs[0][0]]))
    assert np.array_equal(skewed.unmirrored, np.arange(len(skewed.active)))
