"""The closed-form GP layer (Eq. 18, 19, 26-28) against CasADi's AD of the GPDM's own SX functions.

The reference composes ``gpdm.mean_function()`` into the joint motion of Eq. 26-28 with
``ca.jtimes`` (yd = dy/dx xd, ydd = dy/dx xdd + d(yd)/dx xd) and differentiates it, and
``gpdm.variance_function()`` (Eq. 19), once per model.
"""
import casadi as ca
import numpy as np
import pytest

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.latent import GPLayer, IdentityLayer, LatentMotion

RTOL = 1e-10  # of the largest reference entry, per array


def _learn(Y, d: int):
    return learn_gpdm(Y, GPDMSettings(latent_dim=d, max_iterations=40))


@pytest.fixture(scope="module", params=["d2", "d3", "two_sequences"])
def gpdm(request):
    if request.param == "d2":
        return _learn(synthetic_motion(30, 5, seed=11, cycles=1.0, noise=0.02), 2)
    if request.param == "d3":
        return _learn(synthetic_motion(36, 6, seed=12, cycles=1.5, noise=0.02), 3)
    Y = synthetic_motion(44, 5, seed=13, cycles=2.0, noise=0.02)
    model = _learn([Y[:24], Y[24:]], 3)
    assert model.sequence_lengths == [24, 20]
    return model


def _reference(gpdm) -> ca.Function:
    """z = (x, xd, xdd), mu, lam -> u = (y, yd, ydd), du/dz, d2(mu . u)/dz2, sigma^2, its gradient, lam times its Hessian."""
    d = gpdm.latent_dim
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    z = ca.vertcat(x, xd, xdd)
    y = gpdm.mean_function()(x)
    yd = ca.jtimes(y, x, xd)
    ydd = ca.jtimes(y, x, xdd) + ca.jtimes(yd, x, xd)
    u = ca.vertcat(y, yd, ydd)
    mu = ca.SX.sym("mu", u.numel())
    lam = ca.SX.sym("lam")
    s2 = gpdm.variance_function()(x)
    return ca.Function("ref", [z, mu, lam], [u, ca.jacobian(u, z), ca.hessian(ca.dot(mu, u), z)[0],
                                             s2, ca.gradient(s2, x), lam * ca.hessian(s2, x)[0]])


def _points(gpdm, K: int, seed: int) -> np.ndarray:
    """K latent points (x, xd, xdd) near the training points, and one far from them."""
    rng = np.random.default_rng(seed)
    d, sc = gpdm.latent_dim, gpdm.X.std(axis=0)
    X = gpdm.X[rng.integers(0, len(gpdm.X), K)] + 0.2 * sc * rng.standard_normal((K, d))
    X[-1] = gpdm.X.mean(axis=0) + 10.0 * np.ptp(gpdm.X, axis=0)
    Xd = 2.0 * sc * rng.standard_normal((K, d))
    Xdd = 10.0 * sc * rng.standard_normal((K, d))
    return np.hstack([X, Xd, Xdd])


def _close(got, want, rtol=RTOL):
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape
    np.testing.assert_allclose(got, want, rtol=0, atol=rtol * max(np.abs(want).max(), 1e-300))


@pytest.fixture(scope="module")
def case(gpdm):
    """Layer outputs and CasADi's at the same points and multipliers."""
    layer = GPLayer(gpdm)
    K, D = 7, gpdm.output_dim
    Z = _points(gpdm, K, seed=3)
    rng = np.random.default_rng(4)
    mu, lam = rng.standard_normal((K, 3 * D)), rng.standard_normal(K)
    ref = _reference(gpdm)
    out = [ref(Z[k], mu[k], lam[k]) for k in range(K)]
    want = {name: np.array([np.asarray(o[i]) for o in out]) for i, name in
            enumerate(["u", "J", "H", "s2", "g", "Hs"])}
    return layer, Z, mu, lam, want


def test_motion_values(case, gpdm):
    """y, yd, ydd of Eq. 18, 26-28; y also against the GPDM's numpy mean."""
    layer, Z, _, _, want = case
    D, d = gpdm.output_dim, gpdm.latent_dim
    m = layer.motion(Z)
    assert isinstance(m, LatentMotion)
    u = want["u"][:, :, 0]
    _close(m.y, u[:, :D])
    _close(m.yd, u[:, D:2 * D])
    _close(m.ydd, u[:, 2 * D:])
    _close(m.y, gpdm.mean(Z[:, :d]))
    # far from the data the mean falls back to the data mean, with no motion
    np.testing.assert_allclose(m.y[-1], gpdm.Y_mean, rtol=0, atol=1e-12)
    assert np.abs(m.yd[-1]).max() < 1e-12 and np.abs(m.G0[-1]).max() < 1e-12


def test_motion_tangents_and_their_structure(case, gpdm):
    """G0, G1, G2 = d(y, yd, ydd)/dx, and the rest of du/dz is fixed by them:
    dyd/dxd = G0, dydd/dxd = 2 G1, dydd/dxdd = G0, dy/d(xd, xdd) = dyd/dxdd = 0."""
    layer, Z, _, _, want = case
    D, d = gpdm.output_dim, gpdm.latent_dim
    m = layer.motion(Z)
    J = want["J"]  # K x 3D x 3d
    for G in (m.G0, m.G1, m.G2):
        assert G.shape == (len(Z), D, d)
    _close(m.G0, J[:, :D, :d])
    _close(m.G1, J[:, D:2 * D, :d])
    _close(m.G2, J[:, 2 * D:, :d])
    _close(J[:, D:2 * D, d:2 * d], m.G0)
    _close(J[:, 2 * D:, d:2 * d], 2 * m.G1)
    _close(J[:, 2 * D:, 2 * d:], m.G0)
    assert np.abs(J[:, :D, d:]).max() == 0 and np.abs(J[:, D:2 * D, 2 * d:]).max() == 0


def test_curvature(case):
    """sum_j mu_j d2u_j/dz2 over z = (x, xd, xdd)."""
    layer, Z, mu, _, want = case
    H = layer.curvature(Z, mu)
    _close(H, want["H"])
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), rtol=0, atol=1e-12 * np.abs(H).max())
    # flat multipliers (K 3D) are the same multipliers
    _close(layer.curvature(Z, mu.ravel()), want["H"])


def test_variance_and_derivatives(case, gpdm):
    """sigma^2 (Eq. 19), its gradient and lam d2 sigma^2/dx2; sigma^2 also against GPDM.variance."""
    layer, Z, _, lam, want = case
    X = Z[:, :gpdm.latent_dim]
    s2, g = layer.variance(X)
    _close(s2, want["s2"].ravel())
    _close(s2, gpdm.variance(X))
    _close(g, want["g"][:, :, 0])
    s2b, gb, H = layer.variance(X, lam)
    np.testing.assert_array_equal(s2b, s2)
    np.testing.assert_array_equal(gb, g)
    _close(H, want["Hs"])
    assert s2[-1] == pytest.approx(layer.s2_max, rel=1e-3)  # far from the data: b1 + 1/b3


def test_finite_differences(gpdm):
    """The tangents and the variance gradient against central differences (no CasADi)."""
    layer, d = GPLayer(gpdm), gpdm.latent_dim
    Z = _points(gpdm, 4, seed=5)
    m = layer.motion(Z)
    h = 1e-5
    for a in range(d):
        dz = np.zeros_like(Z)
        dz[:, a] = h
        mp, mm = layer.motion(Z + dz), layer.motion(Z - dz)
        for G, u in ((m.G0, "y"), (m.G1, "yd"), (m.G2, "ydd")):
            fd = (getattr(mp, u) - getattr(mm, u)) / (2 * h)
            _close(G[:, :, a], fd, rtol=1e-6)
        fd = (layer.variance(Z[:, :d] + dz[:, :d])[0] - layer.variance(Z[:, :d] - dz[:, :d])[0]) / (2 * h)
        _close(layer.variance(Z[:, :d])[1][:, a], fd, rtol=1e-6)


def test_feature_cache_follows_contents(gpdm):
    """The cached kernel features are keyed on the values: an array changed in place, other
    point sets in between and caller-side edits of results give the fresh layer's values."""
    layer, d = GPLayer(gpdm), gpdm.latent_dim
    Z = _points(gpdm, 5, seed=6)
    mu = np.random.default_rng(7).standard_normal((5, 3 * gpdm.output_dim))
    layer.motion(Z)
    for seed in range(8, 16):  # more point sets than the cache keeps
        layer.motion(_points(gpdm, 5, seed=seed))
    Z += 0.01
    fresh = GPLayer(gpdm)
    for got, want in ((layer.motion(Z), fresh.motion(Z)),):
        for f in ("y", "yd", "ydd", "G0", "G1", "G2"):
            np.testing.assert_array_equal(getattr(got, f), getattr(want, f))
    np.testing.assert_array_equal(layer.curvature(Z, mu), fresh.curvature(Z, mu))
    s2, g = layer.variance(Z[:, :d])
    s2[:] = 0.0
    g[:] = 0.0
    np.testing.assert_array_equal(layer.variance(Z[:, :d])[0], fresh.variance(Z[:, :d])[0])
    np.testing.assert_array_equal(layer.variance(Z[:, :d])[1], fresh.variance(Z[:, :d])[1])


def test_no_points(gpdm):
    layer, d, D = GPLayer(gpdm), gpdm.latent_dim, gpdm.output_dim
    m = layer.motion(np.zeros((0, 3 * d)))
    assert m.y.shape == (0, D) and m.G2.shape == (0, D, d)
    assert layer.curvature(np.zeros((0, 3 * d)), np.zeros((0, 3 * D))).shape == (0, 3 * d, 3 * d)
    s2, g, H = layer.variance(np.zeros((0, d)), np.zeros(0))
    assert s2.shape == (0,) and g.shape == (0, d) and H.shape == (0, d, d)


def test_identity_layer():
    """y = x: G0 = I, G1 = G2 = 0, no curvature."""
    layer = IdentityLayer(4)
    assert layer.latent_dim == layer.output_dim == 4
    Z = np.random.default_rng(0).standard_normal((3, 12))
    m = layer.motion(Z)
    np.testing.assert_array_equal(m.y, Z[:, :4])
    np.testing.assert_array_equal(m.yd, Z[:, 4:8])
    np.testing.assert_array_equal(m.ydd, Z[:, 8:])
    np.testing.assert_array_equal(m.G0, np.broadcast_to(np.eye(4), (3, 4, 4)))
    assert not m.G1.any() and not m.G2.any()
    H = layer.curvature(Z, np.ones((3, 12)))
    assert H.shape == (3, 12, 12) and not H.any()


@pytest.fixture(scope="module")
def small_layer():
    return GPLayer(_learn(synthetic_motion(20, 4, seed=21, cycles=1.0), 2))


@pytest.mark.parametrize("call, name", [
    (lambda L: L.motion(np.zeros((3, 5))), "Z"),
    (lambda L: L.motion(np.zeros(6)), "Z"),
    (lambda L: L.curvature(np.zeros((3, 4)), np.zeros((3, 12))), "Z"),
    (lambda L: L.curvature(np.zeros((3, 6)), np.zeros((3, 11))), "mu"),
    (lambda L: L.curvature(np.zeros((3, 6)), np.zeros((2, 12))), "mu"),
    (lambda L: L.variance(np.zeros((3, 3))), "X"),
    (lambda L: L.variance(np.zeros(2)), "X"),
    (lambda L: L.variance(np.zeros((3, 2)), np.zeros(2)), "lam"),
])
def test_bad_shapes_name_the_input(small_layer, call, name):
    with pytest.raises(ValueError, match=rf"^{name}: .*got shape"):
        call(small_layer)


@pytest.mark.parametrize("call, name", [
    (lambda L: L.motion(np.zeros((3, 5))), "Z"),
    (lambda L: L.curvature(np.zeros((3, 6)), np.zeros((3, 5))), "mu"),
])
def test_identity_layer_bad_shapes(call, name):
    with pytest.raises(ValueError, match=rf"^{name}: .*got shape"):
        call(IdentityLayer(2))


def test_blas_threads_restored(small_layer):
    """The layer runs OpenBLAS on one thread and gives the caller's thread count back, also
    after an error."""
    from latentoc.runtime.threads import openblas_handles

    handles = openblas_handles()
    if not handles:
        pytest.skip("no OpenBLAS found")
    before = [int(get()) for get, _ in handles]
    small_layer.motion(np.zeros((3, 6)))
    small_layer.variance(np.zeros((3, 2)), np.ones(3))
    with pytest.raises(ValueError):
        small_layer.curvature(np.zeros((3, 6)), np.zeros((3, 5)))
    assert [int(get()) for get, _ in handles] == before
