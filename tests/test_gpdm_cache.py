"""Learned GPDMs on disk: the second call reads the model the first one learned, other data or
settings learn their own, and a damaged file is learned again."""
import numpy as np
import pytest

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


def test_shipped_models_are_converged_minima_of_their_data():
    """Each model in latentoc/models/ is named by its data and settings, and is a converged minimum
    of Eq. 16 for them: the Newton decrement, from a fresh Hessian of the exact gradient, is within
    the settings' ftol |L| (what learning it again would stop at)."""
    from latentoc.gpdm import GPDM
    from latentoc.gpdm.cache import SHIPPED
    from latentoc.gpdm.learning import learning_problem
    from latentoc.gpdm.newton import fd_hessian
    from latentoc.gpdm.objective import HYPER_NAMES, neg_log_posterior, pack

    files = sorted(SHIPPED.glob("gpdm_*.npz"))
    assert files, "the broad jump's model ships with the package"
    for path in files:
        m = GPDM.load(path)
        starts = np.cumsum([0] + m.sequence_lengths)
        seqs = [m.Y[a:b] for a, b in zip(starts[:-1], starts[1:])]
        assert model_path(seqs[0] if len(seqs) == 1 else seqs, m.settings).name == path.name
        p = learning_problem(m.Y - m.Y_mean, m.sequence_lengths, m.settings)
        v = pack(m.X, m.alpha, m.beta)
        free = np.ones(v.size, dtype=bool)
        for name in m.settings.fixed:
            free[v.size - 7 + HYPER_NAMES.index(name)] = False

        def grad(z, v=v, free=free, p=p):
            w = v.copy()
            w[free] = z
            return neg_log_posterior(w, p)[1][free]

        f, g = neg_log_posterior(v, p)[0], grad(v[free])
        assert f == pytest.approx(m.objective_value, rel=1e-12) and m.learning.converged
        lam, V = np.linalg.eigh(fd_hessian(grad, v[free], g))
        a = np.maximum(np.abs(lam), 1e-8 * np.abs(lam).max())
        assert 0.5 * np.sum((V.T @ g) ** 2 / a) <= 10 * m.settings.ftol * abs(f)


@pytest.fixture
def cached(tmp_path, monkeypatch):
    """A model learned into an empty cache: (data, settings, its path, the model)."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    Y, settings = synthetic_motion(20, 4, seed=5, noise=0.05), GPDMSettings(latent_dim=2)
    return Y, settings, model_path(Y, settings), learned_gpdm(Y, settings)


def _truncate(p):
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _flip_a_byte(p):
    data = bytearray(p.read_bytes())
    data[len(data) // 3] ^= 0xFF
    p.write_bytes(bytes(data))


@pytest.mark.parametrize("damage, why", [
    (_truncate, "checksum differs"),
    (lambda p: p.write_bytes(b""), "checksum differs"),
    (_flip_a_byte, "checksum differs"),
    (lambda p: (p.with_name(p.name + ".sha256").unlink(), _truncate(p)), "not a readable model"),
    (lambda p: (p.with_name(p.name + ".sha256").unlink(), p.write_bytes(b"")), "not a readable model"),
])
def test_a_damaged_cached_model_is_learned_again_with_a_warning(cached, capsys, damage, why):
    """A truncated, empty or bit-flipped gpdm_*.npz (with or without its checksum file) is learned
    again with one warning line naming it, not a BadZipFile/EOFError traceback, and replaced."""
    Y, settings, path, first = cached
    capsys.readouterr()
    damage(path)
    model = learned_gpdm(Y, settings)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("latentoc: warning: the cached GPDM") and why in err
    assert str(path) in err
    np.testing.assert_array_equal(model.X, first.X)
    assert learned_gpdm(Y, settings).objective_value == first.objective_value and capsys.readouterr().err == ""


def test_a_foreign_model_under_the_name_is_learned_again(cached, capsys):
    """Another model's file (valid, checksummed) under this data's name is not read as its model."""
    Y, settings, path, first = cached
    other = learned_gpdm(Y[:-2], settings)
    other_path = model_path(Y[:-2], settings)
    for suffix in ("", ".sha256"):
        path.with_name(path.name + suffix).write_bytes(other_path.with_name(other_path.name + suffix).read_bytes())
    capsys.readouterr()
    model = learned_gpdm(Y, settings)
    assert "model of other data or settings" in capsys.readouterr().err
    assert model.X.shape == first.X.shape != other.X.shape


def test_cache_files_are_written_under_a_temporary_name_with_a_checksum(cached):
    """The cache folder holds the model and its SHA-256 only (no temporary file left), and a model
    cached before checksums existed is verified, read and given its checksum."""
    import hashlib

    Y, settings, path, _ = cached
    side = path.with_name(path.name + ".sha256")
    assert sorted(p.name for p in path.parent.iterdir()) == [path.name, side.name]
    assert side.read_text().strip() == hashlib.sha256(path.read_bytes()).hexdigest()
    side.unlink()
    learned_gpdm(Y, settings)
    assert side.read_text().strip() == hashlib.sha256(path.read_bytes()).hexdigest()
