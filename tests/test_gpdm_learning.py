"""GPDM learning (Eq. 16): objective decrease, smooth latent trajectories,
a known latent circle, several sequences, input validation."""

import numpy as np
import pytest

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDM, GPDMInputError, GPDMSettings, learn_gpdm
from latentoc.gpdm.learning import pca_initialization, roughness
from latentoc.gpdm.objective import GPDMProblem, neg_log_posterior, optimal_w, pack


def circle_data(N=80, turns=2.0, D=20, seed=1, noise=0.01):
    """D-dim observations of a 2-D latent circle through tanh(A z + b) + noise."""
    rng = np.random.default_rng(seed)
    th = np.linspace(0, 2 * np.pi * turns, N, endpoint=False)
    Z = np.stack([np.cos(th), np.sin(th)], axis=1)
    A = rng.standard_normal((2, D))
    b = 0.3 * rng.standard_normal(D)
    return np.tanh(Z @ A + b) + noise * rng.standard_normal((N, D))


@pytest.fixture(scope="module")
def motion():
    # 2 cycles of a smooth periodic motion, 60 frames per cycle, noise 0.05
    Y = synthetic_motion(120, 20, seed=0, noise=0.05)
    settings = GPDMSettings(latent_dim=3)
    return Y, settings, learn_gpdm(Y, settings)


def _objective_at_pca_start(Y, settings):
    Yc = Y - Y.mean(axis=0)
    X0 = pca_initialization(Yc, settings.latent_dim)
    lam = Y.shape[1] / settings.latent_dim if settings.balanced else 1.0
    p = GPDMProblem(Yc, [len(Y)], settings.latent_dim, dynamics_weight=lam)
    b0 = np.array(settings.beta0)
    w0 = optimal_w(Yc, X0, b0, settings.kappa_sq)
    return neg_log_posterior(pack(X0, np.array(settings.alpha0), b0), p, w0, with_grad=False)


def test_objective_decreases_from_pca_start(motion):
    Y, settings, model = motion
    f0 = _objective_at_pca_start(Y, settings)
    assert model.objective_value < f0 - 0.1 * abs(f0)
    # the recorded value is the objective of the returned variables
    lam = Y.shape[1] / 3 if settings.balanced else 1.0
    p = GPDMProblem(Y - model.Y_mean, model.sequence_lengths, 3, dynamics_weight=lam)
    f = neg_log_posterior(pack(model.X, model.alpha, model.beta), p, model.W, with_grad=False)
    assert f == pytest.approx(model.objective_value, rel=1e-12)


def test_latent_trajectory_is_smooth(motion):
    """Roughness r = mean|second difference| / mean|first difference|.

    A smooth closed curve with 60 samples per cycle has r ~ 2 sin(pi/60) ~ 0.1
    (more with higher harmonics); white noise gives r ~ sqrt(3) ~ 1.7.  PCA of
    the noisy data gives r ~ 0.4 here; the learned trajectory must be clearly
    smoother than PCA (<= 0.6 x) and below 0.25.
    """
    Y, settings, model = motion
    r_pca = roughness(pca_initialization(Y - Y.mean(axis=0), 3))
    r = roughness(model.X)
    assert r < 0.6 * r_pca
    assert r < 0.25


def test_settings_and_shapes_recorded(motion):
    Y, settings, model = motion
    assert isinstance(model, GPDM)
    assert model.settings == settings
    assert model.X.shape == (120, 3) and model.W.shape == (20,)
    assert model.alpha.shape == (4,) and model.beta.shape == (3,)
    np.testing.assert_array_equal(model.Y, Y)
    np.testing.assert_allclose(model.Y_mean, Y.mean(axis=0))
    assert model.latent_dim == 3 and model.output_dim == 20
    assert model.sequence_lengths == [120]


def test_latent_circle_closes_into_loop():
    """80 frames over two turns of a latent circle (period 40 frames).

    After one period the latent point must return to its start: the gap
    |x_0 - x_40| is < 5% of the loop's diameter (the step between frames is
    ~ pi/40 ~ 8% of the diameter).  Reconstruction RMS must be at the noise
    level (0.01) -- below 3x noise, i.e. < 2% of the data's std.
    """
    Y = circle_data()
    model = learn_gpdm(Y, GPDMSettings(latent_dim=2))
    X = model.X
    diam = np.max(np.linalg.norm(X[:, None] - X[None], axis=-1))
    for t in range(0, 40, 7):
        assert np.linalg.norm(X[t] - X[t + 40]) < 0.05 * diam
    step = np.linalg.norm(np.diff(X, axis=0), axis=1).mean()
    assert step > 0.04 * diam  # not collapsed: it really goes around
    # the loop encloses area (not a back-and-forth curve): winding angle ~ 2 turns
    c = X.mean(axis=0)
    ang = np.unwrap(np.arctan2(X[:, 1] - c[1], X[:, 0] - c[0]))
    assert abs(ang[-1] - ang[0]) > 2 * np.pi * 1.8
    rms = model.reconstruction_rmse()
    assert rms < 3 * 0.01 and rms < 0.02 * Y.std()


def test_two_sequences():
    Y = circle_data(N=100, turns=2.5, seed=2)
    seqs = [Y[:55], Y[55:]]
    model = learn_gpdm(seqs, GPDMSettings(latent_dim=2, outer_iterations=3))
    assert model.sequence_lengths == [55, 45]
    trajs = model.latent_trajectories()
    assert [t.shape for t in trajs] == [(55, 2), (45, 2)]
    np.testing.assert_array_equal(np.vstack(trajs), model.X)
    # objective uses per-sequence X_in/X_out: compare against the problem built from lengths
    p = GPDMProblem(np.vstack(seqs) - model.Y_mean, [55, 45], 2,
                    dynamics_weight=20 / 2 if model.settings.balanced else 1.0)
    f = neg_log_posterior(pack(model.X, model.alpha, model.beta), p, model.W, with_grad=False)
    assert f == pytest.approx(model.objective_value, rel=1e-12)
    # both sequences trace the same circle: the second sequence's start lies
    # near the first sequence's latent points of the same phase (frame 55 - 40 = 15)
    diam = np.max(np.linalg.norm(model.X[:, None] - model.X[None], axis=-1))
    assert np.linalg.norm(trajs[1][0] - trajs[0][15]) < 0.1 * diam
    assert model.reconstruction_rmse() < 0.03


def test_constant_column_does_not_break_learning():
    Y = synthetic_motion(60, 8, seed=4, noise=0.02)
    Y[:, 3] = 1.25
    model = learn_gpdm(Y, GPDMSettings(latent_dim=2, outer_iterations=2, max_iterations=30))
    assert np.all(np.isfinite(model.X)) and np.isfinite(model.objective_value)
    assert model.W[3] > 100 * np.max(np.delete(model.W, 3))
    np.testing.assert_allclose(model.mean(model.X)[:, 3], 1.25, atol=1e-9)


@pytest.mark.parametrize("make,words", [
    (lambda Y: np.where(np.arange(Y.size).reshape(Y.shape) == 3 * 6 + 2, np.nan, Y), ["NaN", "row 3", "column 2"]),
    (lambda Y: np.where(np.arange(Y.size).reshape(Y.shape) == 5 * 6 + 1, np.inf, Y), ["inf", "row 5", "column 1"]),
    (lambda Y: Y[:2], ["too few frames"]),
    (lambda Y: Y[:, 0], ["2-D"]),
    (lambda Y: [Y[:10], Y[10:, :4]], ["Y[1]", "columns"]),
])
def test_bad_input_raises(make, words):
    Y = synthetic_motion(20, 6, seed=5)
    with pytest.raises(GPDMInputError) as exc:
        learn_gpdm(make(Y), GPDMSettings(latent_dim=2))
    for w in words:
        assert w in str(exc.value)
    assert isinstance(exc.value, ValueError)


def test_latent_dim_not_smaller_than_D_raises():
    Y = synthetic_motion(20, 3, seed=5)
    with pytest.raises(GPDMInputError, match="d >= D"):
        learn_gpdm(Y, GPDMSettings(latent_dim=3))


def test_too_few_frames_for_latent_dim_raises():
    Y = synthetic_motion(4, 10, seed=5)
    with pytest.raises(GPDMInputError, match="too few frames"):
        learn_gpdm(Y, GPDMSettings(latent_dim=3))


def test_random_init_uses_seed_and_learns():
    Y = synthetic_motion(40, 6, seed=6, noise=0.02)
    s1 = GPDMSettings(latent_dim=2, init="random", seed=1, outer_iterations=2, max_iterations=40)
    m1 = learn_gpdm(Y, s1)
    m1b = learn_gpdm(Y, s1)
    m2 = learn_gpdm(Y, GPDMSettings(latent_dim=2, init="random", seed=2, outer_iterations=1,
                                    max_iterations=1))
    np.testing.assert_array_equal(m1.X, m1b.X)  # deterministic for a fixed seed
    assert not np.allclose(m1.X, m2.X)
    assert m1.reconstruction_rmse() < 0.2 * Y.std()


def test_roughness_reference_values():
    th = np.linspace(0, 2 * np.pi, 61)
    circ = np.stack([np.cos(th), np.sin(th)], axis=1)
    assert roughness(circ) == pytest.approx(2 * np.sin(np.pi / 60), rel=1e-9)
    noise = np.random.default_rng(0).standard_normal((20000, 3))
    assert 1.5 < roughness(noise) < 1.9


def test_beta3_max_bounds_the_noise_and_defaults_off(motion):
    """beta3_max (default None) caps beta_3, i.e. floors the noise variance at 1/beta3_max."""
    Y, settings, model = motion
    assert GPDMSettings().beta3_max is None
    assert model.beta[2] > 20.0  # unbounded: beta_3 ~ 41 on this motion
    bounded = learn_gpdm(Y, GPDMSettings(latent_dim=3, beta3_max=10.0))
    assert bounded.beta[2] <= 10.0 * (1 + 1e-9)
    assert bounded.noise_variance >= 0.1 * (1 - 1e-9)
    assert GPDMSettings.from_json(bounded.settings.to_json()) == bounded.settings
    with pytest.raises(GPDMInputError, match="beta3_max"):
        learn_gpdm(Y, GPDMSettings(latent_dim=3, beta3_max=-1.0))
