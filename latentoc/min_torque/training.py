"""What a minimum-torque problem learns from: its training frames and its GPDM (learned once per settings).

The GPDM learns every ``gpdm.training_stride``-th frame of the problem's demonstration
(:func:`latentoc.motions.problem_inputs.problem_demonstration`), the last one always kept (the
goal pose), with the problem's latent dimension and ``[gpdm]`` table. A relative tube multiplies
its tube_training (:func:`tube_reference`, Eq. 30).
"""
from __future__ import annotations

import time

import numpy as np

from latentoc.gpdm import GPDM, GPDMSettings, cached_gpdm
from latentoc.gpdm.cache import model_path
from latentoc.motions import Demonstration
from latentoc.motions.problem_inputs import problem_demonstration
from latentoc.problem.declaration import Problem

__all__ = ["training_frames", "gpdm_settings", "problem_gpdm", "tube_reference"]


def training_frames(problem: Problem, demo: Demonstration | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The frames (t, Q) of the problem's training motion the GPDM learns: every
    ``gpdm.training_stride``-th, and the last."""
    demo = problem_demonstration(problem) if demo is None else demo
    t, Q = demo.t, demo.Q
    idx = np.arange(0, len(t), problem.gpdm["training_stride"])
    if idx[-1] != len(t) - 1:
        idx = np.append(idx, len(t) - 1)  # keep the goal pose
    return np.asarray(t)[idx], np.asarray(Q)[idx]


def gpdm_settings(problem: Problem) -> GPDMSettings:
    """GPDMSettings from the problem's latent dimension and [gpdm] table."""
    kw = {k: v for k, v in problem.gpdm.items() if k != "training_stride"}
    return GPDMSettings(latent_dim=int(problem.latent_dim), **kw)


_GPDM_CACHE: dict[str, tuple[GPDM, float]] = {}  # learned once per process and settings


def problem_gpdm(problem: Problem) -> tuple[GPDM, float]:
    """The problem's GPDM and its learning time (s); learned once per training data + settings."""
    settings = gpdm_settings(problem)
    _, Q = training_frames(problem)
    key = model_path(Q, settings).name  # the disk cache's key: data and settings
    if key not in _GPDM_CACHE:
        t0 = time.perf_counter()
        model = cached_gpdm(Q, settings)
        _GPDM_CACHE[key] = (model, time.perf_counter() - t0)
    return _GPDM_CACHE[key]


def tube_reference(problem: Problem) -> float:
    """What a relative tube multiplies: tube_training of the problem's GPDM (Eq. 30)."""
    return problem_gpdm(problem)[0].tube_size()
