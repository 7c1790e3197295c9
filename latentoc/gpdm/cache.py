"""Learned GPDMs kept on disk: learning converges (:mod:`latentoc.gpdm.newton`), so the same data and
settings give the same model, and a problem learns its model once per machine, not per process.

Files: ``gpdm_<key>.npz`` in ``<cache_dir>/gpdm`` (:func:`latentoc.nlp.jit.cache_dir`), the key a
hash of the learner's version, the training sequences and the settings. The package ships the
models of its slow-to-learn problems (the broad jump's, about 2 min) under the same names in
``latentoc/models/``; tests/test_gpdm_cache.py checks each is a converged minimum of its data.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..nlp.jit import cache_dir
from .learning import GPDMSettings, learn_gpdm
from .model import GPDM

__all__ = ["LEARNER_VERSION", "SHIPPED", "learned_gpdm", "model_path"]

#: models shipped with the package (module doc)
SHIPPED = Path(__file__).resolve().parent.parent / "models"

#: bump when learning changes what it returns for the same data and settings
LEARNER_VERSION = 1


def model_path(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings) -> Path:
    """Where the model of these sequences and settings is kept."""
    h = hashlib.sha256(f"latentoc-gpdm-{LEARNER_VERSION}\0{settings.to_json()}".encode())
    for seq in ([Y] if isinstance(Y, np.ndarray) else list(Y)):
        a = np.ascontiguousarray(seq, dtype=float)
        h.update(repr(a.shape).encode())
        h.update(a.tobytes())
    return cache_dir() / "gpdm" / f"gpdm_{h.hexdigest()[:24]}.npz"


def learned_gpdm(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings) -> GPDM:
    """:func:`learn_gpdm` of ``Y``, read from the cache when it was learned before on this machine."""
    path = model_path(Y, settings)
    for known in (path, SHIPPED / path.name):
        if known.exists():
            try:
                return GPDM.load(known)
            except (OSError, ValueError, KeyError):  # a damaged file: learned again and replaced
                pass
    model = learn_gpdm(Y, settings)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, suffix=".npz", delete=False) as tmp:
            model.save(tmp.name)
        os.replace(tmp.name, path)
    except OSError:  # a read-only cache: the model is still returned
        pass
    return model
