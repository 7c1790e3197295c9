"""What a long step shows: tqdm bars on stderr where someone watches (a terminal, a Jupyter kernel),
a line when a step starts and one when it ends where stderr is a log or a pipe (``LATENTOC_PROGRESS
= bars | lines`` chooses); silenced by ``--quiet`` (:func:`set_quiet`) or ``LATENTOC_QUIET=1``."""
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


class _Lines(tqdm):
    """A tqdm bar for a log: no redraws, a line when it starts and one when it ends."""

    def __init__(self, *args, **kwargs) -> None:  # type: ignore[no-untyped-def]
        super().__init__(*args, **kwargs)
        if not self.disable:
            self._line("...")

    def display(self, msg: str | None = None, pos: int | None = None) -> None:  # type: ignore[override]
        return None

    def close(self) -> None:
        if not getattr(self, "disable", True):  # a Ctrl-C inside tqdm's __init__ leaves it unset
            post = f", {self.postfix}" if self.postfix else ""
            self._line(f"done, {self.n} {self.unit} in {self._time() - self.start_t:.1f} s{post}")
        super().close()

    def _line(self, text: str) -> None:
        self.fp.write(f"{self.desc}: {text}\n")
        self.fp.flush()


def _watched() -> bool:
    """Whether stderr is watched live (bars) rather than kept (lines): module doc."""
    mode = os.environ.get("LATENTOC_PROGRESS", "")
    if mode in ("bars", "lines"):
        return mode == "bars"
    if "ipykernel" in sys.modules:
        return True
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def bar(iterable: Iterable[T] | None = None, *, total: int | None = None, desc: str = "", unit: str = "it",
        leave: bool = False) -> tqdm:
    """A tqdm progress bar on stderr, or its start and end lines in a log (disabled when quiet)."""
    if _watched():
        return tqdm(iterable, total=total, desc=desc, unit=unit, leave=leave, disable=_QUIET, file=sys.stderr,
                    dynamic_ncols=True)
    return _Lines(iterable, total=total, desc=desc, unit=unit, leave=False, disable=_QUIET, file=sys.stderr)


@contextmanager
def status(desc: str) -> Iterator[None]:
    """A one-line 'desc ...' that becomes 'desc ... done (t s)' when the block ends."""
    with bar(total=1, desc=desc, unit="step", leave=False) as b:
        yield
        b.update(1)
