"""Acclaim ASF/AMC motion capture: readers, Pinocchio models, jumps, symmetry."""
from .errors import MocapFormatError
from .asf import Bone, Root, Skeleton, parse_asf, read_asf
from .amc import Motion, parse_amc, read_amc
from .skeleton_model import build_model
from .configurations import motion_to_q
from .jumps import Jump, detect_jumps
from .symmetry import SymmetryMap

__all__ = ["MocapFormatError", "Bone", "Root", "Skeleton", "parse_asf", "read_asf",
           "Motion", "parse_amc", "read_amc", "build_model", "motion_to_q", "Jump",
           "detect_jumps", "SymmetryMap"]
