"""The broad jump's row families (latentoc.jump.rows) against numeric Pinocchio.

Every row family is read from the assembled NLP (so the node inputs are checked with the
blocks) at the training start of a jump with few nodes: the joint motion of the GP layer along
the training fit's latent path, the contact phases' base splines fitted to the captured base.
The flight's torque rows are placed at times of the 1 kHz export of that start and checked on
its exported motion. References: ``pinocchio.rnea`` (with the point forces as external
forces), frame placements and Jacobians, the COM, the centroidal momentum and its rate, the
mass matrix (:mod:`jump_reference`).
"""
import dataclasses

import numpy as np
import pinocchio as pin
from scipy.integrate import cumulative_trapezoid

from jump_reference import (SAGITTAL, flight_base, foot_points, full_state, generalized_force, joint_motion,
                            mass_of, momentum, pitch_rate_for, point_forces, polygon_rows)
from latentoc.jump.base import base_to_freeflyer, freeflyer_to_base
from latentoc.jump.contact import TOE_PAD
from latentoc.jump.nlp import build_nlp, default_samples
from latentoc.jump.zmp import G

GRAVITY = np.array([0.0, -9.81])


def family(jn, name: str) -> slice:
    """The rows of row family ``name`` in the NLP's constraint vector."""
    off = jn.nlp.row_offset[name]
    return slice(off, off + next(f.n_rows for f in jn.nlp.families if f.name == name))


def parts_of(g, names, part, n):
    """The rows named ``part`` in order, as (nodes x n)."""
    return g[names == part].reshape(-1, n)


def contact_base(sj, parts, t):
    """(b, bd, bdd) of the contact phase's base spline at time t."""
    ph = sj.js.phases
    _, sps, spl = sj.nlp.splines
    if t >= ph.touchdown - 1e-12:
        return [spl.evaluate(parts["base_land"], np.array([t - ph.touchdown]), k)[0] for k in range(3)]
    return [sps.evaluate(parts["base_stance"], np.array([min(t, ph.takeoff)]), k)[0] for k in range(3)]


def state_at(sj, parts, t):
    """Numeric q, v, a of a contact time: the GP layer's joint motion and the base spline."""
    y, yd, ydd = (u[0] for u in joint_motion(sj.layer, sj.nlp.splines[0], sj.nlp.control_points(sj.x0), t))
    return full_state(sj.js.smap, *contact_base(sj, parts, t), y, yd, ydd)


def with_lam(sj, x, lam):
    x = np.array(x, float)
    x[sj.nlp.variables.index("lam")] = lam
    return x


def test_contact_rows_match_numeric_pinocchio(small_jump):
    """At every contact node (stance and landing): the dynamics rows are the sagittal base rows of
    numeric rnea minus sum J^T f of the point forces (random edge weights, body weights), the
    torque rows the joint torques over their limit range (kept joints), the toe tip's offset from
    its ground point (0 in the stance, x_L in the landing), the heel and ball heights and, once
    settled, the projected COM in the feet's polygon, all from numeric Pinocchio on the same
    state; with edge weights that balance the base rows exactly, the ZMP rows are the normal force
    times the polygon rows of the ZMP of the centroidal momentum rate on the toe tip's plane."""
    sj = small_jump
    model, js, robot = sj.js.model, sj.js, sj.robot
    data = model.createData()
    jn, ph, W = sj.nlp, js.phases, robot.weight
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    nS, nC = len(jn.grid["stance"]), len(tc)
    kept, act, scale = robot.unmirrored, robot.active, robot.torque_scale
    lam = np.random.default_rng(0).uniform(0.0, 0.2, (nC, 6))
    x = with_lam(sj, sj.x0, lam)
    parts = jn.variables.unpack(x)
    sl = family(jn, "contact")
    g, names = jn.nlp.constraints(x)[sl], jn.row_names[sl]
    rows = {"dynamics": parts_of(g, names, "dynamics", 3), "torque": parts_of(g, names, "torque", len(kept)),
            "ball_height": parts_of(g, names, "ball_height", 1)[:, 0],
            "toe_position": parts_of(g, names, "toe_position", 2),
            "heel_height": parts_of(g, names, "heel_height", 1)[:, 0],
            "com_polygon": parts_of(g, names, "com_polygon", 4)}
    settled = np.where((np.arange(nC) >= nS) & (tc >= ph.settle - 1e-9))[0]
    assert len(rows["dynamics"]) == nC and len(rows["com_polygon"]) == len(settled) > 0
    # the balanced edge weights: least norm, all six edges (the reference's own J^T f)
    lam_bal = np.zeros((nC, 6))
    states = []
    for k, t in enumerate(tc):
        q, v, a = state_at(sj, parts, t)
        states.append((q, v, a))
        tau = pin.rnea(model, data, q, v, a)
        gen = generalized_force(model, data, q, js.geom.heel_offset, point_forces(lam[k] * W, robot.mu))
        np.testing.assert_allclose(rows["dynamics"][k], (tau - gen)[SAGITTAL] / W, atol=1e-9)
        tj = (tau - gen)[6:][act[kept]]
        np.testing.assert_allclose(rows["torque"][k], tj / scale[kept], atol=1e-9 * max(1.0, np.abs(tj).max()))
        heel, ball, toe = foot_points(model, data, q, js.geom.heel_offset).T
        x_pin = parts["x_L"][0] if k >= nS else 0.0
        np.testing.assert_allclose(rows["toe_position"][k], [toe[0] - x_pin, toe[2]], atol=1e-10)
        np.testing.assert_allclose([rows["heel_height"][k], rows["ball_height"][k]], [heel[2], ball[2]], atol=1e-10)
        if k in settled:
            com = pin.centerOfMass(model, data, q)
            np.testing.assert_allclose(rows["com_polygon"][list(settled).index(k)], polygon_rows(heel, toe, com),
                                       atol=1e-10)
        C = np.column_stack([generalized_force(model, data, q, js.geom.heel_offset, point_forces(e * W, robot.mu))
                             for e in np.eye(6)])[SAGITTAL]
        lam_bal[k] = np.linalg.lstsq(C, tau[SAGITTAL], rcond=None)[0]
    # a realistic start: forces of a few body weights in all, the feet on the ground within 2 cm
    assert np.all(np.abs(rows["toe_position"][:, 1]) < 0.02) and 0.1 < np.abs(lam_bal).sum(1).max() < 10
    xb = with_lam(sj, sj.x0, lam_bal)
    gb = jn.nlp.constraints(xb)[sl]
    np.testing.assert_allclose(parts_of(gb, names, "dynamics", 3), 0.0, atol=1e-10)
    zmp_rows = parts_of(gb, names, "zmp_polygon", 4)
    assert len(zmp_rows) == nC - nS
    for j, k in enumerate(range(nS, nC)):
        q, v, a = states[k]
        heel, _, toe = foot_points(model, data, q, js.geom.heel_offset).T
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a).vector
        c = pin.centerOfMass(model, data, q)
        fz = dh[2] + mass_of(model) * G  # both feet
        zmp_x = c[0] - ((c[2] - toe[2]) * dh[0] + dh[4]) / fz
        assert np.isclose(2 * lam_bal[k].sum() * W, fz)  # each pyramid edge carries its weight in fz
        np.testing.assert_allclose(zmp_rows[j], fz / (2 * W) * polygon_rows(heel, toe, [zmp_x, 0.0]), atol=1e-9)


def test_wrench_rows_are_the_cone_of_the_needed_wrench(small_jump):
    """At every wrench sample: the sagittal base rows of numeric rnea solved for the (fx, fz, my)
    of each toe tip (body weights), its cone rows and the centre-of-pressure row of the rearmost
    point the contact schedule loads (heel, ball or the toe pad), and the torques of the joints no
    foot force enters over their limit range. Those joints' torques do not depend on how the
    wrench is split into point forces (two splits of the same wrench agree there, not in the legs)."""
    sj = small_jump
    model, js, robot = sj.js.model, sj.js, sj.robot
    data = model.createData()
    jn, ph, W, mu = sj.nlp, js.phases, robot.weight, robot.mu
    parts = jn.variables.unpack(sj.x0)
    sl = family(jn, "wrench")
    g, names = jn.nlp.constraints(sj.x0)[sl], jn.row_names[sl]
    tw = jn.meta["samples"].wrench
    np.testing.assert_array_equal(np.unique(jn.meta["row_times"][sl]), tw)
    K = len(tw)
    ff = robot.force_free
    free_kept = np.intersect1d(ff, robot.unmirrored)
    back_names = names[np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
    back = g[np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
    rows = {"wrench_normal": parts_of(g, names, "wrench_normal", 1)[:, 0],
            "wrench_friction": parts_of(g, names, "wrench_friction", 2), "cop_front": parts_of(g, names, "cop_front", 1)[:, 0],
            "torque_free": parts_of(g, names, "torque_free", len(free_kept))}
    assert len(back) == len(rows["cop_front"]) == K > 10
    ids = [model.getFrameId(n) for n in ("ltoes_end", "rtoes_end")]
    for k, t in enumerate(tw):
        q, v, a = state_at(sj, parts, t)
        tau = pin.rnea(model, data, q, v, a)
        pin.computeJointJacobians(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        J = sum(pin.getFrameJacobian(model, data, i, pin.LOCAL_WORLD_ALIGNED) for i in ids)
        wrench = np.zeros(6)
        wrench[SAGITTAL] = np.linalg.solve(J.T[np.ix_(SAGITTAL, SAGITTAL)], tau[SAGITTAL])
        np.testing.assert_allclose((J.T @ wrench)[:6], tau[:6], atol=1e-9 * np.abs(tau[:6]).max())
        fx, _, fz, _, my, _ = wrench / W
        heel, ball, toe = foot_points(model, data, q, js.geom.heel_offset).T
        loaded = [ph.loaded(p, np.array([t]))[0] for p in ("heel", "ball")]
        which, rear = (("cop_heel", heel[0]) if loaded[0] else ("cop_ball", ball[0]) if loaded[1]
                       else ("cop_pad", toe[0] - TOE_PAD))
        assert back_names[k] == which
        tol = 1e-9 * max(1.0, abs(fz), abs(my))
        assert abs(rows["wrench_normal"][k] - fz) < tol and abs(rows["cop_front"][k] - my) < tol
        np.testing.assert_allclose(rows["wrench_friction"][k], [mu * fz - fx, mu * fz + fx], atol=tol)
        np.testing.assert_allclose(back[k], (toe[0] - rear) * fz - my, atol=tol)
        # no foot force enters these joints: their torque is the motion's alone
        assert len(ff) == 30 and np.all(J[:, 6 + robot.active[ff]] == 0)
        tf = tau[6:][robot.active[free_kept]]
        np.testing.assert_allclose(rows["torque_free"][k], tf / robot.torque_scale[free_kept],
                                   atol=1e-9 * max(1.0, np.abs(tf).max()))
        split = []
        for b in (0, 1):  # the wrench as (fx, fz) at the heel or the ball and fz at the toe tip
            unit = []
            for point, axis in ((b, 0), (b, 1), (2, 1)):
                f = np.zeros((3, 2))
                f[point, axis] = 1.0
                unit.append(generalized_force(model, data, q, js.geom.heel_offset, f))
            C = np.column_stack(unit)
            sol = np.linalg.solve(C[SAGITTAL], (J.T @ wrench)[SAGITTAL])
            split.append((tau - C @ sol)[6:][robot.active])
        np.testing.assert_allclose(split[0][ff], split[1][ff], atol=1e-6)
        assert np.max(np.abs(np.delete(split[0] - split[1], ff))) > 1e-3  # far above the 1e-6 agreement


def test_wrench_samples_lie_between_the_nodes_with_the_scheduled_support(small_jump):
    """The wrench samples lie strictly between the contact nodes of the stance and the landing:
    the even samples of each interval, one just inside each unloaded interval of the contact
    schedule and one at each spline breakpoint inside a contact phase, none at a node; the
    rearmost support follows the schedule; without wrench samples the NLP has none of their rows."""
    sj = small_jump
    jn, ph, robot = sj.nlp, sj.js.phases, sj.robot
    names = jn.row_names
    default = default_samples(sj.settings, ph)
    np.testing.assert_array_equal(jn.meta["samples"].wrench, default.wrench)
    np.testing.assert_array_equal(default.flight_torque, jn.grid["flight"])
    n0 = build_nlp(robot, sj.layer, sj.blocks, ph, sj.settings, sj.js.init["P"], "feasibility",
                   samples=dataclasses.replace(default, wrench=np.zeros(0)))
    assert not any(str(k).startswith(("wrench_", "cop_", "torque_free")) for k in n0.row_names)
    assert "wrench" not in n0.nlp.row_offset and n0.variables.n == jn.variables.n
    tw, grid, spacing = jn.meta["samples"].wrench, jn.grid, sj.settings.wrench_spacing
    n_samples = int((names == "wrench_normal").sum())
    nodes = np.concatenate([grid["stance"], grid["land"]])
    assert len(tw) == n_samples and np.all(np.diff(tw) > 0)
    assert np.min(np.abs(tw[:, None] - nodes[None]), axis=1).min() > 1e-4
    assert np.all((tw < ph.takeoff) | (tw > ph.touchdown)) and tw.min() > 0 and tw.max() < ph.duration
    for tn in (grid["stance"], grid["land"]):
        for a, b in zip(tn[:-1], tn[1:]):
            k = int(np.ceil((b - a) / spacing - 1e-9))
            for tk in np.linspace(a, b, k + 1)[1:-1]:
                assert np.min(np.abs(tw - tk)) < 1e-12
    switches = ph.switch_samples()
    assert len(switches) == 4 and np.allclose(switches, [ph.heel_off + 5e-4, ph.ball_off + 5e-4,
                                                         ph.ball_strike - 5e-4, ph.heel_strike - 5e-4])
    assert not any(ph.loaded(p, np.array([tk]))[0] for tk, p in zip(switches, ("heel", "ball", "ball", "heel")))
    sp_, sps, spl = jn.splines
    knots = np.concatenate([sp_.breakpoints, sps.breakpoints, ph.touchdown + spl.breakpoints])
    knots = knots[((knots > 0) & (knots < ph.takeoff)) | ((knots > ph.touchdown) & (knots < ph.duration))]
    assert len(knots) > 10
    for tk in np.concatenate([switches, knots]):  # at a sample, or at a node already
        assert np.min(np.abs(np.concatenate([tw, nodes]) - tk)) <= 1e-4
    assert (names == "wrench_friction").sum() == 2 * n_samples and (names == "cop_front").sum() == n_samples
    back = names[np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
    heel, ball = ph.loaded("heel", tw), ph.loaded("ball", tw)
    assert list(back) == ["cop_heel" if h else "cop_ball" if b else "cop_pad" for h, b in zip(heel, ball)]
    assert {"cop_heel", "cop_ball", "cop_pad"} == set(back)
    # trunk, neck, head and left arm joints (the right arm's rows are their mirror copies)
    assert (names == "torque_free").sum() == 18 * n_samples


def test_takeoff_rows_are_the_stance_momentum(small_jump):
    """The takeoff rows are the stance state's COM, COM velocity and angular momentum about the COM
    (pinocchio.computeCentroidalMomentum) and pitch at takeoff minus the flight's takeoff
    variables; the training start's flight variables are that state."""
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
    tau, nsub = jn.meta["tau_fine"], jn.meta["flight_substeps"]
    Y, Yd, _ = joint_motion(sj.layer, jn.splines[0], P, ph.takeoff + tau)
    pd = np.array([pitch_rate_for(model, data, smap, Y[i], Yd[i], parts["L_to"][0]) for i in range(len(tau))])
    integral = cumulative_trapezoid(pd, tau, initial=0.0)[::nsub]
    pf = parts["pitch_flight"]
    rows = jn.nlp.constraints(sj.x0)[family(jn, "pitch_integration")]
    np.testing.assert_allclose(rows, pf[1:] - pf[0] - integral[1:], atol=1e-10)
    np.testing.assert_allclose(rows, 0.0, atol=1e-10)  # the start integrates the same pitch rate


def test_touchdown_rows_match_numeric_momentum_and_impact(small_jump):
    """The touchdown rows: the flight's base pose at touchdown (the COM on its parabola, the angular
    momentum kept; base from numeric COM and momentum) minus the landing's, and the inelastic
    impact M_bb (v+ - v-) - (sum J^T Pi)_base in body weights, with Pinocchio's mass matrix
    (crba) and the impulses as external forces through rnea."""
    sj = small_jump
    model, jn, ph, smap, robot = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap, sj.robot
    data = model.createData()
    var = jn.variables
    x = np.array(sj.x0)
    x[var.index("lam_impact")] = np.random.default_rng(5).uniform(0.0, 1.0, 6)
    parts = var.unpack(x)
    y, yd, _ = (u[0] for u in joint_motion(sj.layer, jn.splines[0], jn.control_points(x), ph.touchdown))
    T = ph.touchdown - ph.takeoff
    c = parts["c_to"] + parts["cd_to"] * T + 0.5 * GRAVITY * T ** 2
    cd = parts["cd_to"] + GRAVITY * T
    bm, bdm = flight_base(model, data, smap, y, yd, parts["pitch_flight"][-1], parts["L_to"][0], c, cd)
    bp, bdp, _ = contact_base(sj, parts, ph.touchdown)
    q = full_state(smap, bp, bdp, np.zeros(3), y, yd, np.zeros_like(y))[0]
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    v_plus, v_minus = (base_to_freeflyer(bp, bd)[1][0] for bd in (bdp, bdm))
    W = robot.weight
    gen = generalized_force(model, data, q, sj.js.geom.heel_offset, point_forces(parts["lam_impact"] * W * 0.1, robot.mu))
    impact = (M[:6, :6] @ (v_plus - v_minus) - gen[:6])[SAGITTAL] / W
    rows = jn.nlp.constraints(x)[family(jn, "touchdown")]
    names = jn.row_names[family(jn, "touchdown")]
    np.testing.assert_allclose(rows[names == "touchdown_position"], bm - bp, atol=1e-10)
    np.testing.assert_allclose(rows[names == "impact"], impact, atol=1e-9)
    assert np.abs(impact).max() > 1e-2  # a non-trivial impact


def test_flight_torque_rows_match_numeric_pinocchio_on_the_exported_flight(small_jump, small_export):
    """With the flight's torque samples at 1 kHz times of the exported ballistic flight, the NLP's
    flight torque rows are numeric pinocchio.rnea's joint torques of the exported (q, v, a) over
    their limit range (the block computes the motion about the falling COM at zero pitch); the
    exported flight is ballistic (no base wrench), its base continuous at takeoff and off the
    landing's by the touchdown rows at touchdown."""
    sj, tr = small_jump, small_export
    model, ph, robot = sj.js.model, sj.js.phases, sj.robot
    data = model.createData()
    flight = np.where((tr["t"] > ph.takeoff) & (tr["t"] < ph.touchdown))[0]
    assert len(flight) > 300
    idx = flight[[0, 2, len(flight) // 3, len(flight) // 2, -3, -1]]
    jn = build_nlp(robot, sj.layer, sj.blocks, ph, sj.settings, sj.js.init["P"], "distance",
                   samples=dataclasses.replace(sj.nlp.meta["samples"], flight_torque=tr["t"][idx]))
    kept = robot.unmirrored
    sl = family(jn, "flight_torque")
    np.testing.assert_array_equal(np.unique(jn.meta["row_times"][sl]), tr["t"][idx])
    rows = jn.nlp.constraints(sj.x0)[sl].reshape(len(idx), len(kept))
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
    """At the interior flight nodes the clearance rows are the heel, ball and toe heights by
    forward kinematics of the flight state: the node's pitch, the COM on the parabola of the
    takeoff state, the base placed from the numeric COM."""
    sj = small_jump
    model, jn, ph, smap = sj.js.model, sj.nlp, sj.js.phases, sj.js.smap
    data = model.createData()
    parts = jn.variables.unpack(sj.x0)
    tf = jn.grid["flight"][1:-1]
    sl = family(jn, "flight_clearance")
    np.testing.assert_array_equal(np.unique(jn.meta["row_times"][sl]), tf)
    rows = jn.nlp.constraints(sj.x0)[sl].reshape(len(tf), 3)
    Y, Yd, _ = joint_motion(sj.layer, jn.splines[0], jn.control_points(sj.x0), tf)
    for k, t in enumerate(tf):
        T = t - ph.takeoff
        c = parts["c_to"] + parts["cd_to"] * T + 0.5 * GRAVITY * T ** 2
        cd = parts["cd_to"] + GRAVITY * T
        b, _ = flight_base(model, data, smap, Y[k], Yd[k], parts["pitch_flight"][k + 1], parts["L_to"][0], c, cd)
        q = full_state(smap, b, np.zeros(3), np.zeros(3), Y[k], Yd[k], np.zeros_like(Y[k]))[0]
        np.testing.assert_allclose(rows[k], foot_points(model, data, q, sj.js.geom.heel_offset)[2], atol=1e-10)
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
    n_nodes = sum(len(jn.grid[k]) for k in ("stance", "flight", "land"))
    assert (jn.row_names == "torque").sum() == n_nodes * len(robot.unmirrored)
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
