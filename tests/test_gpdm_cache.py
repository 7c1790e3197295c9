"""Learned GPDMs on disk: the second call reads the model the first one learned, other data or
settings learn their own, and a damaged file is learned again."""
import numpy as np

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm, learned_gpdm
from latentoc.gpdm.cache import model_path


def test_learned_once_then_read(tmp_path, monkeypatch):
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    first = learned_gpdm(Y, settings)
    path = model_path(Y, settings)
    assert path.exists() and path.parent.parent == tmp_path
    again = learned_gpdm(Y, settings)
    for name in ("X", "alpha", "beta", "W"):
        np.testing.assert_array_equal(getattr(again, name), getattr(first, name))
    assert again.learning == first.learning and again.objective_value == first.objective_value
    # the cached model is the one learn_gpdm returns
    assert learn_gpdm(Y, settings).objective_value == first.objective_value
    assert model_path(Y[:-1], settings) != path
    assert model_path(Y, GPDMSettings(latent_dim=3)) != path
    assert model_path([Y[:15], Y[15:]], settings) != path


def test_a_damaged_file_is_learned_again(tmp_path, monkeypatch):
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(30, 5, seed=3, noise=0.05), GPDMSettings(latent_dim=2)
    path = model_path(Y, settings)
    path.parent.mkdir(parents=True)
    path.write_bytes(b"not a model")
    model = learned_gpdm(Y, settings)
    assert model.learning.converged and learned_gpdm(Y, settings).objective_value == model.objective_value
