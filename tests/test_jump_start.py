"""The training start (latentoc.jump.start.initial_point, balanced_forces) and the smoothed
initial latent path (latentoc.jump.problem.initial_latent_path)."""
import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicSpline

from jump_reference import SAGITTAL, foot_points, generalized_force, point_forces
from latentoc.jump.contact import POINTS
from latentoc.jump.start import balanced_forces
from test_jump_rows import state_at


def _node_base_rows(sj, x, t):
    """The sagittal base rows at contact time t as c - A lam (body weights): c from numeric
    rnea on the anchored base (test_jump_rows.state_at), A the generalized force of a unit weight
    on each pyramid edge."""
    js, robot = sj.js, sj.robot
    model = js.model
    data = model.createData()
    q, v, a = state_at(sj, x, t)
    W = robot.weight
    c = pin.rnea(model, data, q, v, a)[SAGITTAL] / W
    A = np.column_stack([generalized_force(model, data, q, js.geom, point_forces(e, robot.mu))[SAGITTAL]
                         for e in np.eye(8)])
    return c, A


def test_initial_point_fits_the_training_motion(small_jump):
    """The start's latent control points and landing point are the set-up's (where the planted
    training jump's toe point lands, sideways by y_L); its rolling toes' pitch splines are
    least-squares fits (normal equations) of the (planted) training base pitch, interpolated by a
    cubic spline (scipy), at four points per control point of each rolling window, and follow it to
    0.01 rad; the variables are within their bounds; the touchdown impulse is the uniform guess on
    the loaded point (the landing rolls on the toe point alone)."""
    sj = small_jump
    js, jn, ph = sj.js, sj.nlp, sj.js.phases
    parts = jn.variables.unpack(sj.x0)
    np.testing.assert_array_equal(jn.control_points(sj.x0), js.init["P"])
    assert parts["x_L"][0] == js.init["x_L"] and parts["y_L"][0] == js.init["y_L"]
    # the landing point is where the planted training jump's toes land (forward kinematics): the toe
    # point on the landing's flat toes at (x_L, ground_y + y_L, 0)
    model, data = js.model, js.model.createData()
    tr = js.training
    landed = (tr.t >= ph.touchdown - 1e-9) & ~ph.pivot(tr.t)
    toe = np.array([foot_points(model, data, q, js.geom)[:, 2] for q in tr.Q[landed]])
    np.testing.assert_allclose(toe, np.broadcast_to([js.init["x_L"], js.geom.ground_y[2] + js.init["y_L"], 0.0],
                                                    toe.shape), atol=1e-9)
    assert np.all(sj.x0 >= jn.lbx) and np.all(sj.x0 <= jn.ubx)
    t, base = js.init["t"], js.init["base"]
    np.testing.assert_array_equal(base, js.training.base)
    pitch = CubicSpline(t, base[:, 2])
    windows = [(t0, t0 + sp_.duration) for t0, sp_ in jn.rolls]
    np.testing.assert_allclose(windows, [(ph.ball_off, ph.takeoff), (ph.touchdown, ph.ball_strike)], atol=1e-12)
    off = 0
    for t0, sp_ in jn.rolls:
        assert sp_.n_control == max(4, int(round(sp_.duration / sj.settings.roll_spacing)) + 3)
        coef = parts["roll"][off:off + sp_.n_control]
        off += sp_.n_control
        tk = np.linspace(0.0, sp_.duration, 4 * sp_.n_control)
        B = sp_.basis(tk)
        resid = B @ coef - pitch(t0 + tk)
        np.testing.assert_allclose(B.T @ resid, 0.0, atol=1e-9)
        assert np.abs(resid).max() < 0.01  # rad
        inside = (t >= t0) & (t <= t0 + sp_.duration)
        np.testing.assert_allclose(jn.roll_pitch(sj.x0, t[inside])[:, 0], base[inside, 2], atol=0.01)
    assert off == len(parts["roll"])
    at_touchdown = [ph.loaded(p, np.array([ph.touchdown]))[0] for p in POINTS]
    assert at_touchdown == [False, False, True, False]  # the landing rolls on the toe point
    np.testing.assert_array_equal(parts["lam_impact"], 0.5 * np.repeat(at_touchdown, 2))


def test_balanced_forces_fit_the_base_rows_with_nonnegative_loaded_edges(small_jump):
    """The start's edge weights are >= 0, zero on the edges the contact schedule unloads (bounded
    to zero: the heel after heel-off, before heel strike; the toe point and the pad on the flat
    foot) and on every edge of the nodes inside a rolling window (they carry no rows), and at every
    other contact node the non-negative least-squares fit of the sagittal base rows of numeric rnea
    on the anchored base over the loaded edges (KKT conditions with the edge forces from numeric
    Pinocchio); no node's residual is worse than with the uniform guess. Refitting from other
    weights changes only the weights, back to these."""
    sj = small_jump
    jn, ph = sj.nlp, sj.js.phases
    parts = jn.variables.unpack(sj.x0)
    lam = parts["lam"]
    tc = np.concatenate([jn.grid["stance"], jn.grid["land"]])
    ub = jn.ubx[jn.variables.index("lam")]
    rolling = ph.pivot(tc)
    loaded = np.repeat(np.column_stack([ph.loaded(p, tc) for p in POINTS]), 2, axis=1) & ~rolling[:, None]
    np.testing.assert_array_equal(ub > 0, loaded)
    assert (~loaded[:, 0]).sum() >= 2 and rolling.sum() == 2
    np.testing.assert_array_equal(loaded[:, 4], ~ph.flat(tc) & ~rolling)  # the toe point off the flat foot
    assert np.all(lam >= 0) and np.all(lam[~loaded] == 0)
    residuals = []
    for k, t in enumerate(tc):
        if rolling[k]:
            continue
        c, A = _node_base_rows(sj, sj.x0, t)
        residuals.append(c - A @ lam[k])
        grad = A.T @ (A @ lam[k] - c)
        tol = 1e-8 * max(1.0, np.abs(A).max() * np.abs(c).max())
        assert np.all(grad[loaded[k]] >= -tol), (k, grad)
        assert np.all(np.abs(grad[loaded[k] & (lam[k] > 1e-9)]) <= tol), (k, grad)
        uniform = np.where(loaded[k], 1.0 / 16.0, 0.0)
        assert np.linalg.norm(c - A @ lam[k]) <= np.linalg.norm(c - A @ uniform) + 1e-12, k
    # the NLP's dynamics rows at the start are these residuals, at the nodes outside the rolling windows
    sl = jn.family_rows("contact")
    dyn = jn.nlp.constraints(sj.x0)[sl][jn.row_names[sl] == "dynamics"].reshape(-1, 3)
    assert dyn.shape == ((~rolling).sum(), 3) and np.linalg.norm(dyn) > 0
    np.testing.assert_allclose(dyn, residuals, atol=1e-9)
    x = np.array(sj.x0)
    x[jn.variables.index("lam")] = np.random.default_rng(2).uniform(0.0, 1.0, lam.shape)
    refit = balanced_forces(jn, x)
    np.testing.assert_allclose(refit, sj.x0, atol=1e-9)


def test_initial_latent_path_keeps_the_kept_state_and_smooths_the_rest():
    """Equality-constrained smoothing: at the kept times the value and velocity equal the plain
    fit's (to solver precision), the end control points stay, and the curvature integral drops."""
    from latentoc.jump.problem import initial_latent_path
    from latentoc.spline import BSpline

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
