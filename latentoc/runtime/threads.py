"""OpenBLAS's thread count, limited where latentoc's matrices are small.

The kernel matrices of GPDM learning and of the GP layer are a few hundred wide; on a small shared
machine multi-threaded BLAS was measured up to 10x slower than one thread, its workers waiting
for a busy core. Three places limit it, all through this module:

* :func:`blas_threads` around GPDM learning (:mod:`latentoc.gpdm.learning`, its settings'
  ``blas_threads``);
* :func:`one_blas_thread` on the GP layer's methods (:mod:`latentoc.latent.gp_layer`), called at
  every Ipopt iteration: the libraries are found once per process (:func:`known_openblas_handles`);
* :func:`openblas_threads_at_load` while a library that brings its own OpenBLAS is loaded
  (Ipopt's MUMPS, :func:`latentoc.nlp.ipopt.load_ipopt`): ``$OPENBLAS_NUM_THREADS`` set for the
  load unless the user set it.

Every limit is best effort: without an OpenBLAS in the process nothing changes.

:func:`mapped_threads` is the other thread count: the threads that evaluate the compiled blocks
mapped over the nodes (``$LATENTOC_THREADS``).
"""
from __future__ import annotations

import ctypes
import functools
import os
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, TypeVar

from latentoc.errors import LatentocError

__all__ = ["BlasHandle", "openblas_handles", "known_openblas_handles", "blas_threads", "one_blas_thread",
           "openblas_threads_at_load", "mapped_threads"]

_GET_NAMES = ("openblas_get_num_threads", "openblas_get_num_threads64_",
              "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_")
_SET_NAMES = ("openblas_set_num_threads", "openblas_set_num_threads64_",
              "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")

#: (get, set) thread-count functions of one loaded OpenBLAS
BlasHandle = tuple[Callable[[], int], Callable[[int], None]]
F = TypeVar("F", bound=Callable[..., Any])


def openblas_handles() -> list[BlasHandle]:
    """(get, set) thread-count functions of every OpenBLAS loaded in this process now."""
    handles: list[BlasHandle] = []
    try:
        with open("/proc/self/maps") as fh:
            paths = {line.split()[-1] for line in fh if "openblas" in line.lower() and "/" in line}
    except OSError:
        return handles
    for p in sorted(paths):
        try:
            lib = ctypes.CDLL(p)
        except OSError:
            continue
        get = next((getattr(lib, n) for n in _GET_NAMES if hasattr(lib, n)), None)
        set_ = next((getattr(lib, n) for n in _SET_NAMES if hasattr(lib, n)), None)
        if get is not None and set_ is not None:
            handles.append((get, set_))
    return handles


@functools.cache
def known_openblas_handles() -> list[BlasHandle]:
    """:func:`openblas_handles` at the first call, kept for the process (a hot path reads no file)."""
    return openblas_handles()


@contextmanager
def blas_threads(n: int | None, handles: Sequence[BlasHandle] | None = None) -> Iterator[None]:
    """OpenBLAS on ``n`` threads inside, the caller's counts given back after (also after an
    error). ``n`` None: left as it is; ``handles``: the libraries to limit (default: those
    loaded now)."""
    if n is None:
        yield
        return
    saved = []
    try:
        for get, set_ in openblas_handles() if handles is None else handles:
            old = int(get())
            if old != n:
                set_(int(n))
                saved.append((set_, old))
    except Exception:  # pragma: no cover - best effort: a library that does not answer is left alone
        pass
    try:
        yield
    finally:
        for set_, old in saved:
            set_(old)


def one_blas_thread(method: F) -> F:
    """``method`` run with OpenBLAS on one thread (the libraries known since the first call)."""
    @functools.wraps(method)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with blas_threads(1, known_openblas_handles()):
            return method(*args, **kwargs)

    return wrapper  # type: ignore[return-value]


@contextmanager
def openblas_threads_at_load(n: int = 1) -> Iterator[None]:
    """``$OPENBLAS_NUM_THREADS`` = ``n`` inside, unless the user set it: an OpenBLAS loaded inside
    starts with ``n`` threads (its spinning workers slowed the threaded node evaluations)."""
    unset = "OPENBLAS_NUM_THREADS" not in os.environ
    if unset:
        os.environ["OPENBLAS_NUM_THREADS"] = str(n)
    try:
        yield
    finally:
        if unset:
            del os.environ["OPENBLAS_NUM_THREADS"]


def mapped_threads() -> int:
    """Threads for the compiled blocks mapped over the nodes (:func:`latentoc.nlp.jit.node_map`):
    ``$LATENTOC_THREADS``, else the CPU count."""
    n = os.environ.get("LATENTOC_THREADS")
    if not n:
        return max(1, os.cpu_count() or 1)
    if not n.strip().isdigit() or int(n) < 1:
        raise LatentocError(f"LATENTOC_THREADS must be a positive integer, got {n!r}")
    return int(n)
