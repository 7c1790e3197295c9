"""The learned GPDM: Eq. 18/19 predictions, CasADi functions, dynamics,
variance tube (Eq. 30), save/load."""

import casadi as ca
import numpy as np
import pytest

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDM, GPDMSettings, learn_gpdm


@pytest.fixture(scope="module")
def model():
    Y = synthetic_motion(90, 12, seed=7, noise=0.03)
    return learn_gpdm(Y, GPDMSettings(latent_dim=3, max_iterations=50))


def _rand_points(model, n, seed=0, spread=1.5):
    rng = np.random.default_rng(seed)
    c, s = model.X.mean(axis=0), model.X.std(axis=0)
    return c + spread * s * rng.standard_normal((n, model.latent_dim))


def test_mean_reproduces_training_poses(model):
    """Per dimension RMS of mu_Q(x_i) - y_i within 3 noise std (sqrt(1/beta3)/w_d)."""
    err = model.mean(model.X) - model.Y
    rms = np.sqrt(np.mean(err ** 2, axis=0))
    assert np.all(rms <= 3 * np.sqrt(model.noise_variance) / model.W)
    assert model.reconstruction_rmse() == pytest.approx(np.sqrt(np.mean(err ** 2)))
    # single-point and batch forms agree
    np.testing.assert_allclose(model.mean(model.X[5]), model.mean(model.X)[5], rtol=0, atol=1e-12)


def test_mean_equals_direct_eq18(model):
    """Eq. 18 with a fresh dense solve (independent of the cached Cholesky inverse)."""
    b1, b2, b3 = model.beta
    X = model.X
    K = b1 * np.exp(-b2 / 2 * np.sum((X[:, None] - X[None]) ** 2, -1)) + np.eye(len(X)) / b3
    x = _rand_points(model, 4, seed=1)
    k = b1 * np.exp(-b2 / 2 * np.sum((x[:, None] - X[None]) ** 2, -1))
    Yw = (model.Y - model.Y_mean) * model.W
    q = model.Y_mean + (k @ np.linalg.solve(K, Yw)) / model.W
    np.testing.assert_allclose(model.mean(x), q, rtol=1e-7, atol=1e-8)
    s2 = b1 + 1 / b3 - np.sum(k * np.linalg.solve(K, k.T).T, axis=1)
    np.testing.assert_allclose(model.variance(x), s2, rtol=1e-7, atol=1e-10)


def test_variance_on_training_points_near_noise(model):
    """sigma^2(x_i) is in [1/beta3, 2/beta3]: the latent GP variance at a training
    point is >= 0 and <= the noise variance (one noisy observation at x_i alone
    already reduces it to b1 s/(b1 + s) < s)."""
    s2 = model.variance(model.X)
    nv = model.noise_variance
    assert np.all(s2 >= nv * (1 - 1e-8)) and np.all(s2 <= 2 * nv)


def test_variance_grows_away_from_data(model):
    c = model.X.mean(axis=0)
    far = model.X[np.argmax(np.linalg.norm(model.X - c, axis=1))]
    u = (far - c) / np.linalg.norm(far - c)
    R = np.linalg.norm(far - c)
    t = np.linspace(0.05, 20, 400) * R
    s2 = model.variance(far + t[:, None] * u)
    assert np.all(np.diff(s2) >= -1e-12)
    top = model.beta[0] + 1 / model.beta[2]
    assert s2[-1] == pytest.approx(top, rel=1e-6)
    assert s2[0] < top


def test_casadi_functions_equal_numpy(model):
    fm, fv = model.mean_function(), model.variance_function()
    assert fm.name_in() == ["x"] and fm.name_out() == ["q"]
    assert fv.name_in() == ["x"] and fv.name_out() == ["sigma2"]
    assert fm.size_out(0) == (model.output_dim, 1) and fv.size_out(0) == (1, 1)
    assert model.mean_function() is fm  # cached
    pts = np.vstack([_rand_points(model, 15, seed=2), model.X[:5]])
    for x in pts:
        np.testing.assert_allclose(np.array(fm(x)).ravel(), model.mean(x), rtol=0, atol=1e-10)
        assert abs(float(fv(x)) - model.variance(x)) < 1e-10


def test_casadi_usable_in_sx_and_mx_graphs(model):
    x0 = _rand_points(model, 1, seed=3)[0]
    for sym in (ca.SX, ca.MX):
        z = sym.sym("z", model.latent_dim)
        expr = ca.sumsqr(model.mean_function()(2 * z)) + model.variance_function()(z)
        f = ca.Function("f", [z], [expr])
        ref = np.sum(model.mean(2 * x0) ** 2) + model.variance(x0)
        assert float(f(x0)) == pytest.approx(ref, rel=1e-10)


def test_casadi_derivatives_match_finite_differences(model):
    d = model.latent_dim
    x = ca.SX.sym("x", d)
    Jm = ca.Function("Jm", [x], [ca.jacobian(model.mean_function()(x), x)])
    Jv = ca.Function("Jv", [x], [ca.jacobian(model.variance_function()(x), x)])
    Hv = ca.Function("Hv", [x], [ca.hessian(model.variance_function()(x), x)[0]])
    h = 1e-6
    for x0 in _rand_points(model, 4, seed=4, spread=0.8):
        E = np.eye(d) * h
        fd_m = np.stack([(model.mean(x0 + e) - model.mean(x0 - e)) / (2 * h) for e in E], axis=1)
        fd_v = np.array([(model.variance(x0 + e) - model.variance(x0 - e)) / (2 * h) for e in E])
        Jm0, Jv0 = np.array(Jm(x0)), np.array(Jv(x0)).ravel()
        assert np.max(np.abs(Jm0 - fd_m)) <= 1e-6 * max(1.0, np.max(np.abs(fd_m)))
        assert np.max(np.abs(Jv0 - fd_v)) <= 1e-6 * max(1e-3, np.max(np.abs(fd_v)))
        fd_H = np.stack([(np.array(Jv(x0 + e)).ravel() - np.array(Jv(x0 - e)).ravel()) / (2 * h)
                         for e in E], axis=1)
        H0 = np.array(Hv(x0))
        np.testing.assert_allclose(H0, H0.T, atol=1e-10)
        assert np.max(np.abs(H0 - fd_H)) <= 1e-5 * max(1e-2, np.max(np.abs(fd_H)))


def test_predict_next_follows_training_trajectory(model):
    X = model.X
    pred = model.predict_next(X[:-1])
    step = np.linalg.norm(np.diff(X, axis=0), axis=1).mean()
    err = np.linalg.norm(pred - X[1:], axis=1)
    assert err.max() < 0.2 * step
    assert err.mean() < 0.05 * step
    sim = model.simulate(X[0], 10)
    assert sim.shape == (11, 3)
    np.testing.assert_array_equal(sim[0], X[0])
    np.testing.assert_allclose(sim[1], model.predict_next(X[0]), rtol=1e-13)
    # the mean dynamics rolled out from x_1 stays on the training path
    assert np.max(np.linalg.norm(sim - X[:11], axis=1)) < step


def test_tube_size_eq30(model):
    delta = model.tube_size()
    # independent dense check on the same grid: loop over segments and samples
    vals = []
    for T in model.latent_trajectories():
        for a, b in zip(T[:-1], T[1:]):
            for k in range(11):
                s = k / 10
                vals.append(model.variance((1 - s) * a + s * b))
    assert delta == pytest.approx(max(vals), rel=1e-12)
    assert np.all(model.variance(model.X) <= delta)
    # refining the path can only find larger (or equal) maxima, and not much larger
    fine = model.tube_size(samples_per_segment=50)
    assert delta <= fine + 1e-15 and fine < 1.5 * delta
    # explicit trajectories: a shifted path needs a bigger tube
    shifted = [model.X + 0.5 * model.X.std(axis=0)]
    assert model.tube_size(shifted) > delta


def test_noise_variance_and_trajectories(model):
    assert model.noise_variance == 1 / model.beta[2]
    (T,) = model.latent_trajectories()
    np.testing.assert_array_equal(T, model.X)


def test_save_load_round_trip(model, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    m2 = GPDM.load(path)
    for name in ("X", "alpha", "beta", "W", "Y_mean", "Y"):
        a, b = getattr(model, name), getattr(m2, name)
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes()
    assert m2.sequence_lengths == model.sequence_lengths
    assert m2.settings == model.settings
    assert m2.objective_value == model.objective_value
    assert m2.learning == model.learning and m2.learning_summary() == model.learning_summary()
    x = _rand_points(model, 6, seed=5)
    assert model.mean(x).tobytes() == m2.mean(x).tobytes()
    assert model.variance(x).tobytes() == m2.variance(x).tobytes()
