"""Acclaim ASF/AMC motion capture: readers, Pinocchio models, jumps, symmetry."""
from latentoc.mocap.format_errors import MocapFormatError
from latentoc.mocap.asf import Bone, Root, Skeleton, parse_asf, read_asf
from latentoc.mocap.amc import Motion, parse_amc, read_amc
from latentoc.mocap.skeleton_model import build_model
from latentoc.mocap.configurations import motion_to_q
from latentoc.mocap.jumps import Jump, detect_jumps
from latentoc.mocap.symmetry import SymmetryMap

__all__ = ["MocapFormatError", "Bone", "Root", "Skeleton", "parse_asf", "read_asf",
           "Motion", "parse_amc", "read_amc", "build_model", "motion_to_q", "Jump",
           "detect_jumps", "SymmetryMap"]
