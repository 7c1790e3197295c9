"""latentoc.solver's compiled Functions (used by the broad jump) and Ipopt's BLAS threads
(latentoc.solver and latentoc.nlp.ipopt load the plugin the same way)."""

import os

import casadi as ca
import numpy as np
import pytest


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


@pytest.mark.parametrize("module", ["latentoc.solver", "latentoc.nlp.ipopt"])
def test_ipopt_loads_its_blas_on_one_thread(module):
    """Loading the Ipopt plugin starts no OpenBLAS worker threads (counted in /proc in a fresh
    process), leaves $OPENBLAS_NUM_THREADS unset, and a value the user sets is obeyed."""
    import subprocess
    import sys

    if not os.path.isdir("/proc/self/task"):
        pytest.skip("needs /proc to count threads")
    code = ("import os, numpy, casadi\n"
            "n = len(os.listdir('/proc/self/task'))\n"
            f"from {module} import load_ipopt\n"
            "load_ipopt()\n"
            "print(len(os.listdir('/proc/self/task')) - n, os.environ.get('OPENBLAS_NUM_THREADS'))\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["0", "None"]
    if (os.cpu_count() or 1) > 1:  # the count does see OpenBLAS's workers when they are asked for
        out = subprocess.run([sys.executable, "-c", code], env={**env, "OPENBLAS_NUM_THREADS": "2"},
                             capture_output=True, text=True, check=True).stdout
        assert out.split() == ["1", "2"]
