"""GPDM learning (Eq. 16 with the model's priors): convergence and its report, the stationarity
the priors imply along the latent rescaling (known analytically), smooth latent trajectories, a
known latent circle, several sequences, input validation."""

import re
from pathlib import Path

import numpy as np
import pytest
from gpdm_reference import aligned_difference, central_hessian, decrement, model_objective, polish

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDM, GPDMInputError, GPDMSettings, learn_gpdm
from latentoc.gpdm.learning import learning_problem, roughness
from latentoc.gpdm.start import pca_initialization
from latentoc.gpdm.objective import HYPER_NAMES, neg_log_posterior, pack


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


def _objective(model, X=None):
    """The objective learning minimised, recomputed from the model (W profiled)."""
    p = learning_problem(model.Y - model.Y_mean, model.sequence_lengths, model.settings)
    v = pack(model.X if X is None else X, model.alpha, model.beta)
    return neg_log_posterior(v, p, with_grad=False), p, v


def test_objective_decreases_from_pca_start(motion):
    Y, settings, model = motion
    X0 = pca_initialization(Y - Y.mean(axis=0), settings.latent_dim)
    p = learning_problem(Y - Y.mean(axis=0), [len(Y)], settings)
    theta0 = np.array(settings.alpha0 + settings.beta0)
    theta0[HYPER_NAMES.index("beta1")] = settings.fixed["beta1"]
    f0 = neg_log_posterior(pack(X0, theta0[:4], theta0[4:]), p, with_grad=False)
    assert model.objective_value < f0 - 0.1 * abs(f0)
    # the recorded value is the objective of the returned variables
    assert _objective(model)[0] == pytest.approx(model.objective_value, rel=1e-12)


def test_converges_and_reports_it():
    """The convergence test held: the Newton decrement (recomputed here from a central-difference
    Hessian) is below ftol |L|, so no Newton step can lower L by more than that."""
    settings = GPDMSettings(latent_dim=3)
    model = learn_gpdm(synthetic_motion(50, 8, seed=2, noise=0.05), settings)
    r = model.learning
    assert r.converged and r.iterations > 0 and r.evaluations > r.iterations and "Newton decrement" in r.message
    f, g, grad, z = model_objective(model)
    # both are roundoff of L at the minimum (~1e-10 here), so they agree to roundoff, not to digits
    assert np.max(np.abs(g)) == pytest.approx(r.gradient_norm, abs=1e-12 * abs(f))
    assert decrement(central_hessian(grad, z), g) <= 10 * settings.ftol * abs(f)
    assert model.learning_summary() == {
        "gpdm_objective": model.objective_value, "gpdm_iterations": r.iterations, "gpdm_evaluations": r.evaluations,
        "gpdm_gradient_norm": r.gradient_norm, "gpdm_newton_decrement": r.newton_decrement, "gpdm_converged": True}


def test_the_arms_minimum_is_the_previous_learners():
    """The arm-raise problem's training data (59 x 7) land in the minimum the previous learner (damped
    Newton on a forward-difference Hessian, commit 8f78e4c) recorded: Eq. 16 within 1e-8 relative, and
    both points, polished by Newton steps on a central-difference Hessian, the same latent points to
    1e-6 after the best rotation (the previous learner stopped 2e-4 from it)."""
    from latentoc.min_torque.training import gpdm_settings, training_frames
    from latentoc.problem.toml_files import load_problem

    problem = load_problem("arm-raise")
    ref = np.load(Path(__file__).with_name("gpdm_previous_minimum_arm.npz"))
    Q = training_frames(problem)[1]
    np.testing.assert_allclose(Q, ref["Y"], rtol=0, atol=1e-12)  # to roundoff across library versions
    model = learn_gpdm(Q, gpdm_settings(problem))
    assert model.learning.converged
    assert abs(model.objective_value - ref["f"]) <= 1e-8 * abs(ref["f"])
    f, g, grad, z = model_objective(model)
    free = np.ones(ref["v"].size, dtype=bool)
    free[-3] = False  # beta_1 = 1
    N, d = Q.shape[0], 3
    new, old = polish(grad, z, N, d), polish(grad, ref["v"][free], N, d)
    assert aligned_difference(new[:N * d].reshape(N, d), old[:N * d].reshape(N, d)) <= 1e-6
    np.testing.assert_allclose(new[N * d:], old[N * d:], atol=1e-6)


@pytest.mark.parametrize("mode", ["bars", "lines"])
def test_learning_shows_its_progress(capsys, monkeypatch, mode):
    """Iteration, L and the Newton decrement on stderr while learning (tqdm, latentoc.runtime.progress): a bar
    redrawn in place on a terminal, in a log one line when it starts and one when it ends."""
    from latentoc.runtime.progress import quiet, set_quiet

    monkeypatch.setenv("LATENTOC_PROGRESS", mode)
    was = quiet()
    set_quiet(False)
    try:
        model = learn_gpdm(synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2))
    finally:
        set_quiet(was)
    err = capsys.readouterr().err
    assert "GPDM on 30 frames" in err and "L = " in err and "decrement" in err
    if mode == "lines":
        start, end = err.splitlines()
        assert "\r" not in err and start == "GPDM on 30 frames: ..." and model.learning.converged
        assert re.fullmatch(r"GPDM on 30 frames: done, [0-9]+ it in [0-9.]+ s, L = \S+, decrement \S+", end)


def test_prior_fixes_the_latent_scale_as_predicted(motion):
    """X -> sX with alpha_1 -> s^2 alpha_1, alpha_2, alpha_4, beta_2 -> theta / s^2 changes Eq. 16
    only by lambda d n ln s (ln|K_X|), the first point's prior and the hyperparameter priors
    (test_gpdm_objective). At a minimum the derivative in ln s vanishes, which with Gamma(a, b)
    priors P = -(a - 1) ln theta + b theta reads
    lambda d n + |x_1|^2 + 2 P'(alpha_1) - 2 P'(alpha_2) - 2 P'(alpha_4) - 2 P'(beta_2) = 0,
    P'(theta) = -(a - 1) + b theta: the priors set alpha_4."""
    Y, settings, model = motion
    lam = Y.shape[1] / settings.latent_dim if settings.balanced else 1.0
    n = len(Y) - 1
    theta = dict(zip(HYPER_NAMES, np.concatenate([model.alpha, model.beta])))

    def dP(name):
        a, b = settings.gamma[name]
        return -(a - 1.0) + b * theta[name]

    terms = [lam * settings.latent_dim * n, float(np.sum(model.X[0] ** 2)), 2 * dP("alpha1"), -2 * dP("alpha2"),
             -2 * dP("alpha4"), -2 * dP("beta2")]
    assert abs(sum(terms)) < 1e-5 * max(abs(t) for t in terms)


def test_fixed_hyperparameters_and_priors_are_the_models(motion):
    Y, settings, model = motion
    assert model.beta[0] == settings.fixed["beta1"] == 1.0
    assert set(settings.gamma) == set(HYPER_NAMES) - {"beta1"}
    assert settings.balanced


def test_safety_cap_is_reported_as_not_converged():
    Y = synthetic_motion(40, 6, seed=3, noise=0.02)
    model = learn_gpdm(Y, GPDMSettings(latent_dim=2, max_iterations=5))
    assert not model.learning.converged and model.learning.iterations <= 5
    assert model.learning_summary()["gpdm_converged"] is False


def test_plain_eq16_has_no_minimum_and_is_not_reported_converged():
    """Eq. 16 with its 1/theta priors: the hyperparameters run away until the cap."""
    Y = synthetic_motion(40, 6, seed=3, noise=0.0)
    model = learn_gpdm(Y, GPDMSettings(latent_dim=2, fixed={}, gamma={}, balanced=False, max_iterations=60))
    assert not model.learning.converged
    assert max(np.abs(np.log(np.concatenate([model.alpha, model.beta])))) > 8


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
    model = learn_gpdm(seqs, GPDMSettings(latent_dim=2))
    assert model.learning.converged
    assert model.sequence_lengths == [55, 45]
    trajs = model.latent_trajectories()
    assert [t.shape for t in trajs] == [(55, 2), (45, 2)]
    np.testing.assert_array_equal(np.vstack(trajs), model.X)
    # objective uses per-sequence X_in/X_out: compare against the problem built from lengths
    assert _objective(model)[0] == pytest.approx(model.objective_value, rel=1e-12)
    # both sequences trace the same circle: the second sequence's start lies
    # near the first sequence's latent points of the same phase (frame 55 - 40 = 15)
    diam = np.max(np.linalg.norm(model.X[:, None] - model.X[None], axis=-1))
    assert np.linalg.norm(trajs[1][0] - trajs[0][15]) < 0.1 * diam
    assert model.reconstruction_rmse() < 0.03


def test_constant_column_does_not_break_learning():
    Y = synthetic_motion(60, 8, seed=4, noise=0.02)
    Y[:, 3] = 1.25
    model = learn_gpdm(Y, GPDMSettings(latent_dim=2, max_iterations=30))
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
    s1 = GPDMSettings(latent_dim=2, init="random", seed=1)
    m1 = learn_gpdm(Y, s1)
    m1b = learn_gpdm(Y, s1)
    m2 = learn_gpdm(Y, GPDMSettings(latent_dim=2, init="random", seed=2, max_iterations=1))
    np.testing.assert_array_equal(m1.X, m1b.X)  # deterministic for a fixed seed
    assert not np.allclose(m1.X, m2.X)
    assert m1.reconstruction_rmse() < 0.2 * Y.std()


def test_roughness_reference_values():
    th = np.linspace(0, 2 * np.pi, 61)
    circ = np.stack([np.cos(th), np.sin(th)], axis=1)
    assert roughness(circ) == pytest.approx(2 * np.sin(np.pi / 60), rel=1e-9)
    noise = np.random.default_rng(0).standard_normal((20000, 3))
    assert 1.5 < roughness(noise) < 1.9


@pytest.mark.parametrize("kw,words", [
    (dict(fixed={"beta4": 1.0}), ["settings.fixed", "beta4"]),
    (dict(fixed={"beta1": 0.0}), ["settings.fixed", "beta1"]),
    (dict(gamma={"alpha2": (2.0, -1.0)}), ["settings.gamma", "alpha2"]),
    (dict(ftol=0.0), ["ftol"]),
])
def test_bad_settings_raise(kw, words):
    Y = synthetic_motion(20, 6, seed=5)
    with pytest.raises(GPDMInputError) as exc:
        learn_gpdm(Y, GPDMSettings(latent_dim=2, **kw))
    for w in words:
        assert w in str(exc.value)


def test_settings_json_round_trip():
    s = GPDMSettings(latent_dim=2, fixed={"beta1": 1.0, "alpha3": 0.5}, gamma={"beta3": (3.0, 0.5)})
    assert GPDMSettings.from_json(s.to_json()) == s
    old = s.to_json().replace('"ftol"', '"beta3_max": 3000.0, "ftol"')  # a model saved before: key dropped
    assert GPDMSettings.from_json(old) == s


def test_same_model_with_one_or_two_blas_threads_and_permuted_joints():
    """Converged, the model does not depend on the BLAS's thread count or on the order of the
    joint columns (Eq. 16 is invariant under permuting them): the same objective to 1e-6."""
    Y = synthetic_motion(40, 6, seed=4, noise=0.05)
    one = learn_gpdm(Y, GPDMSettings(latent_dim=3, blas_threads=1))
    two = learn_gpdm(Y, GPDMSettings(latent_dim=3, blas_threads=2))
    perm = np.random.default_rng(0).permutation(Y.shape[1])
    swapped = learn_gpdm(Y[:, perm], GPDMSettings(latent_dim=3))
    assert one.learning.converged and two.learning.converged and swapped.learning.converged
    assert two.objective_value == pytest.approx(one.objective_value, rel=1e-6)
    assert swapped.objective_value == pytest.approx(one.objective_value, rel=1e-6)
    # the same mean and variance at the training points, in the permuted joints' order
    mu = np.array([one.mean(x) for x in one.X])
    np.testing.assert_allclose(np.array([swapped.mean(x) for x in swapped.X]), mu[:, perm], atol=1e-4)


def test_same_model_with_the_sequences_in_either_order():
    """Two sequences given in the other order are the same data: the same objective to 1e-6."""
    Y = synthetic_motion(60, 6, seed=6, noise=0.05)
    a, b = Y[:33], Y[33:]
    ab = learn_gpdm([a, b], GPDMSettings(latent_dim=2))
    ba = learn_gpdm([b, a], GPDMSettings(latent_dim=2))
    assert ab.learning.converged and ba.learning.converged
    assert ba.objective_value == pytest.approx(ab.objective_value, rel=1e-6)


def test_a_long_recording_starts_from_its_coarse_model():
    """Above 200 frames learning starts from the model of every second frame, interpolated: it
    converges, with a 3-frame sequence beside a long one (kept whole in the coarse model)."""
    from latentoc.gpdm.start import coarse_frames, interpolated_start

    frames = coarse_frames([3, 4, 9])
    assert [f.tolist() for f in frames] == [[0, 1, 2], [0, 1, 2, 3], [0, 2, 4, 6, 8]]
    Xc = np.arange(12.0)[:, None] * np.ones((1, 2))
    X = interpolated_start(Xc, np.ones(7), [3, 4, 9], frames)[:32].reshape(16, 2)
    np.testing.assert_allclose(X[7:, 0], np.linspace(7.0, 11.0, 9))  # linear between the kept frames
    Y = synthetic_motion(230, 5, seed=7, noise=0.02)
    model = learn_gpdm([Y[:3], Y[3:]], GPDMSettings(latent_dim=2))
    assert model.learning.converged and model.sequence_lengths == [3, 227]
