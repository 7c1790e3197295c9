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
