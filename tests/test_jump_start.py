"""The phase-1 start: training guess made consistent with the NLP's linear equalities."""
import numpy as np
import pytest

from latentoc.jump.problem import consistent_start, initial_guess
from latentoc.jump.transcription import JumpSettings, build_nlp


def test_consistent_start_fits_nonnegative_forces(jump_setup):
    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    names = np.array(nlp.names)
    x = consistent_start(nlp, nlp.x0)
    g0, g1 = (np.array(nlp.meta["g_fun"](v)).ravel() for v in (nlp.x0, x))
    a, b = nlp.meta["sizes"]["lam"]
    assert np.all(x[a:b] >= 0)
    # contact schedule: the heel is unloaded at the stance's last node (after heel-off) and the
    # landing's first (before heel strike); those generators are bounded to zero and stay zero
    tc = np.concatenate([nlp.meta["grid"]["stance"], nlp.meta["grid"]["land"]])
    ub = nlp.ubx[a:b].reshape(-1, 6)
    assert np.array_equal(ub[:, 0] == 0, ~js.phases.loaded("heel", tc)) and (ub[:, 0] == 0).sum() >= 2
    assert np.array_equal(ub[:, 2] == 0, ~js.phases.loaded("ball", tc)) and np.all(ub[:, 4] > 0)
    assert np.all(x[a:b][nlp.ubx[a:b] == 0] == 0)
    # the base-row residual of every contact node is no worse than with the uniform guess
    d0, d1 = (np.abs(g[names == "dynamics"]).reshape(-1, 3) for g in (g0, g1))
    assert d0.shape[0] == len(nlp.meta["grid"]["stance"]) + 6 >= 5 + 6
    assert np.all(np.linalg.norm(d1, axis=1) <= np.linalg.norm(d0, axis=1) + 1e-9)
    assert np.linalg.norm(d1) < np.linalg.norm(d0)


def test_foot_pitch_fit_gives_a_consistent_takeoff_velocity(jump_setup):
    """The refitted phi_s gives the toe-pinned start the captured takeoff velocity (x, z, pitch)."""
    from latentoc.jump.transcription import anchored_function
    from latentoc.spline import BSpline

    js = jump_setup
    s = JumpSettings(base_model="pinned")
    ph = js.phases
    anch = anchored_function(js.sym, js.smap, js.gpdm, js.geom)
    tt = np.array([ph.takeoff])

    def takeoff_velocity(ig):
        X = [BSpline(s.n_control, ph.duration).evaluate(ig["P"], tt, k) for k in range(3)]
        f = [BSpline(s.n_phi_stance, ph.takeoff).evaluate(ig["phi_s"][:, None], tt, k)[:, 0][None] for k in range(3)]
        return np.array(anch(X[0].T, X[1].T, X[2].T, *f, 0.0)[1]).ravel()

    tr = js.training
    captured = np.gradient(tr.base, tr.t, axis=0)[int(np.argmin(np.abs(tr.t - ph.takeoff)))]
    raw, fitted = takeoff_velocity(initial_guess(js, s, fit_base=False)), takeoff_velocity(initial_guess(js, s))
    assert np.linalg.norm(raw - captured) > 1.0
    assert np.all(np.abs(fitted - captured) < [0.1, 0.15, 0.1])


@pytest.mark.parametrize("base_model", ["spline", "pinned"])
def test_lifted_jacobian_matches_finite_differences(base_model, jump_setup):
    """The NLP's jac_g (compiled node Jacobians chained through the affine node inputs) against
    central differences of its constraint rows along random directions, for both base models."""
    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, base_model=base_model)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    rng = np.random.default_rng(0)
    x = nlp.x0 + 1e-3 * rng.standard_normal(nlp.x0.size)
    J = np.array(nlp.meta["jac_fun"](x, 1.0)[1])
    g = nlp.meta["g_fun"]
    for _ in range(3):
        dv = rng.standard_normal(x.size)
        h = 1e-6
        fd = (np.array(g(x + h * dv)).ravel() - np.array(g(x - h * dv)).ravel()) / (2 * h)
        an = J @ dv
        assert np.max(np.abs(fd - an)) <= 1e-6 * np.max(np.abs(an))


@pytest.mark.parametrize("time_scale", [True, False])
def test_exact_hessian_matches_finite_differences(time_scale, jump_setup):
    """hessian="exact": the Hessian of the Lagrangian (compiled node Hessians chained through the
    node inputs, with the time scale's curvature and the pitch integral's product rule) against
    central differences of the Lagrangian's gradient, lam_f grad f + jac_g^T lam_g."""
    import casadi as ca

    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6, hessian="exact", wrench_spacing=0.02,
                     time_scale=time_scale)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    rng = np.random.default_rng(1)
    x = nlp.x0 + 1e-3 * rng.standard_normal(nlp.x0.size)
    lam_f, lam_g = 0.7, rng.standard_normal(len(nlp.names))
    Hu = np.array(ca.densify(nlp.meta["hess_fun"](x, 1.0, lam_f, lam_g)))
    assert np.allclose(np.tril(Hu, -1), 0)
    H = Hu + Hu.T - np.diag(np.diag(Hu))
    w = ca.MX.sym("w", x.size)
    grad_f = ca.Function("grad_f", [w], [ca.gradient(nlp.meta["f_fun"](w, 1.0), w)])

    def grad_lagrangian(v):
        return lam_f * np.array(grad_f(v)).ravel() + np.array(nlp.meta["jac_fun"](v, 1.0)[1]).T @ lam_g

    for _ in range(3):
        dv = rng.standard_normal(x.size)
        h = 1e-6
        fd = (grad_lagrangian(x + h * dv) - grad_lagrangian(x - h * dv)) / (2 * h)
        assert np.max(np.abs(fd - H @ dv)) <= 1e-6 * np.max(np.abs(fd))


def test_time_scaled_export_is_differentiable_in_real_time(jump_setup):
    """With time scale k the exported motion lasts k T, and its v and a are the real-time
    derivatives of q (central differences with pinocchio.difference on the 1 kHz grid)."""
    import pinocchio as pin

    from latentoc.jump.problem import trajectory

    js = jump_setup
    s = JumpSettings(tube=0.02, n_stance=5, n_flight=5, n_land=6)
    nlp = build_nlp(js.model, js.smap, js.gpdm, js.geom, js.phases, js.limits, s, initial_guess(js, s), js.sym)
    x = consistent_start(nlp, nlp.x0)
    x[slice(*nlp.meta["sizes"]["time_scale"])] = 1.1
    parts = {k: np.array(v) for k, v in zip(nlp.unpack.name_out(), nlp.unpack(x))}
    tr = trajectory(js, {"settings": s, "parts": parts, "nlp": nlp})
    t, Q, V, A = tr["t"], tr["q"], tr["v"], tr["a"]
    assert np.isclose(t[-1], 1.1 * js.phases.duration) and np.isclose(tr["takeoff"], 1.1 * js.phases.takeoff)
    h = t[1] - t[0]
    for i in (100, 500, 1000, 1300):  # stance, flight, landing
        vd = pin.difference(js.model, Q[i - 1], Q[i + 1]) / (2 * h)
        assert np.allclose(vd, V[i], atol=2e-3 * max(1.0, np.abs(V[i]).max()))
        assert np.allclose((V[i + 1] - V[i - 1]) / (2 * h), A[i], atol=2e-2 * max(1.0, np.abs(A[i]).max()))


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
