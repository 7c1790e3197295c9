"""Learned GPDMs on disk: the second call reads the model the first one learned, other data or
settings learn their own, and a damaged file is learned again."""
import numpy as np
import pytest

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm, cached_gpdm
from latentoc.gpdm.cache import model_path


def test_learned_once_then_read(tmp_path, monkeypatch):
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    first = cached_gpdm(Y, settings)
    path = model_path(Y, settings)
    assert path.exists() and path.parent.parent == tmp_path
    again = cached_gpdm(Y, settings)
    for name in ("X", "alpha", "beta", "W"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    assert again.learning == first.learning and again.objective_value == first.objective_value
    # the cached model is the one learn_gpdm returns
    assert learn_gpdm(Y, settings).objective_value == first.objective_value
    assert model_path(Y[:-1], settings) != path
    assert model_path(Y, GPDMSettings(latent_dim=3)) != path
    assert model_path([Y[:15], Y[15:]], settings) != path


def test_a_model_of_another_learner_version_is_not_read(tmp_path, monkeypatch):
    """A model cached by an earlier learner (stopped elsewhere near the minimum) is never read back
    for the current one: a changed LEARNER_VERSION names the model anew, so it is learned again."""
    import latentoc.gpdm.cache as cache

    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    current = cache.model_path(Y, settings)
    monkeypatch.setattr(cache, "LEARNER_VERSION", cache.LEARNER_VERSION - 1)
    old = cache.model_path(Y, settings)
    stale = learn_gpdm(Y, settings)
    stale.X = stale.X + 1e-3  # what another learner might have returned: not this learner's minimum
    old.parent.mkdir(parents=True)
    stale.save(old)
    monkeypatch.setattr(cache, "LEARNER_VERSION", cache.LEARNER_VERSION + 1)
    assert old != current and cache.model_path(Y, settings) == current
    model = cached_gpdm(Y, settings)
    assert current.exists() and not np.allclose(model.X, stale.X)
    np.testing.assert_array_equal(model.X, learn_gpdm(Y, settings).X)


def test_a_damaged_file_is_learned_again(tmp_path, monkeypatch):
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    path = model_path(Y, settings)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a model")
    model = cached_gpdm(Y, settings)
    assert model.learning.converged and cached_gpdm(Y, settings).objective_value == model.objective_value


def test_an_entry_without_its_checksum_is_learned_again(tmp_path, monkeypatch, capsys):
    """A cached model whose checksum file is gone is never adopted, even when its data and settings
    match its name (its learned variables can be anything): it is learned again, with a warning."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    good = cached_gpdm(Y, settings)
    path = model_path(Y, settings)
    tampered = learn_gpdm(Y, settings)
    tampered.X, tampered.alpha = 1.5 * tampered.X, 50 * tampered.alpha
    tampered.save(path)
    path.with_name(path.name + ".sha256").unlink()
    capsys.readouterr()
    model = cached_gpdm(Y, settings)
    assert "no checksum" in capsys.readouterr().err
    np.testing.assert_array_equal(model.X, good.X)
    np.testing.assert_array_equal(model.alpha, good.alpha)
    # the entry is replaced with the learned model and its checksum: read back without a warning
    np.testing.assert_array_equal(cached_gpdm(Y, settings).X, good.X)
    assert capsys.readouterr().err == ""


def test_shipped_models_are_converged_minima_of_their_data():
    """Each model in latentoc/models/ is named by its data and settings, and is a converged minimum
    of Eq. 16 for them: the Newton decrement, from a central-difference Hessian of the exact gradient,
    is within the settings' ftol |L| (what learning it again would stop at)."""
    from gpdm_reference import central_hessian, decrement, model_objective

    from latentoc.gpdm import GPDM
    from latentoc.gpdm.cache import SHIPPED

    files = sorted(SHIPPED.glob("gpdm_*.npz"))
    assert files, "the broad jump's model ships with the package"
    for path in files:
        m = GPDM.load(path)
        starts = np.cumsum([0] + m.sequence_lengths)
        seqs = [m.Y[a:b] for a, b in zip(starts[:-1], starts[1:])]
        assert model_path(seqs[0] if len(seqs) == 1 else seqs, m.settings).name == path.name
        f, g, grad, z = model_objective(m)
        assert f == pytest.approx(m.objective_value, rel=1e-12) and m.learning.converged
        assert decrement(central_hessian(grad, z), g) <= 10 * m.settings.ftol * abs(f)
