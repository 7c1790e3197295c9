"""The GP layer with a joint-space residual (latentoc.latent.residual_layer) against a CasADi
reference of y = GPDM mean(x) + E r along (x, r, their rates), and against central differences."""
import casadi as ca
import numpy as np
import pytest

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.latent.residual_layer import ResidualLayer

JOINTS = np.array([0, 3, 4])


@pytest.fixture(scope="module")
def gpdm():
    return learn_gpdm(synthetic_motion(36, 6, seed=12, cycles=1.5, noise=0.02), GPDMSettings(latent_dim=3, max_iterations=40))


def _reference(gpdm) -> ca.Function:
    d, r, D = gpdm.latent_dim, len(JOINTS), gpdm.output_dim
    E = np.zeros((D, r))
    E[JOINTS, np.arange(r)] = 1.0
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    q, qd, qdd = (ca.SX.sym(n, r) for n in ("r", "rd", "rdd"))
    z = ca.vertcat(x, q, xd, qd, xdd, qdd)
    y0 = gpdm.mean_function()(x)
    yd0 = ca.jtimes(y0, x, xd)
    ydd0 = ca.jtimes(y0, x, xdd) + ca.jtimes(yd0, x, xd)
    u = ca.vertcat(y0 + E @ q, yd0 + E @ qd, ydd0 + E @ qdd)
    mu, lam = ca.SX.sym("mu", u.numel()), ca.SX.sym("lam")
    xr = ca.vertcat(x, q)
    s2 = gpdm.variance_function()(x)
    return ca.Function("ref", [z, mu, lam], [u, ca.jacobian(u, z), ca.hessian(ca.dot(mu, u), z)[0], s2,
                                             ca.gradient(s2, xr), lam * ca.hessian(s2, xr)[0]])


def _points(gpdm, K: int) -> np.ndarray:
    rng = np.random.default_rng(5)
    d, r, sc = gpdm.latent_dim, len(JOINTS), gpdm.X.std(axis=0)
    X = gpdm.X[rng.integers(0, len(gpdm.X), K)] + 0.2 * sc * rng.standard_normal((K, d))
    R = 0.1 * rng.standard_normal((K, r))
    Xd, Xdd = 2.0 * sc * rng.standard_normal((K, d)), 10.0 * sc * rng.standard_normal((K, d))
    return np.hstack([X, R, Xd, rng.standard_normal((K, r)), Xdd, rng.standard_normal((K, r))])


def _close(got, want):
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * max(np.abs(want).max(), 1e-300))


def test_residual_layer_against_casadi(gpdm):
    """Values, tangents (G0, G1, G2 and the structure the robot blocks assume), curvature and the
    tube's sigma^2 of x alone, with its derivatives zero along r."""
    layer = ResidualLayer(gpdm, JOINTS)
    D, n = gpdm.output_dim, layer.latent_dim
    assert n == gpdm.latent_dim + len(JOINTS)
    assert layer.latent_coordinates == gpdm.latent_dim and layer.gp.latent_coordinates == gpdm.latent_dim
    K = 5
    Z = _points(gpdm, K)
    rng = np.random.default_rng(6)
    mu, lam = rng.standard_normal((K, 3 * D)), rng.standard_normal(K)
    ref = _reference(gpdm)
    out = [ref(Z[k], mu[k], lam[k]) for k in range(K)]
    u, J, H, s2, g, Hs = (np.array([np.asarray(o[i]) for o in out]) for i in range(6))
    m = layer.motion(Z)
    _close(m.y, u[:, :D, 0])
    _close(m.yd, u[:, D:2 * D, 0])
    _close(m.ydd, u[:, 2 * D:, 0])
    _close(m.G0, J[:, :D, :n])
    _close(m.G1, J[:, D:2 * D, :n])
    _close(m.G2, J[:, 2 * D:, :n])
    _close(J[:, D:2 * D, n:2 * n], m.G0)  # dyd/d(xd, rd) = G0
    _close(J[:, 2 * D:, n:2 * n], 2 * m.G1)
    _close(J[:, 2 * D:, 2 * n:], m.G0)
    _close(layer.curvature(Z, mu), H)
    X = Z[:, :n]
    s2_got, g_got, H_got = layer.variance(X, lam)
    _close(s2_got, s2.ravel())
    _close(g_got, g[:, :, 0])
    _close(H_got, Hs)
