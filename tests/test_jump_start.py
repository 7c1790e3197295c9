"""The training start (latentoc.jump.solve.initial_point.initial_point, balanced_forces) and the smoothed
initial latent path (latentoc.jump.schedule.path.initial_latent_path)."""
import numpy as np
import pinocchio as pin

from jump_reference import SAGITTAL, generalized_force, point_forces
from latentoc.jump.solve.initial_point import balanced_forces


def _node_base_rows(sj, parts, t):
    """The sagittal base rows at contact time t as c - A lam (body weights): c from numeric
    rnea, A the generalized force of a unit weight on each pyramid edge."""
    from test_jump_rows import state_at

    js, robot = sj.js, sj.robot
    model = js.model
    data = model.createData()
    q, v, a = state_at(sj, parts, t)
    W = robot.weight
    c = pin.rnea(model, data, q, v, a)[SAGITTAL] / W
    A = np.column_stack([generalized_force(model, data, q, js.geom, point_forces(e, robot.mu))[SAGITTAL]
                         for e in np.eye(8)])
    return c, A


def test_initial_point_takes_the_flight_from_the_closed_stance(small_jump):
    """The start's latent control points and landing point are the set-up's; the variables are within
    their bounds; the flight's takeoff state is the closed stance's at takeoff (the takeoff rows
    hold but for the legs' gap to the GP mean) and its pitch the ballistic one (the pitch rows hold)."""
    sj = small_jump
    js, jn = sj.js, sj.nlp
    parts = jn.variables.unpack(sj.x0)
    np.testing.assert_array_equal(jn.control_points(sj.x0), js.init["P"])
    assert parts["x_L"][0] == js.init["x_L"]
    assert np.all(sj.x0 >= jn.lbx) and np.all(sj.x0 <= jn.ubx)
    g = jn.nlp.constraints(sj.x0)
    sl = jn.family_rows("takeoff")
    np.testing.assert_allclose(g[sl][jn.row_names[sl] == "takeoff"], 0.0, atol=1e-10)
    np.testing.assert_allclose(g[jn.family_rows("pitch_integration")], 0.0, atol=1e-10)


def test_balanced_forces_fit_the_base_rows_with_nonnegative_loaded_edges(small_jump):
    """The start's edge weights are >= 0, zero on the edges the contact schedule unloads (bounded
    to zero: the heel after heel-off, before heel strike), and at every contact node the
    non-negative least-squares fit of the sagittal base rows of numeric rnea over the loaded edges
    (KKT conditions with the edge forces from numeric Pinocchio); no node's residual is worse than
    with the uniform guess. Refitting from other weights changes only the weights, back to these."""
    sj = small_jump
    jn, ph = sj.nlp, sj.js.phases
    parts = jn.variables.unpack(sj.x0)
    lam = parts["lam"]
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    ub = jn.ubx[jn.variables.index("lam")]
    loaded = np.repeat(np.column_stack([ph.loaded(p, tc) for p in ("heel", "ball", "toe", "pad")]), 2, axis=1)
    np.testing.assert_array_equal(ub > 0, loaded)
    assert (~loaded[:, 0]).sum() >= 2 and loaded[:, 4].all()
    assert np.all(lam >= 0) and np.all(lam[~loaded] == 0)
    for k, t in enumerate(tc):
        c, A = _node_base_rows(sj, parts, t)
        grad = A.T @ (A @ lam[k] - c)
        tol = 1e-8 * max(1.0, np.abs(A).max() * np.abs(c).max())
        assert np.all(grad[loaded[k]] >= -tol), (k, grad)
        assert np.all(np.abs(grad[loaded[k] & (lam[k] > 1e-9)]) <= tol), (k, grad)
        uniform = np.where(loaded[k], 1.0 / 16.0, 0.0)
        assert np.linalg.norm(c - A @ lam[k]) <= np.linalg.norm(c - A @ uniform) + 1e-12
    # the NLP's dynamics rows at the start are these residuals
    dyn = jn.nlp.constraints(sj.x0)[jn.family_rows("contact")][jn.row_names[jn.family_rows("contact")] == "dynamics"]
    dyn = dyn.reshape(-1, 3)
    assert dyn.shape == (len(tc), 3) and np.linalg.norm(dyn) > 0
    x = np.array(sj.x0)
    x[jn.variables.index("lam")] = np.random.default_rng(2).uniform(0.0, 1.0, lam.shape)
    refit = balanced_forces(jn, x)
    np.testing.assert_allclose(refit, sj.x0, atol=1e-9)


def test_initial_latent_path_keeps_the_kept_state_and_smooths_the_rest():
    """Equality-constrained smoothing: at the kept times the value and velocity equal the plain
    fit's (to solver precision), the end control points stay, and the curvature integral drops."""
    from latentoc.jump.schedule.path import initial_latent_path
    from latentoc.latent.spline import BSpline

    sp = BSpline(15, 1.3)
    t = np.linspace(0.0, 1.3, 157)
    rng = np.random.default_rng(1)
    X = np.column_stack([np.sin(5 * t), np.cos(3 * t), t]) + 0.05 * rng.standard_normal((157, 3))
    keep = np.array([0.31, 0.69])
    plain, P = sp.fit(t, X), initial_latent_path(sp, t, X, 1e-3, keep)
    for j in (0, 1):
        assert np.allclose(sp.evaluate(P, keep, j), sp.evaluate(plain, keep, j), atol=1e-9)
    assert np.array_equal(P[[0, -1]], plain[[0, -1]])
    S = sp.smoothing_rows(1.0)
    curv = [np.sum((S @ Q) ** 2) for Q in (plain, P, initial_latent_path(sp, t, X, 1e-1, keep))]
    assert curv[0] > curv[1] > curv[2]
    assert np.array_equal(initial_latent_path(sp, t, X, 0.0, keep), plain)
