"""The one Ipopt path (latentoc.nlp.ipopt.solve) on a small NLP with a known optimum: the
Rosenbrock function on the unit disc, through a SparseNLP with one hand-written family."""

import casadi as ca
import numpy as np
import pytest
import scipy.sparse as sp

from latentoc.nlp import ipopt
from latentoc.nlp.assemble import Family, SparseNLP

OPTIMUM = [0.78641515, 0.61769831]  # on the unit circle


class Disc:
    """x0^2 + x1^2 at one node, local inputs s = (x0, x1)."""

    n_in, n_out = 2, 1

    def values(self, s):
        return np.sum(s * s, axis=1, keepdims=True)

    def jacobian(self, s):
        return self.values(s), 2.0 * s[:, None, :]

    def hessian(self, s, lam):
        return 2.0 * lam[:, 0, None, None] * np.eye(2)[None]


def rosenbrock_nlp() -> SparseNLP:
    w = ca.SX.sym("w", 2)
    terms = ca.Function("rosenbrock", [w], [(1 - w[0]) ** 2 + 100 * (w[1] - w[0] ** 2) ** 2])
    disc = Family("disc", Disc(), sp.identity(2, format="csr"), np.zeros(2), Cg=sp.identity(1, format="csr"))
    return SparseNLP(2, [disc], terms)


def _solve(options=None, hessian="exact"):
    inf = np.full(2, np.inf)
    return ipopt.solve(rosenbrock_nlp(), np.array([-1.0, 1.0]), -inf, inf, [-np.inf], [1.0],
                       {"max_iter": 500, **(options or {})}, hessian=hessian)


@pytest.mark.parametrize("hessian", ipopt.HESSIANS)
def test_constrained_rosenbrock(hessian, capfd):
    r = _solve(hessian=hessian)
    assert r.success and r.iterations > 0 and r.time_s >= 0
    assert np.allclose(r.x, OPTIMUM, atol=1e-4)
    assert np.isclose(r.f, (1 - r.x[0]) ** 2 + 100 * (r.x[1] - r.x[0] ** 2) ** 2)
    assert np.isclose(r.g[0], 1.0) and r.lam_g[0] > 0
    assert ("nlp_hess_l" in r.calls) == (hessian == "exact")  # L-BFGS: no Hessian callback
    assert set(r.timings) == set(r.calls) and all(n > 0 for n in r.calls.values())
    assert "Ipopt" not in capfd.readouterr().out  # silent by default


def test_iteration_limit_reports_failure():
    r = _solve({"max_iter": 2})
    assert not r.success and r.status == "Maximum_Iterations_Exceeded" and r.iterations == 2


def test_bad_hessian_name():
    with pytest.raises(ValueError, match="hessian"):
        _solve(hessian="newton")


def test_options_reach_ipopt():
    with pytest.raises(RuntimeError):
        _solve({"no_such_ipopt_option": 1.0})


def test_warm_start_from_the_optimum_and_its_multipliers():
    first = _solve()
    inf = np.full(2, np.inf)
    again = ipopt.solve(rosenbrock_nlp(), first.x, -inf, inf, [-np.inf], [1.0], {"max_iter": 500},
                        warm=first.multipliers())
    assert again.success and again.iterations < first.iterations and np.allclose(again.x, OPTIMUM, atol=1e-4)
