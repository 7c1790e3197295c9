"""Learned GPDMs kept on disk: learning converges (:mod:`latentoc.gpdm.newton`), so the same data and
settings give the same model, and a problem learns its model once per machine, not per process.

Files: ``gpdm_<key>.npz`` in ``<cache_dir>/gpdm`` (:func:`latentoc.runtime.paths.cache_dir`), the key a
hash of the learner's version, the training sequences and the settings. The package ships the
models of its larger problems (the broad jump's: 5 s to learn) under the same names in
``latentoc/models/``; tests/test_gpdm_cache.py checks each is a converged minimum of its data.

A cached model is written under a temporary name and renamed, with its SHA-256 in
``gpdm_<key>.npz.sha256`` beside it; before it is loaded the checksum is verified and the model
must be the one its name stands for (its data and settings hash to the name). A damaged,
truncated, empty or foreign file, or one without its checksum, is learned again and replaced, with
a one-line warning.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from latentoc.runtime.files import NPZ_ERRORS, atomic_write, sha256
from latentoc.runtime.paths import cache_dir
from latentoc.gpdm.learning import learn_gpdm
from latentoc.gpdm.model import GPDM
from latentoc.gpdm.learning_settings import GPDMSettings

__all__ = ["LEARNER_VERSION", "SHIPPED", "cached_gpdm", "model_path"]

#: models shipped with the package (module doc)
SHIPPED = Path(__file__).resolve().parent.parent / "models"

#: bump when learning changes what it returns for the same data and settings
LEARNER_VERSION = 3


def model_path(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings) -> Path:
    """Where the model of these sequences and settings is kept."""
    h = hashlib.sha256(f"latentoc-gpdm-{LEARNER_VERSION}\0{settings.to_json()}".encode())
    for seq in ([Y] if isinstance(Y, np.ndarray) else list(Y)):
        a = np.ascontiguousarray(seq, dtype=float)
        h.update(repr(a.shape).encode())
        h.update(a.tobytes())
    return cache_dir() / "gpdm" / f"gpdm_{h.hexdigest()[:24]}.npz"


def _sequences(model: GPDM) -> np.ndarray | list[np.ndarray]:
    starts = np.cumsum([0] + list(model.sequence_lengths))
    seqs = [model.Y[a:b] for a, b in zip(starts[:-1], starts[1:])]
    return seqs[0] if len(seqs) == 1 else seqs


def _checksum_path(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def _read(path: Path, checked: bool) -> GPDM:
    """The model in ``path``, verified: its checksum (``checked``: the cache's), then that it is the
    model of the data and settings its name stands for. A ValueError says what is wrong."""
    data = path.read_bytes()
    if checked:
        try:
            recorded = _checksum_path(path).read_text().strip()
        except (OSError, UnicodeDecodeError):
            recorded = None
        if recorded is None:  # never adopted: its content cannot be told from a tampered one
            raise ValueError(f"no checksum is recorded beside it ({_checksum_path(path).name})")
        if recorded != sha256(data):
            raise ValueError("its checksum differs from the one recorded beside it")
    try:
        model = GPDM.load(path)
        name = model_path(_sequences(model), model.settings).name
    except NPZ_ERRORS as exc:
        raise ValueError(f"not a readable model ({type(exc).__name__}: {exc})") from None
    if name != path.name:
        raise ValueError("it is the model of other data or settings")
    return model


def _warn(message: str) -> None:
    print(f"latentoc: warning: {message}", file=sys.stderr)


def _store(model: GPDM, path: Path) -> None:
    """Write ``model`` to ``path`` and its checksum beside it, each under a temporary name first."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=".npz")
    os.close(fd)
    tmp = Path(name)
    try:
        model.save(tmp)
        digest = sha256(tmp.read_bytes())
        atomic_write(_checksum_path(path), lambda f: f.write(digest + "\n"))
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def cached_gpdm(Y: np.ndarray | Sequence[np.ndarray], settings: GPDMSettings) -> GPDM:
    """:func:`learn_gpdm` of ``Y``, read from the cache (or the shipped models) when it was learned
    before; a cached file that fails its checks is learned again with a warning (module doc)."""
    path = model_path(Y, settings)
    for known, checked in ((path, True), (SHIPPED / path.name, False)):
        if not known.exists():
            continue
        try:
            model = _read(known, checked)
        except (OSError, ValueError) as exc:
            _warn(f"the cached GPDM {known} is damaged or foreign ({exc}); learning it again")
            continue
        return model
    model = learn_gpdm(Y, settings)
    try:
        _store(model, path)
    except OSError:  # a read-only cache: the model is still returned
        pass
    return model
