"""Gaussian process dynamical model (Kang & Park 2015, Sect. 3.1-3.3)."""

from .cache import cached_gpdm
from .learning import learn_gpdm
from .model import GPDM
from .settings import GPDMInputError, GPDMSettings
from .size import GPDMSizeError

__all__ = ["GPDM", "GPDMSettings", "learn_gpdm", "cached_gpdm", "GPDMInputError", "GPDMSizeError"]
