"""The ``"broad-jump"`` problem kind (:class:`~latentoc.problem.kinds.Kind`): the humanoid's standing broad jump.

Its schema, tube reference and solve are :mod:`.problem`'s; its NLP builder stays
:func:`.transcription.nlp.build_nlp`.
"""
from __future__ import annotations

from latentoc.problem.kinds import Kind
from latentoc.jump.schedule.path import METHODS
from latentoc.jump.problem import SCHEMA, solve_jump_problem, tube_reference

__all__ = ["BROAD_JUMP"]

#: the broad jump (Sect. 4.2): methods "latent" and "joint-range" (the full configuration space)
BROAD_JUMP = Kind(schema=SCHEMA, tube_reference=tube_reference, solve=solve_jump_problem, methods=METHODS)
