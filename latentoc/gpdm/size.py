"""What learning a GPDM on N frames needs, checked before anything is computed: a recording too long
for this machine's memory is refused with the numbers and the fix, never a MemoryError halfway.

Learning keeps N x N kernel matrices (K_Y, K_X, their inverses and derivatives) and the dense
(N d + 6)^2 Hessian with its eigenvectors (:mod:`latentoc.gpdm.newton`); docs/gpdm.md has the
measured peak memory against N that :func:`learning_memory` follows.
"""
from __future__ import annotations

import math
import os

from latentoc.errors import LatentocError

__all__ = ["GPDMSizeError", "available_memory", "check_size", "learning_memory"]

#: peak bytes per N^2 kernel entry and per Hessian entry, and the fixed part: 15-20 % above the peaks
#: measured for N = 350, 1000, 2000 (docs/gpdm.md)
_PER_KERNEL_ENTRY = 8 * 52
_PER_HESSIAN_ENTRY = 8 * 4
_FIXED = 200 * 2 ** 20


class GPDMSizeError(LatentocError, ValueError):
    """Training data too long for the memory learning would need (the numbers and the fix in the message)."""


def learning_memory(N: int, D: int, d: int) -> int:
    """Peak memory (bytes) of :func:`~latentoc.gpdm.learning.learn_gpdm` on N frames of D dimensions."""
    n = N * d + 6
    return int(_FIXED + _PER_KERNEL_ENTRY * N * N + _PER_HESSIAN_ENTRY * n * n + 8 * 8 * N * D)


def available_memory() -> int | None:
    """Memory this process can still use (bytes): MemAvailable of /proc/meminfo, else the free pages."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_AVPHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def check_size(N: int, D: int, d: int, available: int | None = None) -> None:
    """Raise :class:`GPDMSizeError` if learning on N frames needs more memory than is ``available``
    (default: :func:`available_memory`; unknown: no check)."""
    available = available_memory() if available is None else available
    need = learning_memory(N, D, d)
    if available is None or need <= available:
        return
    fit = max(d + 2, int(math.isqrt(max((available - _FIXED) // (_PER_KERNEL_ENTRY + _PER_HESSIAN_ENTRY * d * d), 1))))
    stride = math.ceil(N / fit)
    gib = 2.0 ** 30
    raise GPDMSizeError(
        f"learning a GPDM on {N} frames (D = {D}, d = {d}) needs about {need / gib:.1f} GiB of memory and "
        f"{available / gib:.1f} GiB are available: about {fit} frames fit. Learn on fewer frames: every "
        f"{stride}th with --stride {stride} (training_stride in a problem file), a lower rate with --rate, or a "
        f"segment with --start/--stop")
