"""Gaussian process dynamical model (Kang & Park 2015, Sect. 3.1-3.3)."""

from .learning import GPDMInputError, GPDMSettings, learn_gpdm
from .model import GPDM

__all__ = ["GPDM", "GPDMSettings", "learn_gpdm", "GPDMInputError"]
