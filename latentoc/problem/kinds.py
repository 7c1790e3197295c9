"""What a problem kind provides (:class:`Kind`) and what its solve returns (:class:`Solution`).

A kind is one object, registered once in :data:`KINDS` (docs/kinds.md)::

    Kind(schema=SCHEMA,                  # its problem files' keys, defaults, docs and checks
         tube_reference=tube_reference,  # what a relative tube "<k>x" multiplies (tube_training)
         solve=solve_my_kind,            # problem -> Solution (the signature of :class:`Solver`)
         methods=("latent",))            # the solve methods it offers

The solve reads every setting from the :class:`~latentoc.problem.declaration.Problem` (already checked
against the schema), raises :class:`~latentoc.errors.SolveError` for what only solving can find
wrong (an infeasible tube, an unknown method) BEFORE any work is written, and returns a
:class:`Solution`: a JSON-ready ``result`` dict (at least problem, kind, method, status, success,
iterations, cost_initial, cost, performance_gain_pct, cost_meaning, solve_time_s and violations;
for a latent solve the tube's tube_spec, tube, tube_relative, tube_training, max_sigma2,
:mod:`latentoc.latent.tube`), the ``trajectory`` arrays (keys from
:data:`latentoc.results.TRAJECTORY_KEYS`), the GPDM it used and what a neighbouring tube may
start from (``warm``, with its ``tube``). The result's keys beyond the core ones are the kind's
result details (:attr:`latentoc.results.Result.details`). :meth:`latentoc.results.Result.from_solution`
turns a Solution into the versioned result schema; the public ``latentoc.solve`` returns that.

:data:`KINDS` is the registry: kind name -> its Kind, its package imported when a problem of its
kind is first loaded (an arm solve never imports the jump's). Adding a kind is one new package that
defines its Kind (docs/kinds.md) and one line there.
"""
from __future__ import annotations

import importlib
from collections.abc import Iterator, MutableMapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from latentoc.errors import ProblemError, SolveError

if TYPE_CHECKING:  # annotations only: loading a problem file imports neither numpy nor the GPDM
    from latentoc.gpdm import GPDM
    from latentoc.problem.declaration import Problem
    from latentoc.problem.schema import Schema

__all__ = ["Kind", "Solution", "Solver", "TubeReference", "joint_range", "KINDS", "kind_of"]


@dataclass
class Solution:
    """What a kind's solve returns: ``result`` (JSON-ready dict), ``trajectory`` (numpy arrays),
    the ``gpdm`` it solved in, and ``warm``, what a neighbouring solve of the same problem may
    start from (a kind's own data, with the ``tube`` it was solved at)."""

    result: dict[str, Any]
    trajectory: dict[str, Any] = field(default_factory=dict)
    warm: dict[str, Any] | None = None
    gpdm: GPDM | None = None

    @property
    def success(self) -> bool:
        return bool(self.result.get("success", False))


class Solver(Protocol):
    """A kind's solve: ``warm_start`` is the Solution of the same problem at a smaller tube (each
    kind takes what it needs from its ``warm``), ``gpdm`` a learned GPDM to use instead of the
    problem's, ``verbose`` Ipopt's own log."""

    def __call__(self, problem: Problem, *, method: str, joint_range_deg: float | None, gpdm: GPDM | None,
                 verbose: bool, warm_start: Solution | None) -> Solution: ...


class TubeReference(Protocol):
    """What a relative tube ``"<k>x"`` of ``problem`` multiplies: tube_training of its GPDM (Eq. 30),
    learned if needed."""

    def __call__(self, problem: Problem) -> float: ...


@dataclass(frozen=True)
class Kind:
    """One problem kind (module doc)."""

    schema: Schema
    tube_reference: TubeReference
    solve: Solver
    methods: tuple[str, ...] = ("latent",)

    @property
    def name(self) -> str:
        """The kind's name, its problem files' ``kind``."""
        return self.schema.kind


def joint_range(problem: Problem, joint_range_deg: float | None = None) -> float:
    """The full configuration-space baseline's joint range in degrees (method ``"joint-range"``):
    ``joint_range_deg`` (``--joint-range``), else the problem's ``baseline.joint_range_deg``; a
    SolveError naming it unless a positive finite number."""
    import numpy as np

    value = problem.joint_range_deg if joint_range_deg is None else joint_range_deg
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not np.isfinite(value) or value <= 0:
        raise SolveError(f"joint range (--joint-range, baseline.joint_range_deg) must be a positive number of "
                         f"degrees, got {value!r}")
    return float(value)


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
