"""The ``"latent-min-torque"`` problem kind (:class:`~latentoc.problem.kinds.Kind`): any fixed-base robot's
minimum-torque motion (Sect. 4.1), in the latent space or, as the baseline, in joint space."""
from __future__ import annotations

from latentoc.problem.kinds import Kind
from latentoc.min_torque.problem import SCHEMA
from latentoc.min_torque.solve import METHODS, solve_latent_min_torque
from latentoc.min_torque.training import tube_reference

__all__ = ["MIN_TORQUE"]

#: the minimum-torque kind: methods "latent" and "joint-range"
MIN_TORQUE = Kind(schema=SCHEMA, tube_reference=tube_reference, solve=solve_latent_min_torque, methods=METHODS)
