"""What a long step shows on the terminal: tqdm bars on stderr, silenced by ``--quiet``
(:func:`set_quiet`) or ``LATENTOC_QUIET=1``."""
from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import TypeVar

# tqdm.std, not tqdm.auto: in Jupyter auto picks the widget bar, which needs ipywidgets ("IProgress not
# found") and stores widget state in the notebook; the text bar works in a terminal and in Jupyter alike
from tqdm.std import tqdm

__all__ = ["bar", "quiet", "set_quiet", "status"]

T = TypeVar("T")
_QUIET = os.environ.get("LATENTOC_QUIET", "0") not in ("", "0")


def set_quiet(value: bool) -> None:
    """Silence (or restore) every progress display of this process."""
    global _QUIET
    _QUIET = bool(value)


def quiet() -> bool:
    return _QUIET


def bar(iterable: Iterable[T] | None = None, *, total: int | None = None, desc: str = "", unit: str = "it",
        leave: bool = False) -> tqdm:
    """A tqdm progress bar on stderr (disabled when quiet)."""
    return tqdm(iterable, total=total, desc=desc, unit=unit, leave=leave, disable=_QUIET, file=sys.stderr,
                dynamic_ncols=True)


@contextmanager
def status(desc: str) -> Iterator[None]:
    """A one-line 'desc ...' that becomes 'desc ... done (t s)' when the block ends."""
    with bar(total=1, desc=desc, unit="step", leave=False) as b:
        yield
        b.update(1)
