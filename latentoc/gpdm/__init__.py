"""Gaussian process dynamical model (Kang & Park 2015, Sect. 3.1-3.3)."""

from latentoc.gpdm.cache import cached_gpdm
from latentoc.gpdm.learning import learn_gpdm
from latentoc.gpdm.model import GPDM
from latentoc.gpdm.learning_settings import GPDMInputError, GPDMSettings
from latentoc.gpdm.size import GPDMSizeError

__all__ = ["GPDM", "GPDMSettings", "learn_gpdm", "cached_gpdm", "GPDMInputError", "GPDMSizeError"]
