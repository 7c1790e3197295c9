"""Local evaluators: the GP mean (joint-limit rows) and the variance, against CasADi's AD."""
import casadi as ca
import numpy as np

from latentoc.benchmarks.gpdm_bench import synthetic_motion
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.latent import GPLayer
from latentoc.nlp.evaluators import MeanEvaluator, VarianceEvaluator


def _gpdm():
    return learn_gpdm(synthetic_motion(30, 5, seed=11, cycles=1.0, noise=0.02),
                      GPDMSettings(latent_dim=2, max_iterations=40))


def test_mean_and_variance_evaluators_match_casadi():
    gp = _gpdm()
    layer = GPLayer(gp)
    rng = np.random.default_rng(0)
    X = gp.X[[3, 11, 27]] + 0.05 * rng.standard_normal((3, 2))
    lam = rng.standard_normal((3, 5))
    x = ca.SX.sym("x", 2)
    l = ca.SX.sym("l", 5)
    y = gp.mean_function()(x)
    s2 = gp.variance_function()(x)
    ref = ca.Function("ref", [x, l], [y, ca.jacobian(y, x), ca.hessian(ca.dot(l, y), x)[0], s2,
                                      ca.jacobian(s2, x), ca.hessian(s2, x)[0]])
    mean, var = MeanEvaluator(layer), VarianceEvaluator(layer)
    F, J = mean.jacobian(X)
    H = mean.hessian(X, lam)
    V, JV = var.jacobian(X)
    HV = var.hessian(X, np.ones((3, 1)))
    for k in range(3):
        y_, Jy, Hy, s_, Js, Hs = (np.asarray(a) for a in ref(X[k], lam[k]))
        np.testing.assert_allclose(F[k], y_.ravel(), rtol=1e-10)
        np.testing.assert_allclose(mean.values(X)[k], y_.ravel(), rtol=1e-10)
        np.testing.assert_allclose(J[k], Jy, rtol=1e-8, atol=1e-10 * np.abs(Jy).max())
        np.testing.assert_allclose(H[k], Hy, rtol=1e-8, atol=1e-10 * np.abs(Hy).max())
        np.testing.assert_allclose(V[k, 0], s_.item(), rtol=1e-10)
        np.testing.assert_allclose(JV[k, 0], Js.ravel(), rtol=1e-8, atol=1e-10 * np.abs(Js).max())
        np.testing.assert_allclose(HV[k], Hs, rtol=1e-8, atol=1e-10 * np.abs(Hs).max())
