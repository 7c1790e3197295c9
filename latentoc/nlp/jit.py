"""Compiling CasADi Functions to C: the system compiler, flags and an on-disk cache.

Libraries are cached under ``$LATENTOC_CACHE`` (else ``$XDG_CACHE_HOME/latentoc/jit`` or
``~/.cache/latentoc/jit``) by a hash of their C source, the compiler, the flags and CasADi's
version, and written atomically, so only the first build on a machine compiles. Without a
compiler (warning) or with ``LATENTOC_JIT=0`` the Functions stay in CasADi's virtual machine.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import casadi as ca

from ..errors import LatentocError
from ..progress import bar

__all__ = ["JIT_FLAGS", "cache_dir", "compiler", "enabled", "compile_sources", "threads", "node_map"]

JIT_FLAGS = ("-O1",)


def cache_dir() -> Path:
    """Directory of compiled libraries (module doc)."""
    if os.environ.get("LATENTOC_CACHE"):
        return Path(os.environ["LATENTOC_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "latentoc" / "jit"


def compiler() -> str | None:
    """The C compiler ($CC, else gcc, else cc), or None."""
    return shutil.which(os.environ.get("CC") or "gcc") or shutil.which("cc")


def enabled() -> bool:
    """False when ``LATENTOC_JIT=0``."""
    return os.environ.get("LATENTOC_JIT", "1") != "0"


def threads() -> int:
    """Threads for mapped compiled Functions: ``$LATENTOC_THREADS``, else the CPU count."""
    n = os.environ.get("LATENTOC_THREADS")
    if not n:
        return max(1, os.cpu_count() or 1)
    if not n.strip().isdigit() or int(n) < 1:
        raise LatentocError(f"LATENTOC_THREADS must be a positive integer, got {n!r}")
    return int(n)


def node_map(f: ca.Function, K: int) -> ca.Function:
    """``f`` mapped over K nodes, on :func:`threads` threads when f is compiled (in CasADi's
    virtual machine threads are slower)."""
    n = threads()
    if K > 1 and n > 1 and f.class_name() == "External":
        return f.map(K, "thread", min(n, K))
    return f.map(K)


def library_path(source: str, flags: tuple[str, ...] = JIT_FLAGS) -> Path:
    key = hashlib.sha256("\0".join([source, str(compiler()), *flags, ca.__version__]).encode()).hexdigest()[:24]
    return cache_dir() / f"lc_{key}.so"


def compile_sources(sources: list[tuple[str, str]], flags: tuple[str, ...] = JIT_FLAGS,
                    workers: int | None = None) -> list[Path | None]:
    """Compile C sources ``(label, source)`` to shared libraries, ``workers`` at a time, with a
    progress bar; a library already in the cache is not compiled again. None for a source that
    could not be compiled (no compiler, or it failed: warning)."""
    cc = compiler()
    if cc is None:
        warnings.warn("no C compiler found (set CC): evaluating the NLP Functions without JIT", stacklevel=3)
        return [None] * len(sources)
    paths = [library_path(src, flags) for _, src in sources]
    todo = [i for i, p in enumerate(paths) if not p.exists()]
    if not todo:
        return list(paths)
    cache = cache_dir()
    cache.mkdir(parents=True, exist_ok=True)

    def build(i: int) -> Path | None:
        lib = paths[i]
        try:
            with tempfile.TemporaryDirectory(dir=cache, prefix=".build-") as tmp:
                c_file, so_file = Path(tmp) / f"{lib.stem}.c", Path(tmp) / lib.name
                c_file.write_text(sources[i][1])
                subprocess.run([cc, *flags, "-shared", "-fPIC", "-o", str(so_file), str(c_file), "-lm"],
                               check=True, capture_output=True, text=True)
                os.replace(so_file, lib)  # atomic: readers see no library or a complete one
        except (OSError, subprocess.CalledProcessError) as exc:
            detail = getattr(exc, "stderr", "") or str(exc)
            warnings.warn(f"compiling {sources[i][0]} failed ({detail.strip()[:200]}): evaluating without JIT",
                          stacklevel=3)
            return None
        return lib

    with ThreadPoolExecutor(max_workers=workers or threads()) as pool, \
            bar(total=len(todo), desc=f"compiling {len(todo)} C libraries into {cache}", unit="lib") as b:
        for i, lib in zip(todo, pool.map(build, todo)):
            paths[i] = lib
            b.update(1)
    return paths
