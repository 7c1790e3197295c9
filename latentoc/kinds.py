"""The registry of problem kinds: one :class:`~latentoc.kind.Kind` each, its package imported when a
problem of its kind is first loaded (an arm solve never imports the jump's).

Adding a kind is one new package that defines its Kind (docs/kinds.md) and one line here.
"""
from __future__ import annotations

import importlib
from collections.abc import Iterator, MutableMapping
from typing import TYPE_CHECKING

from latentoc.errors import ProblemError

if TYPE_CHECKING:
    from latentoc.kind import Kind

__all__ = ["KINDS", "kind_of"]


class _Kinds(MutableMapping[str, "Kind"]):
    """Kind name -> Kind, from ``"module:attribute"`` names imported at the first look-up."""

    def __init__(self, where: dict[str, str]) -> None:
        self._where = dict(where)
        self._kinds: dict[str, Kind] = {}

    def __getitem__(self, name: str) -> Kind:
        if name not in self._kinds:
            module, attribute = self._where[name].split(":")
            self._kinds[name] = getattr(importlib.import_module(module), attribute)
        return self._kinds[name]

    def __setitem__(self, name: str, kind: Kind) -> None:
        self._where.setdefault(name, "")
        self._kinds[name] = kind

    def __delitem__(self, name: str) -> None:
        del self._where[name]
        self._kinds.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)


#: problem kind name (a problem file's ``kind``) -> the kind
KINDS: MutableMapping[str, "Kind"] = _Kinds({"latent-min-torque": "latentoc.min_torque.kind:MIN_TORQUE",
                                           "broad-jump": "latentoc.jump.kind:BROAD_JUMP"})


def kind_of(name: str) -> Kind:
    """The kind called ``name``; a ProblemError naming the known ones otherwise."""
    if name not in KINDS:
        raise ProblemError(f"unknown problem kind {name!r}; known kinds: {', '.join(sorted(KINDS))}")
    return KINDS[name]
