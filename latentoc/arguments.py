"""The public functions' argument checks: a value of the wrong type is an
:class:`~latentoc.errors.ArgumentError` naming the function, the argument, what it must be and what
it got, before any work (not an AttributeError from deep inside)."""
from __future__ import annotations

from typing import Any

from latentoc.errors import ArgumentError

__all__ = ["expect"]


def _got(value: Any) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text if len(text) <= 60 else text[:60] + '...'}"


def expect(function: str, name: str, value: Any, types: type | tuple[type, ...], what: str) -> None:
    """An ArgumentError unless ``value`` is an instance of ``types`` (bools are not numbers)."""
    allowed = types if isinstance(types, tuple) else (types,)
    if isinstance(value, allowed) and (bool in allowed or not isinstance(value, bool)):
        return
    raise ArgumentError(f"{function}(): argument {name!r} must be {what}, got {_got(value)}")
