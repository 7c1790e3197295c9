"""The ``"broad-jump"`` problem kind (:class:`~latentoc.kind.Kind`): the humanoid's standing broad jump.

Its schema, tube reference and solve are :mod:`.problem`'s; its NLP builder stays
:func:`.nlp.build_nlp`. The ``[options]`` that set :class:`~.settings.JumpSettings` fields get
their one-line meaning here (:data:`OPTION_DOCS`, shown by ``latentoc show``) until the settings
declare it beside each field.
"""
from __future__ import annotations

from dataclasses import replace

from ..kind import Kind
from ..schema import Schema, Setting, Table
from .problem import SCHEMA, solve_jump_problem, tube_reference

__all__ = ["BROAD_JUMP", "OPTION_DOCS"]

#: [options] key (a JumpSettings field; ``friction`` is ``mu``) -> what it sets
OPTION_DOCS: dict[str, str] = {
    "friction": "friction coefficient mu of the foot points (Table 5)",
    "n_stance": "contact nodes of the stance, every 10 ms",
    "n_flight": "flight nodes, every 5 ms",
    "n_land": "contact nodes of the landing, touchdown to the end",
    "n_base_stance": "control points of the stance's (x, z, pitch) base spline",
    "n_base_land": "control points of the landing's (x, z, pitch) base spline",
    "foot_tolerance": "m the toe tip may move from its ground point in contact",
    "ball_tolerance": "m an unloaded ball may sink below the ground (soft sole)",
    "contact_tolerance": "m a loaded heel or ball stays within this of the ground",
    "flight_substeps": "trapezoid steps of the pitch rate per flight node interval",
    "tube_spacing": "s between the tube's points",
    "sample_spacing": "s between the contact and flight samples of phase 2 (0: none)",
    "exchange": "rows grow where the 1 kHz grid is violated (the exchange)",
    "exchange_rounds": "solves of the exchange at the most",
    "torque_limits": "the torque limits of Eq. 34",
    "polygon": "ZMP and COM in the support polygon in the landing (Eq. 35-36)",
    "two_phase": "phase 1, the feasible point nearest the training fit, before phase 2, the distance",
}


def _described(schema: Schema) -> Schema:
    """``schema`` with the [options] settings that name only their JumpSettings field described
    by :data:`OPTION_DOCS`."""
    def described(s: Setting) -> Setting:
        return replace(s, doc=OPTION_DOCS.get(s.key, s.doc)) if s.doc.startswith("JumpSettings.") else s

    return replace(schema, settings=tuple(
        replace(s, settings=tuple(described(o) for o in s.settings)) if isinstance(s, Table) else s
        for s in schema.settings))


#: the broad jump (Sect. 4.2): method "latent" only
BROAD_JUMP = Kind(schema=_described(SCHEMA), tube_reference=tube_reference, solve=solve_jump_problem)
