"""The assembled broad-jump NLP (latentoc.jump.transcription.nlp.build_nlp) on a jump with few nodes (every
row family, wrench samples every 50 ms): its exact derivatives against central differences, its
bounds and objectives, and its rows' identity across sample sets (the warm start's multipliers).

The Jacobian is compared along random directions and each block's first coordinate with central
differences of the constraints, the objective's gradient with those of the objective, and the exact Hessian of the Lagrangian
(sigma f + lam . g, upper triangle in its sparsity pattern) along random directions with
central differences of the Lagrangian's gradient (sigma grad f + J^T lam); each row against
its own scale, so a small row family's error is not hidden by a large one's.
"""
import numpy as np
import pytest
from finite_differences import central4, dense



def _points(sj):
    """The training start with random multipliers, and a random point near it with others."""
    rng = np.random.default_rng(11)
    x0, m = sj.x0, sj.nlp.nlp.m
    x1 = x0 + 0.02 * rng.standard_normal(x0.size) * np.maximum(1.0, np.abs(x0))
    return {"start": (x0, 1.0, rng.standard_normal(m)), "random": (x1, 0.7, rng.standard_normal(m))}


@pytest.fixture(scope="module", params=["start", "random"])
def point(request, small_jump):
    return (small_jump, *_points(small_jump)[request.param])


def test_jacobian_and_gradient_match_central_differences(point):
    """J v against fourth-order central differences of the constraints along random directions
    (which also find an entry missing from the sparsity pattern) and along each variable block's
    first coordinate, row by row relative to the row's size; the objective's gradient likewise."""
    sj, x, _, _ = point
    nlp, var = sj.nlp.nlp, sj.nlp.variables
    J = dense(nlp.jac_sparsity, nlp.jacobian(x))
    grad = nlp.gradient(x)
    assert J.shape == (nlp.m, x.size)
    rng = np.random.default_rng(13)
    directions = [rng.standard_normal(x.size) for _ in range(6)]
    directions += [np.eye(x.size)[var.slices[name].start] for name in var.shapes]
    for dv in directions:
        scale = np.maximum(1.0, np.abs(J) @ np.abs(dv))
        err = np.abs(central4(nlp.constraints, x, dv, h=1e-4) - J @ dv) / scale
        worst = int(np.argmax(err))
        assert err[worst] < 1e-7, (sj.nlp.row_names[worst], err[worst])
        assert abs(central4(nlp.objective, x, dv, h=1e-4) - grad @ dv) < 1e-7 * max(1.0, np.abs(grad) @ np.abs(dv))
    # every row family has entries, and the pattern is not padded with many structural zeros
    names = sj.nlp.row_names
    for name in set(names):
        assert np.abs(J[names == name]).max() > 0, name
    assert np.count_nonzero(J) > 0.5 * nlp.jac_sparsity.nnz()
    assert grad[sj.nlp.variables.index("x_L")[0]] == pytest.approx(-1.0)  # maximise the distance


def test_exact_hessian_matches_central_differences_of_the_lagrangian_gradient(point):
    """The Hessian of the Lagrangian (node Hessians through the GP layer's tangents and curvature,
    chained through the affine node inputs) against central differences of sigma grad f + J^T lam
    along random directions and along each variable block's first coordinate (fourth-order
    central differences)."""
    sj, x, sigma, lam = point
    nlp, var = sj.nlp.nlp, sj.nlp.variables
    Hu = dense(nlp.hess_sparsity, nlp.hessian(x, sigma, lam))
    assert np.allclose(np.tril(Hu, -1), 0.0)
    H = Hu + Hu.T - np.diag(np.diag(Hu))

    def grad_lagrangian(v):
        return sigma * nlp.gradient(v) + dense(nlp.jac_sparsity, nlp.jacobian(v)).T @ lam

    rng = np.random.default_rng(12)
    directions = [rng.standard_normal(x.size) for _ in range(4)]
    directions += [np.eye(x.size)[var.slices[name].start] for name in var.shapes]
    for dv in directions:
        fd = central4(grad_lagrangian, x, dv, h=1e-4)
        an = H @ dv
        scale = np.maximum(1.0, np.abs(H) @ np.abs(dv))
        assert np.max(np.abs(fd - an) / scale) < 3e-8
    # the objective's and the rows' parts separately: sigma alone, then the multipliers alone
    H_f = dense(nlp.hess_sparsity, nlp.hessian(x, sigma, np.zeros(nlp.m)))
    H_g = dense(nlp.hess_sparsity, nlp.hessian(x, 0.0, lam))
    np.testing.assert_allclose(H_f + H_g, Hu, atol=1e-9 * max(1.0, np.abs(Hu).max()))


def test_point_and_multipliers_follow_their_rows_into_an_nlp_with_more_samples(small_jump):
    """A solution carried into an NLP with more contact and flight samples (the exchange's next
    round, jump.warm): the shared variables keep their values, each carried row has the same value
    there, the new samples' rows get zero multipliers and hold at the carried point (their
    variables follow from the rest), and lam . g is unchanged."""
    from latentoc.jump.transcription.nlp import build_nlp
    from latentoc.jump.transcription.selection import Selection
    from latentoc.jump.solve.warm import carried_multipliers, carried_point

    sj = small_jump
    old = sj.nlp
    nk = sj.robot.unmirrored.size
    extra = Selection(np.zeros((12, nk)), np.zeros((12, 8)), np.array([0.1234, 0.9123]), np.ones((2, nk)),
                      np.zeros((2, 8)), np.array([0.5]), np.ones((1, nk)), np.zeros(0))
    new = build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "distance",
                    old.selection.merged(extra))
    assert new.nlp.m > old.nlp.m and new.variables.n == old.variables.n + 2 * 8 + 4
    x, _ = carried_point(old, new, sj.x0)
    for name in old.variables.shapes:
        if name not in ("lam_sample", "flight_sample"):
            np.testing.assert_array_equal(new.variables.unpack(x)[name], old.variables.unpack(sj.x0)[name])
    lam = np.random.default_rng(13).uniform(0.5, 1.5, old.nlp.m)
    carried = carried_multipliers(old, new, lam)
    g_old, g_new = old.nlp.constraints(sj.x0), new.nlp.constraints(x)
    times = np.round(new.row_times, 9)
    fams = np.empty(new.nlp.m, object)
    for f in new.nlp.families:
        fams[new.family_rows(f.name)] = f.name
    sampled = np.isin(fams, ["contact_sample", "flight", "flight_pitch"])
    at_new = sampled & np.isin(times, [0.1234, 0.9123, 0.5])
    assert np.all(carried[at_new] == 0) and np.all(carried[~at_new] > 0)
    assert (~at_new).sum() == old.nlp.m
    np.testing.assert_array_equal(np.sort(carried[~at_new]), np.sort(lam))
    assert carried @ g_new == pytest.approx(lam @ g_old, rel=1e-12)
    # the new samples' equality rows hold where their variables were solved for
    eq = at_new & np.isin(new.row_names, ["flight_base", "pitch_rate"])
    assert eq.sum() == 4 and np.abs(g_new[eq]).max() < 1e-9
    for name in set(old.row_names):  # the same rows in the same order, family by family
        np.testing.assert_allclose(g_new[~at_new][new.row_names[~at_new] == name], g_old[old.row_names == name],
                                   rtol=1e-12, atol=1e-12)


def test_row_and_variable_bounds(small_jump):
    """Torque rows bounded by the training limits (held TORQUE_BACKOFF inside them) over their range
    (per joint, at every node and sample), the contact schedule in the heights' rows (an unloaded
    point above the ground), the centre of pressure by the loaded support, the transitions as
    equalities, polygons, flight clearance and tube one-sided as the module doc says; edge
    weights >= 0 and zero on the unloaded points."""
    from latentoc.jump.robot.feet import POINTS
    from latentoc.jump.transcription.nlp import TORQUE_BACKOFF, TUBE_BACKOFF

    sj = small_jump
    jn, robot, ph = sj.nlp, sj.robot, sj.js.phases
    names, lbg, ubg, comps = jn.row_names, jn.lbg, jn.ubg, jn.row_components
    lo, hi, act, scale = robot.limits.tau_min, robot.limits.tau_max, robot.active, robot.torque_scale
    sel = names == "torque"
    assert sel.sum() > 0 and set(comps[sel]) == set(robot.unmirrored)
    np.testing.assert_allclose(lbg[sel] * scale[comps[sel]], lo[act][comps[sel]] + TORQUE_BACKOFF, rtol=1e-12)
    np.testing.assert_allclose(ubg[sel] * scale[comps[sel]], hi[act][comps[sel]] - TORQUE_BACKOFF, rtol=1e-12)
    t = jn.row_times
    # an unloaded point's height above its standing one, at every contact node and sample (the
    # loaded ones hold theirs by the closure)
    h = names == "height"
    pts = np.array(POINTS)[comps[h]]
    assert h.any() and not any(ph.loaded(p, np.array([tk]))[0] for p, tk in zip(pts, t[h]))
    assert {"heel", "ball"} <= set(pts)
    np.testing.assert_array_equal(lbg[h], 0.0)
    np.testing.assert_array_equal(ubg[h], np.inf)
    # one centre-of-pressure row for the rearmost loaded point at every node and contact sample
    back = names[np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
    tb = t[np.isin(names, ["cop_heel", "cop_ball", "cop_pad"])]
    want = np.where(ph.loaded("heel", tb), "cop_heel", np.where(ph.loaded("ball", tb), "cop_ball", "cop_pad"))
    np.testing.assert_array_equal(back, want)
    assert len(back) == (names == "cop_front").sum() == 12 + len(jn.selection.contact)
    one_sided = {"dynamics": (0, 0), "takeoff": (0, 0), "closure_gap": (0, 0), "hinge_switch": (0, 0),
                 "touchdown_velocity": (0, 0), "touchdown_position": (0, 0), "pitch_integration": (0, 0),
                 "flight_base": (0, 0), "pitch_rate": (0, 0),
                 "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0), "flight_clearance": (0, np.inf),
                 "tube": (-np.inf, 1.0 - TUBE_BACKOFF), "cop_front": (0, np.inf), "cop_heel": (0, np.inf), "cop_ball": (0, np.inf),
                 "cop_pad": (0, np.inf)}
    assert set(one_sided) | {"torque", "height"} == set(names)
    for part, (a, b) in one_sided.items():
        assert np.all(lbg[names == part] == a) and np.all(ubg[names == part] == b), part
    var = jn.variables
    for block, times in (("lam", np.concatenate([jn.grid["stance"], jn.grid["land"]])), ("lam_sample", jn.selection.contact)):
        ub = jn.ubx[var.index(block)]
        assert np.all(jn.lbx[var.index(block)] == 0)
        for k, point in enumerate(POINTS):
            np.testing.assert_array_equal(ub[:, 2 * k:2 * k + 2] == 0,
                                          np.repeat(~ph.loaded(point, times)[:, None], 2, axis=1))
    bounded = np.concatenate([var.index(b).ravel() for b in ("lam", "lam_sample")])
    others = np.setdiff1d(np.arange(var.n), bounded)
    assert np.all(np.isinf(jn.lbx[others])) and np.all(np.isinf(jn.ubx[others]))


def test_objectives(small_jump):
    """Objective "distance": minus the landing point x_L (Eq. 33) plus the tiny force regulariser;
    "feasibility": the squared deviation of the free latent control points from the training
    fit (zero at the start) plus the same regulariser; another objective is refused by name."""
    from latentoc.jump.transcription.nlp import FORCE_REGULARISATION, build_nlp

    sj = small_jump
    parts = sj.nlp.variables.unpack(sj.x0)
    reg = FORCE_REGULARISATION * (np.sum(parts["lam"] ** 2) + np.sum(parts["lam_sample"] ** 2))
    assert sj.nlp.nlp.objective(sj.x0) == pytest.approx(-parts["x_L"][0] + reg, rel=1e-12)
    feas = build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "feasibility",
                     sj.nlp.selection)
    assert feas.nlp.objective(sj.x0) == pytest.approx(reg, rel=1e-12)
    x = np.array(sj.x0)
    P = feas.variables.index("P")
    x[P[0, 0]] += 0.1
    P_all = sj.js.init["P"]
    assert feas.nlp.objective(x) == pytest.approx(reg + 0.01 / np.mean(P_all ** 2), rel=1e-9)
    with pytest.raises(ValueError, match="objective must be one of .*'feasibility', 'distance'.*got 'speed'"):
        build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "speed")
