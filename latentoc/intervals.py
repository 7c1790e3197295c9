"""Runs of a boolean mask over samples: the stretches where a condition holds."""
from __future__ import annotations

import numpy as np

__all__ = ["runs"]


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """The (start, stop) index pairs, stop exclusive, of each run of True in ``mask``, in order."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], np.asarray(mask, np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2])]
