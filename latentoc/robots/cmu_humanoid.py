"""The symmetrised CMU humanoid: the model a contact problem's ``[robot] model = "cmu-humanoid"``
names (Kang & Park 2015, Sect. 4.2, Table 5).

It is built from :func:`~latentoc.mocap.symmetry.symmetrized_skeleton` of the CMU subject 01
skeleton (63.86 kg, 1.75 m, de Leva masses) so that mirrored joint motions are exactly symmetric;
its :class:`~latentoc.mocap.symmetry.SymmetryMap` gives the 37 learned (left + centre)
coordinates. The skeleton as captured, without the symmetry, is
:func:`.human_models.build_cmu_humanoid`.
"""
from __future__ import annotations

from functools import lru_cache

import pinocchio as pin

from latentoc.mocap.anthropometry import cmu_inertias
from latentoc.mocap.skeleton_model import build_model
from latentoc.mocap.symmetry import SymmetryMap, symmetrized_skeleton
from latentoc.robots.human_models import cmu_skeleton

__all__ = ["symmetric_model"]


@lru_cache(maxsize=2)
def symmetric_model(mass: float = 63.86, height: float = 1.75) -> tuple[pin.Model, SymmetryMap]:
    """The symmetrised CMU humanoid (nq 63, nv 62) and its symmetry map."""
    sk = symmetrized_skeleton(cmu_skeleton())
    root, inert = cmu_inertias(sk, mass, height)
    model = build_model(sk, inertias=inert, root_inertia=root, name="cmu_humanoid_sym")
    return model, SymmetryMap(model, sk)
