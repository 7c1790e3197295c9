"""Compiling CasADi Functions to C: the system compiler, flags and an on-disk cache.

Libraries are cached under ``$LATENTOC_CACHE`` (else ``$XDG_CACHE_HOME/latentoc/jit`` or
``~/.cache/latentoc/jit``) by a hash of their C source, the compiler, the flags and CasADi's
version, written atomically with their SHA-256 beside them and verified before they are loaded
(:func:`cached_library`), so only the first build on a machine compiles and a damaged file is
compiled again. Processes that need the same library at once (a sweep's workers on an empty
cache) take a lock file beside it: one compiles, the others wait and load its library. Without a
compiler (warning) or with ``LATENTOC_JIT=0`` the Functions stay in CasADi's virtual machine.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import warnings
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path

import casadi as ca

from latentoc.runtime.files import exclusive_lock
from latentoc.runtime.interrupts import interrupts_seen
from latentoc.runtime.paths import cache_dir
from latentoc.runtime.progress import bar
from latentoc.runtime.threads import mapped_threads

CASADI_VERSION: str = getattr(ca, "__version__")  # a key of the cached libraries

__all__ = ["JIT_FLAGS", "c_source", "cache_dir", "compiler", "enabled", "Compiler", "node_map"]

JIT_FLAGS = ("-O1",)  # code evaluated at every Ipopt iteration over many nodes: a half to an eighth of -O0's time
ONCE_FLAGS = ("-O0",)  # code whose evaluation costs little (one node): the quickest compile
# gcc's optimiser is superlinear on long straight-line code: hot Functions longer than this are
# compiled as pieces of about this length (:mod:`latentoc.nlp.split`)
PIECE_INSTRUCTIONS = 250_000


def flags_for(hot: bool = True) -> tuple[str, ...]:
    """Compiler flags: -O1 for ``hot`` code (evaluated at many nodes every iteration, in pieces of
    at most about :data:`PIECE_INSTRUCTIONS`), else -O0 (docs/derivatives.md)."""
    return JIT_FLAGS if hot else ONCE_FLAGS


def c_source(f: ca.Function) -> str:
    """The C source of Function ``f`` as a library of its own (no header)."""
    gen = ca.CodeGenerator(f"{f.name()}.c", {"with_header": False})
    gen.add(f)
    return gen.dump()


def compiler() -> str | None:
    """The C compiler: $CC if set (None if it is not found), else gcc, else cc, else None."""
    if os.environ.get("CC"):
        return shutil.which(os.environ["CC"])
    return shutil.which("gcc") or shutil.which("cc")


def enabled() -> bool:
    """False when ``LATENTOC_JIT=0``."""
    return os.environ.get("LATENTOC_JIT", "1") != "0"


THREADED_WORK = 2_000_000  # instructions per mapped call below which threads cost more than they share


def node_map(f: ca.Function, K: int, instructions: int = 0, compiled: bool = True) -> ca.Function:
    """``f`` mapped over K nodes, on :func:`~latentoc.runtime.threads.mapped_threads` threads when f
    is ``compiled`` (in CasADi's virtual machine threads are slower) and the call does enough work
    (``instructions`` per node)."""
    n = mapped_threads()
    if K > 1 and n > 1 and compiled and K * instructions >= THREADED_WORK:
        return f.map(K, "thread", min(n, K))
    return f.map(K)


LIBRARY_NAME = re.compile(r"lc_[0-9a-f]{24}\.so")  # a cached library's name: its key


def library_path(source: str, flags: tuple[str, ...] = JIT_FLAGS) -> Path:
    key = hashlib.sha256("\0".join([source, str(compiler()), *flags, CASADI_VERSION]).encode()).hexdigest()[:24]
    return cache_dir() / f"lc_{key}.so"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _checksum_file(lib: Path) -> Path:
    return lib.with_name(lib.name + ".sha256")


def cached_library(name: str) -> Path | None:
    """The cached library ``name`` (a bare name of the cache's own form, never a path) if it is
    whole: its SHA-256 is the one recorded when it was compiled. A damaged or foreign file (a
    truncated library would crash the process when loaded) is removed with a one-line warning,
    so that it is compiled again."""
    if not LIBRARY_NAME.fullmatch(str(name)):
        return None
    lib = cache_dir() / name
    try:
        if not lib.exists():
            return None
        if _checksum_file(lib).read_text().strip() == _digest(lib):
            return lib
    except OSError:
        pass
    warnings.warn(f"{lib}: damaged or without its checksum; compiling it again", stacklevel=2)
    for f in (lib, _checksum_file(lib)):
        f.unlink(missing_ok=True)
    return None


class Compiler:
    """Compiles C sources to shared libraries in the background, ``workers`` at a time, while the
    caller generates the next ones; a library already in the cache is not compiled again.

    ``submit`` returns a Future of the library's path, or of None when the source could not be
    compiled (no compiler, or it failed: warning). Use as a context manager: leaving it waits for
    every library, with a progress bar."""

    def __init__(self, workers: int | None = None):
        self.cc = compiler()
        self.pool = ThreadPoolExecutor(max_workers=workers or mapped_threads())
        self.bar = bar(total=0, desc=f"compiling C libraries into {cache_dir()}", unit="lib")
        self.futures: list = []
        if self.cc is None:
            warnings.warn("no C compiler found (set CC): evaluating the NLP Functions without JIT", stacklevel=3)

    def __enter__(self) -> "Compiler":
        return self

    def __exit__(self, kind, *exc) -> None:
        try:
            if kind is None:
                for f in self.futures:
                    f.result()
        except BaseException:
            kind = BaseException
            raise
        finally:  # after an error or Ctrl-C the libraries not started are not needed
            self.pool.shutdown(wait=kind is None, cancel_futures=kind is not None)
            self.bar.close()

    def submit(self, label: str, source: str, flags: tuple[str, ...]):
        lib = library_path(source, flags)
        if self.cc is None or cached_library(lib.name) is not None:
            done: Future = Future()
            done.set_result(None if self.cc is None else lib)
            return done
        self.bar.total += 1
        self.bar.refresh()
        fut = self.pool.submit(self._build, label, source, flags, lib)
        self.futures.append(fut)
        return fut

    def _build(self, label: str, source: str, flags: tuple[str, ...], lib: Path) -> Path | None:
        seen = interrupts_seen()
        try:
            assert self.cc is not None  # submit() compiles nothing without one
            return build_library(self.cc, source, flags, lib)
        except (OSError, subprocess.CalledProcessError) as exc:
            if interrupts_seen() > seen or getattr(exc, "returncode", 0) < 0:  # Ctrl-C reached the compiler too
                return None
            detail = getattr(exc, "stderr", "") or str(exc)
            warnings.warn(f"compiling {label} failed ({detail.strip()[:200]}): evaluating without JIT", stacklevel=3)
            return None
        finally:
            self.bar.update(1)


def build_library(cc: str, source: str, flags: tuple[str, ...], lib: Path) -> Path:
    """Compile ``source`` with ``flags`` into the cached library ``lib`` (module doc: a lock beside it,
    written atomically with its checksum); an OSError or CalledProcessError if it cannot be."""
    cache = lib.parent
    cache.mkdir(parents=True, exist_ok=True)
    # one process compiles a library others need at once; the others wait and find it
    with exclusive_lock(lib.with_name(lib.name + ".lock")), tempfile.TemporaryDirectory(dir=cache, prefix=".build-") as tmp:
        if cached_library(lib.name) is not None:  # another process compiled it while we waited
            return lib
        c_file, so_file = Path(tmp) / f"{lib.stem}.c", Path(tmp) / lib.name
        c_file.write_text(source)
        subprocess.run([cc, *flags, "-shared", "-fPIC", "-o", str(so_file), str(c_file), "-lm"],
                       check=True, capture_output=True, text=True)
        # the checksum first, the library last, each renamed into place: a reader sees no
        # library, or a whole one whose checksum is there
        tmp_sum = Path(tmp) / "sha256"
        tmp_sum.write_text(_digest(so_file))
        os.replace(tmp_sum, _checksum_file(lib))
        os.replace(so_file, lib)
    return lib
