"""The broad jump's row families (latentoc.jump.rows) against numeric Pinocchio.

Every row family is read from the assembled NLP (so the node inputs are checked with the
blocks) at the training start of a jump with few nodes: the joint motion of the GP layer along
the training fit's latent path, in the contact phases with the legs closed and the base from the
planted body (latentoc.jump.closure.planted_legs, itself checked here by the planted body's numeric placement).
The flight samples are placed at times of the 1 kHz export of that start and checked on its
exported motion. References: ``pinocchio.rnea`` (with the point forces as external
forces), frame placements and Jacobians, the COM, the centroidal momentum and its rate, the
mass matrix (:mod:`jump_reference`).
"""
import dataclasses

import numpy as np
import pinocchio as pin
from scipy.integrate import cumulative_trapezoid

from jump_reference import (SAGITTAL, flight_base, foot_points, full_state, generalized_force, joint_motion,
                            mass_of, momentum, pitch_rate_for, point_forces, polygon_rows)
from latentoc.jump.robot.sagittal_base import freeflyer_to_base
from latentoc.jump.rows.flight import FLIGHT_SUBSTEPS
from latentoc.jump.transcription.nlp import build_nlp
from latentoc.jump.robot.zmp import G

GRAVITY = np.array([0.0, -9.81])


def family(jn, name: str) -> slice:
    """The rows of row family ``name`` in the NLP's constraint vector."""
    off = jn.nlp.row_offset[name]
    return slice(off, off + next(f.n_rows for f in jn.nlp.families if f.name == name))


def parts_of(g, names, part, n):
    """The rows named ``part`` in order, as (nodes x n)."""
    return g[names == part].reshape(-1, n)


def contact_state(sj, parts, t):
    """The closed legs (y, yd, ydd) and the planted base (b, bd, bdd) at contact time t, the planted
    body checked at its ground pose (the standing one, moved to x_L in the landing) by numeric Pinocchio."""
    ph, cl, model = sj.js.phases, sj.robot.closure, sj.js.model
    y, yd, ydd = (u[0] for u in joint_motion(sj.layer, sj.nlp.spline, sj.nlp.control_points(sj.x0), t,
                                             ph.closing(np.array([t]))))
    shift = parts["x_L"][0] - sj.robot.geom.footprint[0, 2] if t >= ph.touchdown - 1e-12 else 0.0
    out = [u[0] for u in cl.evaluate(y[None], yd[None], ydd[None], ph.held(np.array([t])), np.array([shift]))]
    q = full_state(sj.js.smap, *out[3:], *out[:3])[0]
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    M = data.oMf[model.getFrameId(cl.anchor)]
    np.testing.assert_allclose(M.translation, cl.p_ground + [shift, 0.0, 0.0], atol=1e-10)
    np.testing.assert_allclose(M.rotation, cl.R_ground, atol=1e-10)
    return out


def contact_base(sj, parts, t):
    """(b, bd, bdd) of the planted base at contact time t."""
    return contact_state(sj, parts, t)[3:]


def state_at(sj, parts, t):
    """Numeric q, v, a of a contact time: the closed legs and the planted base."""
    out = contact_state(sj, parts, t)
    return full_state(sj.js.smap, *out[3:], *out[:3])


def _contact_family_against_pinocchio(sj, family_name: str, times: np.ndarray, block: str) -> None:
    """A contact family's rows (nodes or samples) at random edge weights against numeric Pinocchio:
    base rows = rnea's minus sum J^T f (body weights), torques over their range, the centre of
    pressure on the ground in the loaded support, the unloaded points' heights, the COM in the
    feet's polygon once settled; with balanced edge weights the ZMP rows are
    the normal force times the polygon rows of the ZMP of the centroidal momentum rate on the ground."""
    model, js, robot = sj.js.model, sj.js, sj.robot
    data = model.createData()
    jn, ph, W = sj.nlp, js.phases, robot.weight
    K = len(times)
    act, scale = robot.active, robot.torque_scale
    lam = np.random.default_rng(0).uniform(0.0, 0.2, (K, 8)) * (jn.ubx[jn.variables.index(block)] > 0)
    x = np.array(sj.x0, float)
    x[jn.variables.index(block)] = lam
    parts = jn.variables.unpack(x)
    sl = family(jn, family_name)
    g, names, times_r = jn.nlp.constraints(x)[sl], jn.row_names[sl], jn.row_times[sl]
    comps = jn.row_components[sl]
    lam_bal, states = np.zeros((K, 8)), []
    for k, t in enumerate(times):
        at = np.isclose(times_r, t, atol=1e-12)
        q, v, a = state_at(sj, parts, t)
        states.append((q, v, a))
        tau = pin.rnea(model, data, q, v, a)
        gen = generalized_force(model, data, q, js.geom, point_forces(lam[k] * W, robot.mu))
        np.testing.assert_allclose(g[at & (names == "dynamics")], (tau - gen)[SAGITTAL] / W, atol=1e-9)
        tq = at & (names == "torque")
        tj = (tau - gen)[6:][act[comps[tq]]]
        np.testing.assert_allclose(g[tq], tj / scale[comps[tq]], atol=1e-9 * max(1.0, np.abs(tj).max()))
        heel, ball, toe, pad = foot_points(model, data, q, js.geom).T
        F = point_forces(lam[k] * W, robot.mu)
        my0 = sum((P[2]) * f[0] - (P[0] - toe[0]) * f[1] for P, f in zip((heel, ball, toe, pad), F)) / W
        fz = F[:, 1].sum() / W
        np.testing.assert_allclose(g[at & (names == "cop_front")], my0, atol=1e-10)
        back = g[at & np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
        rear = heel[0] if ph.loaded("heel", np.array([t]))[0] else ball[0] if ph.loaded("ball", np.array([t]))[0] \
            else toe[0] - 0.01
        np.testing.assert_allclose(back, (toe[0] - rear) * fz - my0, atol=1e-10)
        # the unloaded points' heights above their standing ones (the standing frame, numeric)
        d0 = model.createData()
        fp = foot_points(model, d0, js.training.Q[0], js.geom).T
        off = [i for i, p in enumerate(("heel", "ball", "toe", "pad")) if not ph.loaded(p, np.array([t]))[0]]
        hr = at & (names == "height")
        assert sorted(comps[hr]) == off
        np.testing.assert_allclose(g[hr], [(heel, ball, toe, pad)[c][2] - fp[c, 2] for c in comps[hr]], atol=1e-10)
        com_rows = at & (names == "com_polygon")
        if com_rows.any():
            assert t >= ph.settle - 1e-9
            com = pin.centerOfMass(model, data, q)
            np.testing.assert_allclose(g[com_rows], polygon_rows(heel, toe, com)[comps[com_rows]], atol=1e-10)
        C = np.column_stack([generalized_force(model, data, q, js.geom, point_forces(e * W, robot.mu))
                             for e in np.eye(8)])[SAGITTAL]
        lam_bal[k] = np.linalg.lstsq(C, tau[SAGITTAL], rcond=None)[0]
    xb = np.array(sj.x0, float)
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


def test_contact_node_rows_match_numeric_pinocchio(small_jump):
    """The contact nodes' rows (stance and landing) against numeric Pinocchio."""
    jn = small_jump.nlp
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    assert (jn.row_names[family(jn, "contact")] == "com_polygon").any()
    assert (jn.row_names[family(jn, "contact")] == "height").any()
    _contact_family_against_pinocchio(small_jump, "contact", tc, "lam")


def test_contact_sample_rows_match_numeric_pinocchio(small_jump):
    """The contact samples' rows (their own edge weights) against numeric Pinocchio, and their times:
    the packaged grid (every ``sample_spacing`` on the 1 kHz grid, at the path's breakpoints and just
    inside each unloaded interval of the schedule), in contact, none within 1 ms of a node."""
    sj = small_jump
    jn, ph = sj.nlp, sj.js.phases
    tc = jn.selection.contact
    _contact_family_against_pinocchio(sj, "contact_sample", tc, "lam_sample")
    nodes = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    assert np.allclose(tc * 1000, np.round(tc * 1000)) and np.all(np.diff(tc) > 0)
    assert np.min(np.abs(tc[:, None] - nodes[None]), axis=1).min() > 1e-3 - 1e-9
    assert np.all(((tc > 0) & (tc < ph.takeoff)) | ((tc > ph.touchdown) & (tc < ph.duration)))
    sw = ph.switch_samples(eps=1e-3)
    assert len(sw) == 4 and not any(ph.loaded(p, np.array([tk]))[0] for tk, p in zip(sw, ("heel", "ball", "ball", "heel")))
    knots = np.concatenate([jn.spline.breakpoints, sw])
    knots = knots[((knots > 0) & (knots < ph.takeoff)) | ((knots > ph.touchdown) & (knots < ph.duration))]
    for tk in np.round(knots * 1000) / 1000:  # at a sample, or within 1 ms of a node
        assert np.min(np.abs(tc - tk)) < 1e-9 or np.min(np.abs(nodes - tk)) <= 1e-3 + 1e-9


def _closure_gap(sj, parts, t, y, yd):
    """The closed legs less the GP mean's: the out-of-plane joints and (where held) the hinge, then
    their velocities."""
    yc, ydc = contact_state(sj, parts, t)[:2]
    cl = sj.robot.closure
    idx = list(cl.dependent) + ([cl.hinge] if sj.js.phases.held(np.array([t]))[0] else [])
    return np.concatenate([(yc - y)[idx], (ydc - yd)[idx]])


def test_takeoff_rows_are_the_stance_momentum(small_jump):
    """The takeoff rows are the stance state's COM, COM velocity and angular momentum about the COM
    (pinocchio.computeCentroidalMomentum) and pitch at takeoff minus the flight's takeoff
    variables, and the closed legs less the GP mean's; the training start's flight variables are
    that state."""
    sj = small_jump
    model, jn, ph = sj.js.model, sj.nlp, sj.js.phases
    data = model.createData()
    var = jn.variables
    x = np.array(sj.x0)
    rng = np.random.default_rng(3)
    for name in ("c_to", "cd_to", "L_to", "pitch_flight"):
        x[var.index(name)] += 0.1 * rng.standard_normal(var.index(name).shape)
    parts = var.unpack(x)
    q, v, _ = state_at(sj, parts, ph.takeoff)
    c, cd, L = momentum(model, data, q, v)
    pitch = contact_base(sj, parts, ph.takeoff)[0][2]
    y, yd, _ = (u[0] for u in joint_motion(sj.layer, jn.spline, jn.control_points(x), ph.takeoff))
    expected = np.concatenate([c - parts["c_to"], cd - parts["cd_to"], [L - parts["L_to"][0]],
                               [pitch - parts["pitch_flight"][0]], _closure_gap(sj, parts, ph.takeoff, y, yd)])
    np.testing.assert_allclose(jn.nlp.constraints(x)[family(jn, "takeoff")], expected, atol=1e-10)
    np.testing.assert_allclose(jn.nlp.constraints(sj.x0)[family(jn, "takeoff")][:6], 0.0, atol=1e-10)


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
        y, yd, ydd = (u[0] for u in joint_motion(sj.layer, jn.spline, P, t))
        b, bd = rng.standard_normal(3), rng.standard_normal(3)
        q, v, _ = full_state(smap, b, bd, np.zeros(3), y, yd, ydd)
        L = momentum(model, data, q, v)[2]
        assert np.isclose(float(block(y, yd, ydd, [L])), bd[2], rtol=1e-10, atol=1e-10)
    parts = jn.variables.unpack(sj.x0)
    tau, nsub = jn.tau_fine, FLIGHT_SUBSTEPS
    Y, Yd, _ = joint_motion(sj.layer, jn.spline, P, ph.takeoff + tau)
    pd = np.array([pitch_rate_for(model, data, smap, Y[i], Yd[i], parts["L_to"][0]) for i in range(len(tau))])
    integral = cumulative_trapezoid(pd, tau, initial=0.0)[::nsub]
    pf = parts["pitch_flight"]
    rows = jn.nlp.constraints(sj.x0)[family(jn, "pitch_integration")]
    np.testing.assert_allclose(rows, pf[1:] - pf[0] - integral[1:], atol=1e-10)
    np.testing.assert_allclose(rows, 0.0, atol=1e-10)  # the start integrates the same pitch rate


def test_touchdown_rows_meet_the_ballistic_flight_at_rest(small_jump):
    """The touchdown rows: the flight's base pose and velocity at touchdown (the COM on its parabola,
    the angular momentum kept; base from numeric COM and momentum) minus the landing's planted base,
    and the closed legs less the GP mean's."""
    sj = small_jump
    model, jn, ph, smap = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap
    data = model.createData()
    x = np.array(sj.x0)
    x[jn.variables.index("x_L")] += 0.05
    parts = jn.variables.unpack(x)
    y, yd, _ = (u[0] for u in joint_motion(sj.layer, jn.spline, jn.control_points(x), ph.touchdown))
    T = ph.touchdown - ph.takeoff
    c = parts["c_to"] + parts["cd_to"] * T + 0.5 * GRAVITY * T ** 2
    cd = parts["cd_to"] + GRAVITY * T
    bm, bdm = flight_base(model, data, smap, y, yd, parts["pitch_flight"][-1], parts["L_to"][0], c, cd)
    bp, bdp, _ = contact_base(sj, parts, ph.touchdown)
    rows = jn.nlp.constraints(x)[family(jn, "touchdown")]
    names = jn.row_names[family(jn, "touchdown")]
    np.testing.assert_allclose(rows[names == "touchdown_position"], bm - bp, atol=1e-10)
    np.testing.assert_allclose(rows[names == "touchdown_velocity"], bdm - bdp, atol=1e-9)
    np.testing.assert_allclose(rows[names == "closure_gap"], _closure_gap(sj, parts, ph.touchdown, y, yd), atol=1e-10)


def test_flight_rows_are_numeric_pinocchio_on_the_exported_flight(small_jump, small_export):
    """Flight samples at 1 kHz times of the exported ballistic flight, their variables following
    from the rest of the point (jump.warm): the pitch-rate rows hold, the free-fall rows (base rows
    of RNEA) vanish, and the torque rows are numeric pinocchio.rnea's joint torques of the exported
    (q, v, a) over their range (the block computes the motion about the base at zero pitch and
    position); the exported flight is ballistic (no base wrench), its base continuous at takeoff
    and off the landing's by the touchdown rows at touchdown."""
    from latentoc.jump.solve.warm import carried_point

    sj, tr = small_jump, small_export
    model, ph, robot = sj.js.model, sj.js.phases, sj.robot
    data = model.createData()
    flight = np.where((tr["t"] > ph.takeoff) & (tr["t"] < ph.touchdown))[0]
    assert len(flight) > 300
    idx = flight[[0, 2, len(flight) // 3, len(flight) // 2, -3, -1]]
    kept = robot.unmirrored
    sel = dataclasses.replace(sj.nlp.selection, flight=tr["t"][idx], flight_torque=np.ones((len(idx), len(kept)), bool))
    jn = build_nlp(robot, sj.layer, sj.blocks, ph, sj.settings, sj.js.init["P"], "distance", sel)
    x, _ = carried_point(sj.nlp, jn, sj.x0)
    g = jn.nlp.constraints(x)
    np.testing.assert_allclose(g[family(jn, "flight_pitch")], 0.0, atol=1e-12)
    sl = family(jn, "flight")
    names = jn.row_names[sl]
    np.testing.assert_array_equal(np.unique(jn.row_times[sl]), tr["t"][idx])
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
    assert np.max(np.abs(base[i + 1] - base[i - 1])) < 3e-3 * (1.0 + np.abs(tr["v"][i, :6]).max())  # 2 ms at its speed
    i = int(np.searchsorted(tr["t"], ph.touchdown))
    td = sj.nlp.nlp.constraints(sj.x0)[family(sj.nlp, "touchdown")][:3]
    assert np.max(np.abs(td)) > 0.05
    jump = base[i] - base[i - 1] + td
    jump[2] = np.angle(np.exp(1j * jump[2]))  # the pitch modulo a turn
    np.testing.assert_allclose(jump, 0.0, atol=2e-3 * (1.0 + np.abs(tr["v"][i - 1, :6]).max()))


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
    Y, Yd, _ = joint_motion(sj.layer, jn.spline, jn.control_points(sj.x0), tf)
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
    n_rows = len(jn.grid["stance"]) + len(jn.grid["land"]) + len(jn.selection.contact) + len(jn.selection.flight)
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
