"""latentoc.nlp.jit: compiled robot blocks fall back to CasADi's virtual machine without a
working compiler; Ipopt's BLAS threads (latentoc.nlp.ipopt.load_ipopt)."""
import os
import subprocess
import sys

import casadi as ca
import numpy as np
import pytest

from latentoc.nlp.blocks import RobotBlock, block_inputs, compile_blocks


def _block(name: str) -> RobotBlock:
    y, yd, ydd, r = block_inputs(2, 1)
    return RobotBlock.from_parts(name, (y, yd, ydd, r), {"f": ca.sin(y[0]) * yd[1] + r[0] * ydd[0] ** 2}, 1)


@pytest.mark.parametrize("cc", ["no-such-compiler", "false"])
def test_blocks_fall_back_to_sx_without_a_working_compiler(cc, tmp_path, monkeypatch):
    """No compiler (warning), or one that fails (warning): the blocks keep CasADi's SX Functions,
    with the same values, and nothing is left in the cache."""
    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    monkeypatch.setenv("CC", cc)
    if cc == "false":
        monkeypatch.setenv("PATH", os.environ["PATH"])  # /bin/false or /usr/bin/false: runs and fails
    b = _block(f"lc_fallback_{cc.replace('-', '_')}")
    with pytest.warns(UserWarning, match="no C compiler|failed"):
        compile_blocks([b])
    assert all(f.is_a("SXFunction") for f in b.functions.values())
    assert not list(tmp_path.glob("*.so")) and not list(tmp_path.glob(".build-*"))
    ref = b.derivative_functions()["rows"]
    x = np.array([0.3, -0.2])
    assert np.allclose(np.asarray(b.functions["rows"](x, x, x, [0.5])), np.asarray(ref(x, x, x, [0.5])))


@pytest.mark.slow  # fresh processes
def test_ipopt_loads_its_blas_on_one_thread():
    """Loading the Ipopt plugin starts no OpenBLAS worker threads (counted in /proc in a fresh
    process), leaves $OPENBLAS_NUM_THREADS unset, and a value the user sets is obeyed."""
    if not os.path.isdir("/proc/self/task"):
        pytest.skip("needs /proc to count threads")
    code = ("import os, numpy, casadi, latentoc\n"
            "n = len(os.listdir('/proc/self/task'))\n"
            "from latentoc.nlp.ipopt import load_ipopt\n"
            "load_ipopt()\n"
            "print(len(os.listdir('/proc/self/task')) - n, os.environ.get('OPENBLAS_NUM_THREADS'))\n")
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.split() == ["0", "None"]
    if (os.cpu_count() or 1) > 1:  # the count does see OpenBLAS's workers when they are asked for
        out = subprocess.run([sys.executable, "-c", code], env={**env, "OPENBLAS_NUM_THREADS": "2"},
                             capture_output=True, text=True, check=True).stdout
        assert out.split() == ["1", "2"]


def test_a_damaged_library_is_compiled_again_and_an_index_never_points_outside(tmp_path, monkeypatch):
    """A truncated cached library (loading it would crash the process) is found by its checksum,
    removed with a one-line warning and compiled again, with the same values; an index whose
    libraries are paths outside the cache (an edited file) is not followed but compiled anew."""
    import json

    from latentoc.nlp import jit

    monkeypatch.setenv("LATENTOC_CACHE", str(tmp_path))
    monkeypatch.delenv("LATENTOC_JIT", raising=False)
    if jit.compiler() is None:
        pytest.skip("no C compiler")
    x = np.array([0.3, -0.2])
    want = np.asarray(_block("lc_damaged").derivative_functions()["rows"](x, x, x, [0.5]))
    compile_blocks([_block("lc_damaged")])
    libs = sorted(tmp_path.glob("lc_*.so"))
    assert len(libs) == 3 and all((lib.parent / (lib.name + ".sha256")).exists() for lib in libs)
    libs[0].write_bytes(libs[0].read_bytes()[:100])  # truncated, as by a full disk or a killed copy
    with pytest.warns(UserWarning, match="damaged or without its checksum; compiling it again"):
        b = compile_blocks([_block("lc_damaged")])[0]
    assert all(f.is_a("External") for f in b.functions.values())
    np.testing.assert_allclose(np.asarray(b.functions["rows"](x, x, x, [0.5])), want, rtol=1e-14)
    index = next(tmp_path.glob("rb_*.json"))
    entry = json.loads(index.read_text())
    outside = tmp_path.parent / "elsewhere.so"
    outside.write_bytes(libs[1].read_bytes())
    entry["libraries"] = [[str(outside)]] * 3
    index.write_text(json.dumps(entry))
    b = compile_blocks([_block("lc_damaged")])[0]
    assert all(jit.LIBRARY_NAME.fullmatch(n) for parts in json.loads(index.read_text())["libraries"] for n in parts)
    np.testing.assert_allclose(np.asarray(b.functions["rows"](x, x, x, [0.5])), want, rtol=1e-14)


@pytest.mark.slow  # fresh processes
def test_processes_compiling_one_library_at_once_compile_it_once(tmp_path):
    """Two processes that need the same library on an empty cache (a sweep's workers) run the
    compiler once between them (counted by a wrapper around it); both get the library, and its
    values are the SX Function's."""
    import shutil

    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler")
    log = tmp_path / "calls"
    wrapper = tmp_path / "cc"
    wrapper.write_text(f"#!/bin/sh\necho x >> {log}\nsleep 2\nexec {cc} \"$@\"\n")  # slow: the two overlap
    wrapper.chmod(0o755)
    code = ("import sys, casadi as ca, numpy as np\n"
            "from latentoc.nlp.jit import Compiler\n"
            "x = ca.SX.sym('x', 3)\n"
            "f = ca.Function('lc_twice', [x], [ca.sin(x) * ca.sumsqr(x)])\n"
            "cg = ca.CodeGenerator('lc_twice.c'); cg.add(f)\n"
            "with Compiler() as c: lib = c.submit('twice', cg.dump(), ('-O0',)).result()\n"
            "g = ca.external('lc_twice', str(lib))\n"
            "v = np.array([0.3, -1.2, 2.0])\n"
            "print(lib.name, float(np.max(np.abs(np.asarray(g(v)) - np.asarray(f(v))))))\n")
    env = {**os.environ, "LATENTOC_CACHE": str(tmp_path / "cache"), "CC": str(wrapper), "LATENTOC_JIT": "1"}
    runs = [subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             text=True) for _ in range(2)]
    outs = [r.communicate(timeout=120) for r in runs]
    assert all(r.returncode == 0 for r in runs), [o[1][-1000:] for o in outs]
    names, errors = zip(*(o[0].split() for o in outs))
    assert names[0] == names[1] and max(map(float, errors)) < 1e-12
    assert log.read_text().count("x") == 1
