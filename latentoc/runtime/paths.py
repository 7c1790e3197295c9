"""Where latentoc's folders are: its data (``robots/``, ``problems/``, in a checkout or a wheel) and
its on-disk cache (compiled libraries, learned GPDMs)."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["data_dir", "cache_dir"]

_PACKAGE = Path(__file__).resolve().parents[1]  # latentoc/, above runtime/


def data_dir(name: str) -> Path:
    """The top-level folder ``name`` of the source tree, or its copy installed in the wheel."""
    for candidate in (_PACKAGE.parent / name, _PACKAGE / "_data" / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"latentoc data folder {name!r} not found next to {_PACKAGE}")


def cache_dir() -> Path:
    """The cache folder: ``$LATENTOC_CACHE``, else ``$XDG_CACHE_HOME/latentoc/jit`` or
    ``~/.cache/latentoc/jit`` (compiled libraries; learned GPDMs in its ``gpdm/``)."""
    if os.environ.get("LATENTOC_CACHE"):
        return Path(os.environ["LATENTOC_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "latentoc" / "jit"
