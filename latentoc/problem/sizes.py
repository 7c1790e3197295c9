"""Upper bounds on a problem's sizes, from the memory they would take: a size with no bound of its
own (``control_points = 100000000``, a duration of years) is refused when the problem is loaded,
with the keys and the memory, instead of a MemoryError deep inside a solve.

:func:`spline_transcription_bytes` is a lower bound of what a spline transcription allocates
(the basis matrices at the quadrature and constraint nodes, the 1 kHz export grid); a problem
is refused when that alone exceeds the machine's physical memory.
"""
from __future__ import annotations

import os

from latentoc.errors import ProblemError

__all__ = ["physical_memory", "spline_transcription_bytes", "check_memory"]

EXPORT_RATE_HZ = 1000.0
_FLOAT = 8  # bytes


def physical_memory() -> float:
    """This machine's physical memory, bytes (inf where the system does not say)."""
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):
        return float("inf")


def spline_transcription_bytes(control_points: int, spline_degree: int, quadrature_points: int,
                               constraint_points: int, duration: float | None, latent_dim: int) -> float:
    """A lower bound, bytes, of the arrays a B-spline transcription of these sizes allocates: an
    m x m identity for the basis, the basis values (3 orders) at every node and 1 kHz sample, and
    the latent path and the joint motion (q, v, a, tau: at least d + 4 columns) on the 1 kHz grid."""
    m = float(control_points)
    nodes = max(m - spline_degree, 1.0) * (quadrature_points + constraint_points)
    samples = (duration or 0.0) * EXPORT_RATE_HZ + 1.0
    return _FLOAT * (m * m + 3.0 * m * (nodes + samples) + samples * (latent_dim + 4))


def check_memory(needed: float, keys: dict[str, object], where: str) -> None:
    """A ProblemError naming ``where`` and the ``keys`` (key -> value) when ``needed`` bytes exceed
    the physical memory."""
    have = physical_memory()
    if needed > have:
        settings = ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}" for k, v in keys.items())
        raise ProblemError(f"{where}: {settings} would need at least {needed / 1e9:.3g} GB of memory; this machine "
                           f"has {have / 1e9:.3g} GB. Use fewer control points, nodes or a shorter duration")
