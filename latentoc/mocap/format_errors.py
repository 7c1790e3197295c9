"""Errors raised by the Acclaim ASF/AMC readers."""
from __future__ import annotations

import math
from pathlib import Path

from latentoc.errors import LatentocError


class MocapFormatError(LatentocError, ValueError):
    """A malformed ASF or AMC file.

    Carries the offending ``path`` and 1-based ``line`` number (``None`` when the
    problem is not tied to a single line); the message names both.
    """

    def __init__(self, path: str | Path | None, line: int | None, message: str) -> None:
        self.path = None if path is None else str(path)
        self.line = line
        self.reason = message
        where = self.path if self.path is not None else "<text>"
        if line is not None:
            where = f"{where}, line {line}"
        super().__init__(f"{where}: {message}")


def parse_number(tok: str, path: str | None, line: int) -> float:
    """A finite float from token ``tok``, or a MocapFormatError naming the file and line."""
    try:
        v = float(tok)
    except ValueError:
        raise MocapFormatError(path, line, f"not a number: {tok!r}") from None
    if not math.isfinite(v):
        raise MocapFormatError(path, line, f"non-finite number: {tok!r}")
    return v
