"""The assembled broad-jump NLP (latentoc.jump.nlp.build_nlp) on a jump with few nodes (every
row family, wrench samples every 50 ms): its exact derivatives against central differences, its
bounds and objectives, and its rows' identity across sample sets (the warm start's multipliers).

The Jacobian is compared column by column with central differences of the constraints, the
objective's gradient with those of the objective, and the exact Hessian of the Lagrangian
(sigma f + lam . g, upper triangle in its sparsity pattern) along random directions with
central differences of the Lagrangian's gradient (sigma grad f + J^T lam); each row against
its own scale, so a small row family's error is not hidden by a large one's.
"""
import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp

H_FD = 1e-6


def _csc(sparsity, values):
    return sp.csc_matrix((values, np.array(sparsity.row()), np.array(sparsity.colind())),
                         shape=(sparsity.size1(), sparsity.size2())).toarray()


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
    """Every column of the sparse Jacobian (its pattern included) against central differences of
    the constraints, row by row relative to the row's largest entry; the objective's gradient
    against central differences of the objective."""
    sj, x, _, _ = point
    nlp = sj.nlp.nlp
    J = _csc(nlp.jac_sparsity, nlp.jacobian(x))
    grad = nlp.gradient(x)
    assert J.shape == (nlp.m, x.size)
    fd, fd_grad = np.empty_like(J), np.empty_like(grad)
    for j in range(x.size):
        e = np.zeros(x.size)
        e[j] = H_FD
        fd[:, j] = (nlp.constraints(x + e) - nlp.constraints(x - e)) / (2 * H_FD)
        fd_grad[j] = (nlp.objective(x + e) - nlp.objective(x - e)) / (2 * H_FD)
    scale = np.maximum(1.0, np.abs(J).max(axis=1))
    err = np.abs(fd - J).max(axis=1) / scale
    worst = int(np.argmax(err))
    assert err[worst] < 1e-6, (sj.nlp.row_names[worst], err[worst])
    # every row family has entries, and the pattern is not padded with many structural zeros
    names = sj.nlp.row_names
    for name in set(names):
        assert np.abs(J[names == name]).max() > 0, name
    assert np.count_nonzero(J) > 0.5 * nlp.jac_sparsity.nnz()
    np.testing.assert_allclose(grad, fd_grad, atol=1e-7)
    assert grad[sj.nlp.variables.index("x_L")[0]] == pytest.approx(-1.0)  # maximise the distance


def test_exact_hessian_matches_central_differences_of_the_lagrangian_gradient(point):
    """The Hessian of the Lagrangian (node Hessians through the GP layer's tangents and curvature,
    chained through the affine node inputs) against central differences of sigma grad f + J^T lam
    along random directions and along each variable block's first coordinate (fourth-order
    central differences)."""
    sj, x, sigma, lam = point
    nlp, var = sj.nlp.nlp, sj.nlp.variables
    Hu = _csc(nlp.hess_sparsity, nlp.hessian(x, sigma, lam))
    assert np.allclose(np.tril(Hu, -1), 0.0)
    H = Hu + Hu.T - np.diag(np.diag(Hu))

    def grad_lagrangian(v):
        return sigma * nlp.gradient(v) + _csc(nlp.jac_sparsity, nlp.jacobian(v)).T @ lam

    rng = np.random.default_rng(12)
    directions = [rng.standard_normal(x.size) for _ in range(4)]
    directions += [np.eye(x.size)[var.slices[name].start] for name in var.shapes]
    h = 1e-4  # fourth-order central differences: rounding, not truncation, at 1e-6
    for dv in directions:
        fd = (8 * (grad_lagrangian(x + h * dv) - grad_lagrangian(x - h * dv))
              - (grad_lagrangian(x + 2 * h * dv) - grad_lagrangian(x - 2 * h * dv))) / (12 * h)
        an = H @ dv
        scale = np.maximum(1.0, np.abs(H) @ np.abs(dv))
        assert np.max(np.abs(fd - an) / scale) < 3e-8
    # the objective's and the rows' parts separately: sigma alone, then the multipliers alone
    H_f = _csc(nlp.hess_sparsity, nlp.hessian(x, sigma, np.zeros(nlp.m)))
    H_g = _csc(nlp.hess_sparsity, nlp.hessian(x, 0.0, lam))
    np.testing.assert_allclose(H_f + H_g, Hu, atol=1e-9 * max(1.0, np.abs(Hu).max()))


def test_multipliers_follow_their_rows_into_an_nlp_with_more_samples(small_jump):
    """A warm start's multipliers carried to an NLP with more wrench and flight torque samples
    (solve.carried_multipliers) sit on the same constraints: each carried row has the same value
    there, the new samples' rows get zero, and lam . g is unchanged."""
    from latentoc.jump.nlp import Samples, build_nlp
    from latentoc.jump.solve import carried_multipliers

    sj = small_jump
    old = sj.nlp
    none = Samples(**{f.name: np.zeros(0) for f in dataclasses.fields(Samples)})
    extra = dataclasses.replace(none, wrench=np.array([0.1234, 0.9]), flight_torque=np.array([0.5]))
    new = build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "distance",
                    samples=old.meta["samples"].merged(extra))
    assert new.nlp.m > old.nlp.m and new.variables.n == old.variables.n
    lam = np.random.default_rng(13).uniform(0.5, 1.5, old.nlp.m)
    carried = carried_multipliers(old, new, lam)
    g_old, g_new = old.nlp.constraints(sj.x0), new.nlp.constraints(sj.x0)
    sampled = np.zeros(new.nlp.m, bool)  # the rows of the families placed at the samples
    for f in new.nlp.families:
        if f.name in ("wrench", "flight_torque"):
            sampled[new.nlp.row_offset[f.name]:new.nlp.row_offset[f.name] + f.n_rows] = True
    times = np.round(new.meta["row_times"], 9)
    at_new = sampled & np.isin(times, np.round(np.concatenate([extra.wrench, extra.flight_torque]), 9))
    assert np.all(carried[at_new] == 0) and np.all(carried[~at_new] > 0)
    assert (~at_new).sum() == old.nlp.m and at_new.sum() == new.nlp.m - old.nlp.m
    np.testing.assert_array_equal(np.sort(carried[~at_new]), np.sort(lam))
    assert carried @ g_new == pytest.approx(lam @ g_old, rel=1e-12)
    for name in set(old.row_names):  # the same rows in the same order, family by family
        np.testing.assert_allclose(g_new[~at_new][new.row_names[~at_new] == name], g_old[old.row_names == name],
                                   rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(carried[~at_new][new.row_names[~at_new] == name], lam[old.row_names == name])


def test_row_and_variable_bounds(small_jump):
    """Torque rows bounded by the training limits over their range (per joint, at every node and
    sample), the contact schedule in the heel and ball bounds (a loaded point on the ground within
    the contact tolerance, an unloaded ball above the soft-sole depth), the feet, cones, polygons,
    flight clearance and tube one-sided as the module doc says; edge weights >= 0 and zero on
    the unloaded points."""
    sj = small_jump
    jn, robot, s, ph = sj.nlp, sj.robot, sj.settings, sj.js.phases
    names, lbg, ubg = jn.row_names, jn.lbg, jn.ubg
    lo, hi, act, scale = robot.limits.tau_min, robot.limits.tau_max, robot.active, robot.torque_scale
    for part, pos in (("torque", robot.unmirrored), ("torque_free", np.intersect1d(robot.force_free, robot.unmirrored))):
        sel = names == part
        n = sel.sum() // len(pos)
        assert n * len(pos) == sel.sum() and n > 0
        np.testing.assert_allclose(lbg[sel].reshape(n, -1) * scale[pos], np.tile(lo[act[pos]], (n, 1)), rtol=1e-12)
        np.testing.assert_allclose(ubg[sel].reshape(n, -1) * scale[pos], np.tile(hi[act[pos]], (n, 1)), rtol=1e-12)
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    heel, ball = ph.loaded("heel", tc), ph.loaded("ball", tc)
    ct = s.contact_tolerance
    np.testing.assert_array_equal(lbg[names == "heel_height"], -ct)
    np.testing.assert_array_equal(ubg[names == "heel_height"], np.where(heel, ct, np.inf))
    np.testing.assert_array_equal(lbg[names == "ball_height"], np.where(ball, -ct, -s.ball_tolerance))
    np.testing.assert_array_equal(ubg[names == "ball_height"], np.where(ball, ct, np.inf))
    assert not heel.all() and not ball.all() and heel.any() and ball.any()
    one_sided = {"toe_position": (-s.foot_tolerance, s.foot_tolerance), "dynamics": (0, 0), "takeoff": (0, 0),
                 "impact": (0, 0), "touchdown_position": (0, 0), "pitch_integration": (0, 0),
                 "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0), "flight_clearance": (0, np.inf),
                 "tube": (-np.inf, 1.0), "wrench_normal": (0, np.inf), "wrench_friction": (0, np.inf),
                 "cop_front": (0, np.inf), "cop_heel": (0, np.inf), "cop_ball": (0, np.inf), "cop_pad": (0, np.inf)}
    assert set(one_sided) | {"torque", "torque_free", "heel_height", "ball_height"} == set(names)
    for part, (a, b) in one_sided.items():
        assert np.all(lbg[names == part] == a) and np.all(ubg[names == part] == b), part
    var = jn.variables
    lam_ub = jn.ubx[var.index("lam")]
    assert np.all(jn.lbx[var.index("lam")] == 0) and np.all(jn.lbx[var.index("lam_impact")] == 0)
    np.testing.assert_array_equal(lam_ub[:, :2] == 0, np.repeat(~heel[:, None], 2, axis=1))
    np.testing.assert_array_equal(lam_ub[:, 2:4] == 0, np.repeat(~ball[:, None], 2, axis=1))
    assert np.all(np.isinf(lam_ub[:, 4:]))
    others = np.setdiff1d(np.arange(var.n), np.concatenate([var.index("lam").ravel(), var.index("lam_impact")]))
    assert np.all(np.isinf(jn.lbx[others])) and np.all(np.isinf(jn.ubx[others]))


def test_objectives(small_jump):
    """Objective "distance": minus the landing point x_L (Eq. 33) plus the tiny force regulariser;
    "feasibility": the squared deviation of the free latent control points from the training
    fit (zero at the start) plus the same regulariser; another objective is refused by name."""
    from latentoc.jump.nlp import FORCE_REGULARISATION, build_nlp

    sj = small_jump
    parts = sj.nlp.variables.unpack(sj.x0)
    reg = FORCE_REGULARISATION * (np.sum(parts["lam"] ** 2) + np.sum(parts["lam_impact"] ** 2))
    assert sj.nlp.nlp.objective(sj.x0) == pytest.approx(-parts["x_L"][0] + reg, rel=1e-12)
    feas = build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "feasibility")
    assert feas.nlp.objective(sj.x0) == pytest.approx(reg, rel=1e-12)
    x = np.array(sj.x0)
    P = feas.variables.index("P")
    x[P[0, 0]] += 0.1
    P_all = sj.js.init["P"]
    assert feas.nlp.objective(x) == pytest.approx(reg + 0.01 / np.mean(P_all ** 2), rel=1e-9)
    with pytest.raises(ValueError, match="objective must be one of .*'feasibility', 'distance'.*got 'speed'"):
        build_nlp(sj.robot, sj.layer, sj.blocks, sj.js.phases, sj.settings, sj.js.init["P"], "speed")
