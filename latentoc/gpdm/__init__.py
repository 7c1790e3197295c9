"""Gaussian process dynamical model (Kang & Park 2015, Sect. 3.1-3.3)."""

from .learning import GPDMInputError, GPDMSettings, learn_gpdm
from .size import GPDMSizeError
from .model import GPDM
from .cache import learned_gpdm  # noqa: E402  (after learning and model, which it uses)

__all__ = ["GPDM", "GPDMSettings", "learn_gpdm", "learned_gpdm", "GPDMInputError", "GPDMSizeError"]
