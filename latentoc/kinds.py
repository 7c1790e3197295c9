"""The registry of problem kinds: one :class:`~latentoc.kind.Kind` each, imported, never loaded by name.

Adding a kind is one new package that defines its Kind (docs/kinds.md) and one line here.
"""
from __future__ import annotations

from .errors import ProblemError
from .jump.kind import BROAD_JUMP
from .kind import Kind
from .min_torque.kind import MIN_TORQUE

__all__ = ["KINDS", "kind_of"]

#: problem kind name (a problem file's ``kind``) -> the kind
KINDS: dict[str, Kind] = {kind.name: kind for kind in (MIN_TORQUE, BROAD_JUMP)}


def kind_of(name: str) -> Kind:
    """The kind called ``name``; a ProblemError naming the known ones otherwise."""
    if name not in KINDS:
        raise ProblemError(f"unknown problem kind {name!r}; known kinds: {', '.join(sorted(KINDS))}")
    return KINDS[name]
