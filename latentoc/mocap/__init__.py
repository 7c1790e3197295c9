"""Acclaim ASF/AMC motion capture: readers, Pinocchio models, jumps, symmetry."""
from .errors import MocapFormatError
from .asf import Bone, Root, Skeleton, parse_asf, read_asf
from .amc import Motion, parse_amc, read_amc

__all__ = ["MocapFormatError", "Bone", "Root", "Skeleton", "parse_asf", "read_asf",
           "Motion", "parse_amc", "read_amc"]
