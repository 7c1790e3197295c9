"""Row blocks of the broad-jump NLP against numeric Pinocchio on the exported motion."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.jump.contact import TOE_PAD, foot_points, point_jacobians
from latentoc.jump.problem import consistent_start, initial_guess, trajectory
from latentoc.jump.support_polygon import polygon_from_vertices
from latentoc.jump.transcription import JumpSettings, RowModel, build_nlp, node_rows
from latentoc.jump.verify import sagittal_contact_wrench
from latentoc.jump.zmp import G


def test_wrench_rows_are_the_cone_of_the_needed_wrench(jump_setup):
    """wrench_rows at stance and landing samples: the needed wrench of numeric pinocchio.rnea
    on the exported 1 kHz motion (verify.sagittal_contact_wrench), its cone and its centre of
    pressure rows, in body weights, and the torques of the joints no foot force enters."""
    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False, base_model="pinned")
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    x = consistent_start(nlp, nlp.x0)
    parts = {k: np.array(v) for k, v in zip(nlp.unpack.name_out(), nlp.unpack(x))}
    tr = trajectory(js, {"settings": s, "parts": parts, "nlp": nlp})
    mass = sum(i.mass for i in js.model.inertias)
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass, "pinned")
    block, layout = node_rows(rm, jit=False, optional=("wrench_rows",))["wrench_rows"]
    sp, sps, spl = nlp.meta["splines"]
    ph, d = js.phases, js.model.createData()
    ids = [js.model.getFrameId(n) for n in ("ltoes_end", "rtoes_end")]
    checked = 0
    for i in (40, 150, 290, 720, 900, 1250):  # ms: stance (heel, ball, toe loaded), landing
        t = tr["t"][i]
        land = t >= ph.touchdown
        X = [sp.evaluate(parts["P"], np.array([t]), k)[0] for k in range(3)]
        phs, off = (spl, ph.touchdown) if land else (sps, 0.0)
        coef = parts["phi_l"] if land else parts["phi_s"]
        f = [phs.evaluate(coef, np.array([t - off]), k)[0, 0] for k in range(3)]
        u = np.concatenate([*X, f, [float(parts["x_L"].ravel()[0]) if land else 0.0]])
        r = np.array(block.rows(u)).ravel()
        q, v, a = tr["q"][i], tr["v"][i], tr["a"][i]
        tau = pin.rnea(js.model, d, q, v, a)
        pin.computeJointJacobians(js.model, d, q)
        pin.framesForwardKinematics(js.model, d, q)
        J = sum(pin.getFrameJacobian(js.model, d, k, pin.LOCAL_WORLD_ALIGNED) for k in ids)
        wrench = sagittal_contact_wrench(J, tau)
        fx, _, fz, _, my, _ = wrench / (mass * G)
        # the same sagittal wrench as point forces, split two ways (heel + toe tip, ball + toe
        # tip): the torques of the joints no foot force enters do not change, the legs' do
        Jp = point_jacobians(js.model, d, q, js.geom)
        split = []
        for back in (0, 1):
            C = np.column_stack([Jp[back].T[:, [0, 2]], Jp[2].T[:, 2]])  # (fx, fz) at back, fz at toe
            f = np.linalg.solve(C[[0, 2, 4]], (J.T @ wrench)[[0, 2, 4]])
            split.append((tau - C @ f)[6:][rm.active])
        ff = rm.force_free
        assert len(ff) == 30 and np.all(J[:, 6 + rm.active[ff]] == 0)
        assert np.allclose(split[0][ff], split[1][ff], atol=1e-6)
        assert np.max(np.abs(np.delete(split[0] - split[1], ff))) > 1.0
        heel, ball, toe = foot_points(js.model, d, js.geom).T
        expected = {"wrench_normal": [fz], "wrench_friction": [s.mu * fz - fx, s.mu * fz + fx], "cop_front": [my],
                    "cop_heel": [(toe[0] - heel[0]) * fz - my], "cop_ball": [(toe[0] - ball[0]) * fz - my],
                    "cop_pad": [TOE_PAD * fz - my],
                    # N m: the joints no foot force enters, numeric RNEA's torques
                    "torque_free": tau[6:][rm.active[ff]]}
        for name, val in expected.items():
            assert np.allclose(r[layout[name]], val, atol=1e-6 * max(1.0, abs(fz), np.max(np.abs(val)))), (t, name)
        checked += 1
    assert checked == 6


def test_wrench_samples_lie_between_the_nodes_with_the_scheduled_support(jump_setup):
    """With wrench_spacing the NLP gains one sample row set per interval slot, one just inside each
    unloaded interval of the schedule and one at each spline breakpoint of a contact phase (the
    splines' accelerations kink there); none at a node, and the rearmost support follows the
    contact schedule (heel, then ball, then toe pad)."""
    js = jump_setup
    base = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False, knot_nodes=True)
    dense = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False, wrench_spacing=0.02)
    n0, n1 = (build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, st, initial_guess(js, st), js.sym)
              for st in (base, dense))
    names = np.array(n1.names)
    assert not any(k.startswith(("wrench_", "cop_")) for k in n0.names)
    n_samples = int((names == "wrench_normal").sum())
    grid, tw = n1.meta["grid"], n1.meta["wrench_times"]
    ph = js.phases
    nodes = np.concatenate([grid["stance"], grid["land"]])
    assert len(tw) == n_samples and np.all(np.diff(tw) > 0)
    assert np.min(np.abs(tw[:, None] - nodes[None]), axis=1).min() > 1e-4
    assert np.all((tw < ph.takeoff) | (tw > ph.touchdown)) and tw.min() > 0 and tw.max() < ph.duration
    # every interval of 0.02 s spacing gets its even samples (linspace, ends excluded)
    for tn in (grid["stance"], grid["land"]):
        for a, b in zip(tn[:-1], tn[1:]):
            k = int(np.ceil((b - a) / 0.02 - 1e-9))
            for tk in np.linspace(a, b, k + 1)[1:-1]:
                assert np.min(np.abs(tw - tk)) < 1e-12
    switches = ph.switch_samples()  # one sample just inside each unloaded interval of the schedule
    assert len(switches) == 4 and np.allclose(switches, [ph.heel_off + 5e-4, ph.ball_off + 5e-4,
                                                         ph.ball_strike - 5e-4, ph.heel_strike - 5e-4])
    assert not any(ph.loaded(p, np.array([tk]))[0] for tk, p in zip(switches, ("heel", "ball", "ball", "heel")))
    sp, sps, spl = n1.meta["splines"]
    knots = np.concatenate([sp.breakpoints, sps.breakpoints, ph.touchdown + spl.breakpoints])
    knots = knots[((knots > 0) & (knots < ph.takeoff)) | ((knots > ph.touchdown) & (knots < ph.duration))]
    assert len(knots) > 10
    for tk in np.concatenate([switches, knots]):  # at a sample, or at a node already
        assert np.min(np.abs(np.concatenate([tw, nodes]) - tk)) <= 1e-4
    # knot_nodes: the contact grid is the uniform one plus every breakpoint; without, the uniform one
    uniform = ph.grid(5, 5, 6)
    for key in ("stance", "flight", "land"):
        assert np.array_equal(grid[key], uniform[key])
    g = n0.meta["grid"]
    c = np.concatenate([g["stance"], g["land"]])
    assert np.all(np.diff(g["stance"]) > 1e-4) and np.all(np.diff(g["land"]) > 1e-4)
    assert np.allclose(g["flight"], uniform["flight"])
    for tk in np.concatenate([uniform["stance"], uniform["land"], knots]):
        assert np.min(np.abs(c - tk)) <= 1e-4
    added = len(c) - len(uniform["stance"]) - len(uniform["land"])
    assert len(knots) - 3 <= added <= len(knots)
    assert (names == "wrench_friction").sum() == 2 * n_samples and (names == "cop_front").sum() == n_samples
    n_back = sum(int((names == k).sum()) for k in ("cop_heel", "cop_ball", "cop_pad"))
    assert n_back == n_samples and (names == "cop_pad").sum() > 0 and (names == "cop_heel").sum() > 0
    # trunk, neck, head and left arm joints (the right arm's rows are its mirror copies)
    assert (names == "torque_free").sum() == 18 * n_samples
    mass = sum(i.mass for i in js.model.inertias)
    with pytest.raises(ValueError, match="unknown optional row blocks"):
        node_rows(RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, 0.4, mass), jit=False, optional=("wrench",))


def test_right_torque_rows_left_out_are_mirror_copies_of_the_left(jump_setup):
    """The NLP keeps the torque rows of the centre and left joints only: on the exported motion,
    numeric pinocchio.rnea gives every right joint its left partner's torque times the mirror
    factor, and the training limits are mirror images, so the right rows would repeat the left.
    Limits that are not mirror images keep every row."""
    import dataclasses

    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    parts = {k: np.array(v) for k, v in zip(nlp.unpack.name_out(), nlp.unpack(consistent_start(nlp, nlp.x0)))}
    tr = trajectory(js, {"settings": s, "parts": parts, "nlp": nlp})
    mass = sum(i.mass for i in js.model.inertias)
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass)
    pairs = [(r - 7, int(js.smap.learned_q[y]) - 7, f) for r, y, f in js.smap.copied]
    right = {r for r, _, _ in pairs}
    assert len(pairs) == 19 and sorted(set(rm.active[rm.unmirrored]) & right) == []
    assert len(rm.unmirrored) == len(rm.active) - len(right & set(rm.active))
    names = np.array(nlp.names)
    n_nodes = len(nlp.meta["grid"]["stance"]) + len(nlp.meta["grid"]["flight"]) + len(nlp.meta["grid"]["land"])
    assert (names == "torque").sum() == n_nodes * len(rm.unmirrored)
    d = js.model.createData()
    for i in range(0, len(tr["t"]), 97):
        tau = pin.rnea(js.model, d, tr["q"][i], tr["v"][i], tr["a"][i])[6:]
        for r, left, f in pairs:
            assert abs(tau[r] - f * tau[left]) <= 1e-9 * max(1.0, np.abs(tau).max())
    lo, hi = js.limits.tau_min, js.limits.tau_max
    for r, left, f in pairs:
        assert np.allclose((lo[r], hi[r]), (lo[left], hi[left]) if f > 0 else (-hi[left], -lo[left]))
    skewed = dataclasses.replace(js.limits, tau_max=hi + np.eye(len(hi))[pairs[0][0]])
    rm2 = RowModel(js.sym, js.smap, js.gpdm, js.geom, skewed, s.mu, mass)
    assert np.array_equal(rm2.unmirrored, np.arange(len(rm2.active)))


def _spline_base_nlp(js, **kw):
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, jit=False, base_model="spline", **kw)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    x = consistent_start(nlp, nlp.x0)
    parts = {k: np.array(v) for k, v in zip(nlp.unpack.name_out(), nlp.unpack(x))}
    return s, nlp, parts, trajectory(js, {"settings": s, "parts": parts, "nlp": nlp})


def test_spline_base_contact_rows_match_numeric_pinocchio(jump_setup):
    """base_model="spline": at stance and landing nodes the contact rows equal numeric
    pinocchio.rnea minus the point forces' J^T f (body weights) on the exported motion, the joint
    torques, and the toe tip's offset from its ground point and the heel height from forward
    kinematics; the exported base is the spline base."""
    from latentoc.jump.base import base_to_freeflyer
    from latentoc.jump.contact import joint_embedding, point_forces, point_jacobians

    js = jump_setup
    s, nlp, parts, tr = _spline_base_nlp(js)
    mass = sum(i.mass for i in js.model.inertias)
    W = mass * G
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass, "spline")
    block, layout = node_rows(rm, jit=False)["contact_rows"]
    sp, sps, spl = nlp.meta["splines"]
    grid, ph, d = nlp.meta["grid"], js.phases, js.model.createData()
    node_t = np.concatenate([grid["stance"], grid["land"]])
    xL = float(parts["x_L"].ravel()[0])
    for j in (1, 3, len(grid["stance"]) + 2, len(node_t) - 2):
        t = node_t[j]
        land = t >= ph.touchdown
        i = int(np.argmin(np.abs(tr["t"] - t)))
        phs, off, coef = (spl, ph.touchdown, parts["phi_l"]) if land else (sps, 0.0, parts["phi_s"])
        X = [sp.evaluate(parts["P"], np.array([t]), k)[0] for k in range(3)]
        B = [phs.evaluate(coef, np.array([t - off]), k)[0] for k in range(3)]
        lam = np.asarray(parts["lam"])[:, j]
        r = np.array(block.rows(np.concatenate([*X, *B, [xL if land else 0.0], lam]))).ravel()
        # the motion at this instant, numerically
        q7, v6, a6 = base_to_freeflyer(*B)
        gp_y = np.array(js.gpdm.mean_function()(X[0])).ravel()
        E = joint_embedding(js.smap)
        q = np.concatenate([q7[0], E @ gp_y])
        np.testing.assert_allclose(q7[0], tr["q"][i][:7], atol=5e-3)  # the exporter's base at the nearest ms
        # v, a of the joints by finite differences of the GP mean along the spline
        h = 1e-5
        ys = [np.array(js.gpdm.mean_function()(sp.evaluate(parts["P"], np.array([t + e]), 0)[0])).ravel()
              for e in (-h, 0.0, h)]
        v = np.concatenate([v6[0], E @ (ys[2] - ys[0]) / (2 * h)])
        a = np.concatenate([a6[0], E @ (ys[2] - 2 * ys[1] + ys[0]) / h ** 2])
        tau = pin.rnea(js.model, d, q, v, a)
        Jp = point_jacobians(js.model, d, q, js.geom)
        f = np.array(point_forces(lam * W, s.mu))
        gen = sum(Jp[k].T @ np.array([f[k, 0], 0.0, f[k, 1]]) for k in range(3))
        np.testing.assert_allclose(r[layout["dynamics"]], (tau - gen)[[0, 2, 4]] / W, atol=2e-3)
        np.testing.assert_allclose(r[layout["torque"]], (tau - gen)[6:][rm.active], atol=0.5)
        heel, ball, toe = foot_points(js.model, d, js.geom).T
        np.testing.assert_allclose(r[layout["toe_position"]], [toe[0] - (xL if land else 0.0), toe[2]], atol=1e-9)
        np.testing.assert_allclose(r[layout["heel_height"]], [heel[2]], atol=1e-9)
        np.testing.assert_allclose(r[layout["ball_height"]], [ball[2]], atol=1e-9)
        # the projected COM against the polygon of both feet (heel_R, toe_R, toe_L, heel_L)
        A, b = polygon_from_vertices([[heel[0], -heel[1]], [toe[0], -toe[1]], toe[:2], heel[:2]])
        com = pin.centerOfMass(js.model, d, q)
        np.testing.assert_allclose(r[layout["com_polygon"]], A @ com[:2] + b, atol=1e-9)


def test_spline_base_takeoff_and_touchdown_rows_match_numeric_momentum(jump_setup):
    """base_model="spline": the takeoff rows are the stance state's COM, COM velocity and
    angular momentum about the COM (pinocchio.computeCentroidalMomentum) minus the flight's
    takeoff variables; the exported flight starts from that state (continuous base)."""
    from latentoc.jump.base import base_to_freeflyer
    from latentoc.jump.contact import joint_embedding

    js = jump_setup
    s, nlp, parts, tr = _spline_base_nlp(js)
    mass = sum(i.mass for i in js.model.inertias)
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass, "spline")
    block, layout = node_rows(rm, jit=False)["takeoff_rows"]
    sp, sps, _ = nlp.meta["splines"]
    t = np.array([js.phases.takeoff])
    X = [sp.evaluate(parts["P"], t, k)[0] for k in range(3)]
    B = [sps.evaluate(parts["phi_s"], t, k)[0] for k in range(3)]
    c_to, cd_to, L_to = (np.asarray(parts[k], float).ravel() for k in ("c_to", "cd_to", "L_to"))
    p0 = float(np.asarray(parts["pitch_flight"]).ravel()[0])
    r = np.array(block.rows(np.concatenate([*X, *B, c_to, cd_to, L_to, [p0]]))).ravel()
    E = joint_embedding(js.smap)
    h = 1e-6
    y = [np.array(js.gpdm.mean_function()(sp.evaluate(parts["P"], t + e, 0)[0])).ravel() for e in (-h, 0.0, h)]
    q7, v6, _ = base_to_freeflyer(B[0], B[1])
    q = np.concatenate([q7[0], E @ y[1]])
    v = np.concatenate([v6[0], E @ (y[2] - y[0]) / (2 * h)])
    d = js.model.createData()
    hg = pin.computeCentroidalMomentum(js.model, d, q, v)
    c = d.com[0]
    expected = np.concatenate([c[[0, 2]] - c_to, hg.linear[[0, 2]] / mass - cd_to, [hg.angular[1] - L_to[0]],
                               [B[0][2] - p0]])
    np.testing.assert_allclose(r, expected, atol=1e-6)
    # the flight variables of the start are this state, and the exported base is continuous
    np.testing.assert_allclose(r, 0.0, atol=1e-8)
    i = int(np.searchsorted(tr["t"], js.phases.takeoff))
    assert np.max(np.abs(tr["q"][i + 1][:3] - tr["q"][i][:3])) < 5e-3


def test_flight_rows_match_numeric_pinocchio_on_the_exported_flight(jump_setup):
    """At 1 kHz samples of the exported ballistic flight, the flight block's torque rows equal
    numeric pinocchio.rnea of the exported (q, v, a) and its clearance rows the heights of the
    heel, ball and toe points from forward kinematics (the block computes the motion about the
    COM and moves the points by the COM's ballistic path)."""
    from latentoc.jump.base import freeflyer_to_base

    js = jump_setup
    s, nlp, parts, tr = _spline_base_nlp(js)
    mass = sum(i.mass for i in js.model.inertias)
    rm = RowModel(js.sym, js.smap, js.gpdm, js.geom, js.limits, s.mu, mass, "spline")
    block, layout = node_rows(rm, jit=False)["flight_rows"]
    sp = nlp.meta["splines"][0]
    ph, d = js.phases, js.model.createData()
    c_to, cd_to, L_to = (np.asarray(parts[k], float).ravel() for k in ("c_to", "cd_to", "L_to"))
    flight = np.where((tr["t"] > ph.takeoff) & (tr["t"] < ph.touchdown))[0]
    for i in flight[[2, len(flight) // 3, len(flight) // 2, -3]]:
        t = tr["t"][i]
        X = [sp.evaluate(parts["P"], np.array([t]), k)[0] for k in range(3)]
        pitch = freeflyer_to_base(tr["q"][i][:7])[0, 2]
        u = np.concatenate([*X, [pitch], L_to, c_to, cd_to, [t - ph.takeoff]])
        r = np.array(block.rows(u)).ravel()
        tau = pin.rnea(js.model, d, tr["q"][i], tr["v"][i], tr["a"][i])
        np.testing.assert_allclose(r[layout["torque"]], tau[6:][rm.active], atol=1e-6 * max(1.0, np.abs(tau).max()))
        pin.framesForwardKinematics(js.model, d, tr["q"][i])
        np.testing.assert_allclose(r[layout["flight_clearance"]], foot_points(js.model, d, js.geom)[2], atol=1e-9)
