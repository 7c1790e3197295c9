"""Where latentoc's data folders (``robots/``, ``problems/``) are, in a checkout or a wheel."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def data_dir(name: str) -> Path:
    """The top-level folder ``name`` of the source tree, or its copy installed in the wheel."""
    for candidate in (_PACKAGE.parent / name, _PACKAGE / "_data" / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"latentoc data folder {name!r} not found next to {_PACKAGE}")
