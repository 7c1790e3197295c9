"""Ipopt through ``casadi.nlpsol``: building the solver and running it.

``hessian="exact"`` (default) uses CasADi's exact Hessian of the Lagrangian;
``hessian="lbfgs"`` uses Ipopt's limited-memory quasi-Newton approximation (the paper
used L-BFGS, Sect. 3.4). ``verbose=True`` shows Ipopt's own one-line-per-iteration log;
otherwise Ipopt is silent.

``mu_strategy="monotone"`` (Fiacco-McCormick) by default, measured on arm-raise against
"adaptive": latent tubes 1.2x-1000x 243 vs 330 iterations in total (1.5x/5x/50x: 39/57/24
vs 59/70/37), same optima; joint range +-5/20/45/90 deg 20/31/29/43 vs 26/61/53/64
iterations, same optima except +-90 deg (monotone finds a lower one, 213.2 vs 221.4).
(Those counts predate the latent row scaling, :data:`latentoc.transcription.LATENT_IPOPT_OPTIONS`:
now 1.5x/5x/50x take 34/27/24 iterations.)

:func:`compiled_functions` turns SX Functions into C (``CodeGenerator``), compiles them
with the system C compiler and loads them with ``casadi.external``. The shared library is
cached on disk under a hash of the C source, compiler and flags (``$LATENTOC_CACHE`` or
``$XDG_CACHE_HOME/latentoc/jit``, else ``~/.cache/latentoc/jit``), written atomically, so
only the first build on a machine pays the compile (arm node Hessian, 47k SX instructions:
~22 s with ``-O1``, ~2 s with ``-O0``); without a compiler, or with ``LATENTOC_JIT=0``, the
SX Functions are returned unchanged (with a warning when the compiler is missing or fails).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

__all__ = ["NLPResult", "build_solver", "solve_nlp", "HESSIANS", "compiled_functions", "compiled_libraries", "jit_cache_dir",
           "jit_compiler", "jit_enabled", "ipopt_solver", "load_ipopt"]

HESSIANS = ("exact", "lbfgs")


@dataclass
class NLPResult:
    """Outcome of one Ipopt run."""

    x: np.ndarray
    g: np.ndarray
    cost: float
    status: str
    success: bool
    iterations: int
    solve_time_s: float


def build_solver(nlp: dict, *, hessian: str = "exact", max_iter: int = 300, tol: float = 1e-8,
                 verbose: bool = False, name: str = "solver", expand: bool = False,
                 mu_strategy: str = "monotone") -> ca.Function:
    """An Ipopt ``casadi.Function`` for ``nlp = {"x", "f", "g"}``.

    ``nlp`` may also hold ``"derivatives"``: custom ``grad_f``, ``jac_g`` and ``hess_lag``
    Functions (e.g. :func:`latentoc.transcription.build_latent_nlp`'s lifted ones), passed
    to ``nlpsol`` in place of the generated ones (``hess_lag`` only with the exact Hessian),
    and ``"ipopt_options"``: Ipopt options the transcription recommends (e.g. scaling); the
    arguments of this function take precedence.
    """
    if hessian not in HESSIANS:
        raise ValueError(f"hessian must be one of {HESSIANS}, got {hessian!r}")
    nlp = dict(nlp)
    derivatives = dict(nlp.pop("derivatives", None) or {})
    recommended = dict(nlp.pop("ipopt_options", None) or {})
    if hessian != "exact":
        derivatives.pop("hess_lag", None)
    ipopt = {"max_iter": int(max_iter), "tol": float(tol), "print_level": 5 if verbose else 0,
             "sb": "yes", "mu_strategy": mu_strategy, "acceptable_tol": max(1e-6, 100 * float(tol)),
             "acceptable_iter": 10}
    ipopt = {**recommended, **ipopt}  # the explicit arguments win
    if hessian == "lbfgs":
        ipopt["hessian_approximation"] = "limited-memory"
    options = {"ipopt": ipopt, "print_time": False, "error_on_fail": False, "expand": bool(expand), **derivatives}
    return ipopt_solver(name, nlp, options)


_IPOPT_LOADED = False


def load_ipopt() -> None:
    """Load CasADi's Ipopt plugin, with the OpenBLAS it brings (under MUMPS) on one thread
    unless ``$OPENBLAS_NUM_THREADS`` is set.  OpenBLAS reads the variable once, when the
    plugin's libraries are loaded; numpy's own OpenBLAS, loaded before, keeps its threads.
    Its spinning worker threads competed with the threaded node evaluations: broad jump,
    phase 2 at delta 0.005 on 2 cores, 103 s (45.6 s of it system time) with the default,
    82 s (3.3 s) with one thread, same 140 iterations (issue 6)."""
    global _IPOPT_LOADED
    if _IPOPT_LOADED:
        return
    unset = "OPENBLAS_NUM_THREADS" not in os.environ
    if unset:
        os.environ["OPENBLAS_NUM_THREADS"] = "1"
    try:
        ca.load_nlpsol("ipopt")
    finally:
        if unset:
            del os.environ["OPENBLAS_NUM_THREADS"]
    _IPOPT_LOADED = True


def ipopt_solver(name: str, nlp: dict, options: dict) -> ca.Function:
    """``casadi.nlpsol(name, "ipopt", nlp, options)`` after :func:`load_ipopt`."""
    load_ipopt()
    return ca.nlpsol(name, "ipopt", nlp, options)


def solve_nlp(solver: ca.Function, x0: np.ndarray, lbx: np.ndarray, ubx: np.ndarray,
              lbg: np.ndarray, ubg: np.ndarray) -> NLPResult:
    """Run Ipopt from x0; status is Ipopt's return status (``Solve_Succeeded`` ...)."""
    t0 = time.perf_counter()
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    success = bool(stats.get("success", False)) or status == "Solved_To_Acceptable_Level"
    return NLPResult(x=np.asarray(sol["x"]).ravel(), g=np.asarray(sol["g"]).ravel(),
                     cost=float(sol["f"]), status=status, success=success,
                     iterations=int(stats.get("iter_count", -1)), solve_time_s=elapsed)


JIT_FLAGS = ("-O1",)  # -O1: 14x faster than the VM on the arm node Hessian; -O2/-O3 compile longer


def jit_cache_dir() -> Path:
    """Directory of compiled Functions: $LATENTOC_CACHE, else the user cache dir."""
    if os.environ.get("LATENTOC_CACHE"):
        return Path(os.environ["LATENTOC_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "latentoc" / "jit"


def jit_compiler() -> str | None:
    """The C compiler of the JIT ($CC, else gcc, else cc), or None."""
    cc = os.environ.get("CC") or "gcc"
    return shutil.which(cc) or shutil.which("cc")


def jit_enabled() -> bool:
    """False when ``LATENTOC_JIT=0``: the Functions are evaluated in CasADi's virtual machine."""
    return os.environ.get("LATENTOC_JIT", "1") != "0"


def compiled_functions(functions: list[ca.Function], flags: tuple[str, ...] = JIT_FLAGS) -> list[ca.Function]:
    """The Functions compiled to C and loaded back (same names, inputs, outputs and values).

    Cached on disk by a hash of the generated source, compiler and flags (module doc); a
    second call with the same Functions loads the library without compiling. Falls back to
    the given Functions if ``LATENTOC_JIT=0``, or (warning) if there is no C compiler or it fails.
    """
    return compiled_function_groups([functions], flags)[0]


def compiled_function_groups(groups: list[list[ca.Function]], flags: tuple[str, ...] = JIT_FLAGS,
                             workers: int = 2, external_options: dict | None = None) -> list[list[ca.Function]]:
    """:func:`compiled_functions` for several groups, one library each: the C sources are
    generated one after the other (CasADi's code generator is not safe to run from several
    threads: concurrent runs gave different sources), the libraries compiled ``workers`` at a time.
    ``external_options`` go to ``casadi.external`` (e.g. ``enable_fd`` for derivatives)."""
    libs = compiled_libraries(groups, flags, workers)
    opts = dict(external_options or {})
    return [list(g) if lib is None else [ca.external(f.name(), str(lib), opts) for f in g] for g, lib in zip(groups, libs)]


def compiled_libraries(groups: list[list[ca.Function]], flags: tuple[str, ...] = JIT_FLAGS,
                       workers: int = 2) -> list[Path | None]:
    """The shared library of each group (:func:`compiled_function_groups`), or None for a group
    that is not compiled (``LATENTOC_JIT=0``, no compiler, or the compiler failed: warning)."""
    if not jit_enabled():
        return [None] * len(groups)
    cc = jit_compiler()
    if cc is None:
        warnings.warn("no C compiler found (set CC): evaluating the NLP Functions without JIT", stacklevel=3)
        return [None] * len(groups)
    sources = []
    for functions in groups:
        gen = ca.CodeGenerator("latentoc_jit.c", {"with_header": False})
        for f in functions:
            gen.add(f)
        sources.append(gen.dump())

    def build(source: str) -> Path | None:
        key = hashlib.sha256("\0".join([source, cc, *flags, ca.__version__]).encode()).hexdigest()[:24]
        cache = jit_cache_dir()
        lib = cache / f"lc_{key}.so"
        if lib.exists():
            return lib
        try:
            cache.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=cache, prefix=".build-") as tmp:
                c_file, so_file = Path(tmp) / f"lc_{key}.c", Path(tmp) / f"lc_{key}.so"
                c_file.write_text(source)
                subprocess.run([cc, *flags, "-shared", "-fPIC", "-o", str(so_file), str(c_file), "-lm"],
                               check=True, capture_output=True, text=True)
                os.replace(so_file, lib)  # atomic: readers see no library or a complete one
        except (OSError, subprocess.CalledProcessError) as exc:
            detail = getattr(exc, "stderr", "") or str(exc)
            warnings.warn(f"compiling the NLP Functions failed ({detail.strip()[:200]}): evaluating without JIT",
                          stacklevel=3)
            return None
        return lib

    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        return list(pool.map(build, sources))  # the compiler runs outside Python: threads suffice
