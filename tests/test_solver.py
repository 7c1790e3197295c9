"""Ipopt wrapper on a small NLP with a known optimum."""

import os
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


def _small_functions():
    x = ca.SX.sym("x", 3)
    f = ca.Function("lc_test_f", [x], [ca.sin(x[0]) * ca.exp(x[1]) + x[2] ** 3, ca.hessian(ca.sumsqr(ca.sin(x)), x)[0]])
    g = ca.Function("lc_test_g", [x], [ca.cos(x) * x[0]])
    return [f, g]


def test_compiled_functions_match_and_are_cached(tmp_path, monkeypatch):
    """Compiled Functions equal the SX ones at random points; the second call loads the
    cached library without running the compiler."""
    from latentoc import solver
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    fns = _small_functions()
    compiled = solver.compiled_functions(fns)
    libs = list(tmp_path.glob("lc_*.so"))
    assert len(libs) == 1 and not list(tmp_path.glob(".build-*"))  # no temporary left behind
    assert [c.name() for c in compiled] == ["lc_test_f", "lc_test_g"]
    assert all(c.is_a("External") for c in compiled)
    rng = np.random.default_rng(0)
    for _ in range(5):
        x = rng.standard_normal(3)
        for f, c in zip(fns, compiled):
            for a, b in zip(f.call([x]), c.call([x])):
                assert a.sparsity() == b.sparsity()
                assert np.allclose(np.asarray(a), np.asarray(b), rtol=1e-12, atol=1e-12)

    def no_compiler(*args, **kwargs):
        raise AssertionError("compiler run despite the cache")
    monkeypatch.setattr(solver.subprocess, "run", no_compiler)
    again = solver.compiled_functions(_small_functions())
    assert all(c.is_a("External") for c in again) and list(tmp_path.glob("lc_*.so")) == libs


def test_compiled_functions_fall_back_without_compiler(tmp_path, monkeypatch):
    from latentoc import solver
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    monkeypatch.setattr(solver, "jit_compiler", lambda: None)
    fns = _small_functions()
    with pytest.warns(UserWarning, match="no C compiler"):
        out = solver.compiled_functions(fns)
    assert out == fns and not list(tmp_path.iterdir())
    monkeypatch.setattr(solver, "jit_compiler", lambda: "/bin/false")  # a "compiler" that fails
    with pytest.warns(UserWarning, match="compiling the NLP Functions failed"):
        assert solver.compiled_functions(fns) == fns
    assert not list(tmp_path.glob("lc_*.so")) and not list(tmp_path.glob(".build-*"))
    monkeypatch.setenv("LATENTOC_JIT", "0")
    assert solver.compiled_functions(fns) == fns


def test_recommended_ipopt_options_are_passed():
    """nlp["ipopt_options"] reaches Ipopt (an unknown option is rejected by it), the explicit
    arguments win over it, and the caller's dict is kept."""
    nlp = _nlp()
    nlp["ipopt_options"] = {"max_iter": 1000, "nlp_scaling_constr_target_gradient": 1.0}
    r = solve_nlp(build_solver(nlp, max_iter=2), np.array([-1.0, 1.0]), -np.inf * np.ones(2), np.inf * np.ones(2),
                  [-np.inf], [1.0])
    assert r.status == "Maximum_Iterations_Exceeded" and "ipopt_options" in nlp
    nlp["ipopt_options"] = {"no_such_ipopt_option": 1.0}
    with pytest.raises(RuntimeError):
        s = build_solver(nlp)
        solve_nlp(s, np.array([-1.0, 1.0]), -np.inf * np.ones(2), np.inf * np.ones(2), [-np.inf], [1.0])


def test_ipopt_loads_its_blas_on_one_thread():
    """Loading the Ipopt plugin starts no OpenBLAS worker threads (counted in /proc in a fresh
    process), leaves $OPENBLAS_NUM_THREADS unset, and a value the user sets is obeyed."""
    import subprocess
    import sys

    if not os.path.isdir("/proc/self/task"):
        pytest.skip("needs /proc to count threads")
    code = ("import os, numpy, casadi\n"
            "n = len(os.listdir('/proc/self/task'))\n"
            "from latentoc.solver import load_ipopt\n"
            "load_ipopt()\n"
            "print(len(os.listdir('/proc/self/task')) - n, os.environ.get('OPENBLAS_NUM_THREADS'))\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["0", "None"]
    if (os.cpu_count() or 1) > 1:  # the count does see OpenBLAS's workers when they are asked for
        out = subprocess.run([sys.executable, "-c", code], env={**env, "OPENBLAS_NUM_THREADS": "2"},
                             capture_output=True, text=True, check=True).stdout
        assert out.split() == ["1", "2"]
