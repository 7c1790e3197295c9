"""OpenBLAS's thread count, limited while learning: the kernel matrices are a few hundred wide, and on a
small shared machine multi-threaded BLAS was measured up to 10x slower than one thread."""
from __future__ import annotations

import ctypes
from contextlib import contextmanager
from typing import Iterator

__all__ = ["blas_threads", "openblas_handles"]

_GET_NAMES = ("openblas_get_num_threads", "openblas_get_num_threads64_",
              "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_")
_SET_NAMES = ("openblas_set_num_threads", "openblas_set_num_threads64_",
              "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")


def openblas_handles() -> list[tuple]:
    """(get, set) thread-count functions of every OpenBLAS loaded in this process."""
    handles: list[tuple] = []
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


@contextmanager
def blas_threads(n: int | None) -> Iterator[None]:
    """Temporarily limit OpenBLAS threads (best effort; no-op if not found).

    The kernel matrices are only a few hundred wide; on a small shared machine
    multi-threaded BLAS was measured up to 10x slower than one thread.
    """
    if n is None:
        yield
        return
    handles = []
    try:
        for get, set_ in openblas_handles():
            old = int(get())
            set_(int(n))
            handles.append((set_, old))
    except Exception:  # pragma: no cover - defensive
        pass
    try:
        yield
    finally:
        for set_, old in handles:
            set_(old)
