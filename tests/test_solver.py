"""Ipopt wrapper on a small NLP with a known optimum."""

import casadi as ca
import numpy as np
import pytest

from latentoc.solver import build_solver, solve_nlp


def _nlp():
    x = ca.MX.sym("x", 2)
    f = (1 - x[0]) ** 2 + 100 * (x[1] - x[0] ** 2) ** 2
    return {"x": x, "f": f, "g": x[0] ** 2 + x[1] ** 2}


@pytest.mark.parametrize("hessian", ["exact", "lbfgs"])
def test_constrained_rosenbrock(hessian, capfd):
    s = build_solver(_nlp(), hessian=hessian, max_iter=500)
    r = solve_nlp(s, np.array([-1.0, 1.0]), -np.inf * np.ones(2), np.inf * np.ones(2), [-np.inf], [1.0])
    # optimum on the unit circle, known: x ~ (0.7864, 0.6177)
    assert r.success and r.iterations > 0 and r.solve_time_s >= 0
    assert np.allclose(r.x, [0.78641515, 0.61769831], atol=1e-4)
    assert np.isclose(r.cost, (1 - r.x[0]) ** 2 + 100 * (r.x[1] - r.x[0] ** 2) ** 2)
    assert "Ipopt" not in capfd.readouterr().out  # silent by default


def test_iteration_limit_reports_failure():
    s = build_solver(_nlp(), max_iter=2)
    r = solve_nlp(s, np.array([-1.0, 1.0]), -np.inf * np.ones(2), np.inf * np.ones(2), [-np.inf], [1.0])
    assert not r.success and r.status == "Maximum_Iterations_Exceeded"


def test_bad_hessian_name():
    with pytest.raises(ValueError, match="hessian"):
        build_solver(_nlp(), hessian="newton")


@pytest.mark.parametrize("hessian", ["exact", "lbfgs"])
def test_custom_derivatives_are_used(hessian):
    """nlp["derivatives"] replaces nlpsol's generated grad_f / jac_g / hess_lag: a hess_lag
    counting its calls is called with the exact Hessian and dropped with L-BFGS."""
    nlp = _nlp()
    x, f, g = nlp["x"], nlp["f"], nlp["g"]
    p, lf, lg = ca.MX.sym("p", 0), ca.MX.sym("lf"), ca.MX.sym("lg")
    calls = []

    class Counter(ca.Callback):
        def __init__(self):
            ca.Callback.__init__(self)
            self.construct("counter", {})

        def eval(self, arg):
            calls.append(1)
            return [arg[0]]

    counter = Counter()
    hess = ca.triu(ca.hessian(lf * f + lg * g, x)[0])
    nlp["derivatives"] = {
        "grad_f": ca.Function("grad_f", [x, p], [f, ca.gradient(f, x)], ["x", "p"], ["f", "grad_f_x"]),
        "jac_g": ca.Function("jac_g", [x, p], [g, ca.jacobian(g, x)], ["x", "p"], ["g", "jac_g_x"]),
        "hess_lag": ca.Function("hess_lag", [x, p, lf, lg], [ca.substitute(hess, lf, counter(lf))],
                                ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"]),
    }
    s = build_solver(nlp, hessian=hessian, max_iter=500)
    r = solve_nlp(s, np.array([-1.0, 1.0]), -np.inf * np.ones(2), np.inf * np.ones(2), [-np.inf], [1.0])
    assert r.success and np.allclose(r.x, [0.78641515, 0.61769831], atol=1e-4)
    assert (len(calls) > 0) == (hessian == "exact")
    assert "derivatives" in nlp  # the caller's dict is not modified
