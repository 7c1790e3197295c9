"""The settings of GPDM learning (:class:`GPDMSettings`, recorded in every learned model) and the
error of bad training data or settings (:class:`GPDMInputError`)."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from latentoc.errors import LatentocError
from latentoc.gpdm.objective import HYPER_NAMES, KAPPA_SQ

__all__ = ["GPDMSettings", "GPDMInputError", "DEFAULT_FIXED", "DEFAULT_GAMMA", "check_settings"]


class GPDMInputError(LatentocError, ValueError):
    """Invalid training data or settings for GPDM learning."""


#: hyperparameters held fixed: beta_1 (the scale of W, module docstring)
DEFAULT_FIXED: dict[str, float] = {"beta1": 1.0}
#: Gamma(shape, rate) priors of the learned hyperparameters (module docstring)
DEFAULT_GAMMA: dict[str, tuple[float, float]] = {
    "alpha1": (2.0, 1.0), "alpha2": (2.0, 1.0), "alpha3": (2.0, 1.0), "alpha4": (2.0, 0.01),
    "beta2": (2.0, 1.0), "beta3": (2.0, 1.0)}


@dataclass
class GPDMSettings:
    """Settings of :func:`~latentoc.gpdm.learning.learn_gpdm` (all recorded in the learned model)."""

    latent_dim: int = 3
    balanced: bool = True  # lambda = D/d on the dynamics term (Urtasun et al. 2006)
    # hyperparameters held at these values (HYPER_NAMES), not learned
    fixed: dict[str, float] = field(default_factory=lambda: dict(DEFAULT_FIXED))
    # Gamma(shape, rate) priors replacing Eq. 16's 1/theta prior of these hyperparameters
    gamma: dict[str, tuple[float, float]] = field(default_factory=lambda: dict(DEFAULT_GAMMA))
    ftol: float = 1e-10  # convergence: the Newton decrement <= ftol |L| (:mod:`latentoc.gpdm.newton`)
    max_iterations: int = 500  # Newton iterations (fresh Hessians) at most: a safety cap, then not converged
    seed: int = 0  # only used by init="random"
    init: str = "pca"  # "pca" or "random"
    kappa_sq: float = KAPPA_SQ
    alpha0: tuple[float, ...] = (0.9, 1.0, 0.1, float(np.e))
    beta0: tuple[float, ...] = (1.0, 1.0, float(np.e))
    log_hyper_bound: float = 40.0  # |ln alpha_i|, |ln beta_i| <= this (a hyperparameter on it: not converged)
    blas_threads: int | None = 1  # BLAS threads during learning (None: leave as is)

    def to_json(self) -> str:
        """Settings as a JSON string."""
        return json.dumps(asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "GPDMSettings":
        """Inverse of :meth:`to_json`."""
        data = json.loads(text)
        for key in ("alpha0", "beta0"):
            if key in data:
                data[key] = tuple(data[key])
        if "gamma" in data:
            data["gamma"] = {k: tuple(v) for k, v in data["gamma"].items()}
        known = {f.name for f in fields(cls)}  # a model saved by an older version: its other keys dropped
        return cls(**{k: v for k, v in data.items() if k in known})


def check_settings(settings: GPDMSettings) -> None:
    """A GPDMInputError naming the first setting learning cannot use."""
    if not isinstance(settings.latent_dim, (int, np.integer)) or settings.latent_dim < 1:
        raise GPDMInputError(f"settings.latent_dim must be a positive integer, got {settings.latent_dim!r}")
    if settings.max_iterations < 1 or not settings.ftol > 0:
        raise GPDMInputError(f"settings.max_iterations must be >= 1 and settings.ftol > 0, got "
                             f"{settings.max_iterations!r} and {settings.ftol!r}")
    if settings.init not in ("pca", "random"):
        raise GPDMInputError(f"settings.init must be 'pca' or 'random', got {settings.init!r}")
    if len(settings.alpha0) != 4 or len(settings.beta0) != 3 or min(settings.alpha0) <= 0 \
            or min(settings.beta0) <= 0:
        raise GPDMInputError("settings.alpha0 must be 4 positive numbers and settings.beta0 3 positive numbers")
    for name, value in settings.fixed.items():
        if name not in HYPER_NAMES or not float(value) > 0:
            raise GPDMInputError(f"settings.fixed: {name!r} = {value!r}; keys are {', '.join(HYPER_NAMES)}, "
                                 "values positive")
    for name, ab in settings.gamma.items():
        if name not in HYPER_NAMES or len(ab) != 2 or min(ab) < 0:
            raise GPDMInputError(f"settings.gamma: {name!r} = {ab!r}; keys are {', '.join(HYPER_NAMES)}, "
                                 "values (shape, rate) >= 0")
