"""The user's own robot: a URDF file read into a ``pinocchio.Model``, its physics checked.

Only the URDF's kinematic and inertial tags are read (no meshes), so mesh-less URDFs work; its
masses, inertias and limits are checked (:mod:`.robot_checks`); ``package_dirs`` resolve a
``package://`` URDF path. :func:`continuous_as_revolute` gives a continuous joint one angle.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Sequence

import numpy as np
import pinocchio

from latentoc.errors import LatentocError
from latentoc.robots.robot_checks import check_urdf
from latentoc.robots.urdf_tree import check_tree

__all__ = ["RobotFileError", "load_urdf", "continuous_as_revolute"]


class RobotFileError(LatentocError, ValueError):
    """A robot file that does not exist or cannot be read (URDF, ASF skeleton)."""


def _package_path(text: str, package_dirs: list[Path]) -> Path:
    """A ``package://name/rest`` path found under one of ``package_dirs``, else the path itself."""
    if not text.startswith("package://"):
        return Path(text)
    rest = text[len("package://"):]
    for d in package_dirs:
        if (d / rest).is_file():
            return d / rest
    raise RobotFileError(f"URDF {text}: not found under the package_dirs {', '.join(map(str, package_dirs)) or '[]'}")


def load_urdf(path: str | Path, free_flyer: bool = False,
              package_dirs: Sequence[str | Path] = ()) -> pinocchio.Model:
    """A ``pinocchio.Model`` of the URDF at ``path`` (kinematics and inertias only, no meshes);
    a :class:`RobotFileError` naming the file if it does not exist or does not parse."""
    dirs = [Path(d) for d in package_dirs]
    urdf = _package_path(str(path), dirs)
    if not urdf.is_file():
        raise RobotFileError(f"URDF {urdf} does not exist")
    try:  # a readable message (urdfdom's is only "does not contain a valid URDF model")
        root = ET.parse(urdf).getroot()
    except ET.ParseError as exc:
        raise RobotFileError(f"URDF {urdf} is not valid XML: {exc}") from None
    except OSError as exc:
        raise RobotFileError(f"URDF {urdf} cannot be read: {exc}") from None
    if root.tag != "robot":
        raise RobotFileError(f"URDF {urdf}: the root element is <{root.tag}>, a URDF's is <robot>")
    try:  # the tree Pinocchio's parser can take, then the names of what it would get wrong
        check_tree(root)
    except ValueError as exc:
        raise RobotFileError(f"URDF {urdf}: {exc}") from None
    try:  # masses, inertias and limits that pinocchio would take as they are (module robot_checks)
        check_urdf(root, urdf)
    except ValueError as exc:
        raise RobotFileError(str(exc)) from None
    try:
        if free_flyer:
            model = pinocchio.buildModelFromUrdf(str(urdf), pinocchio.JointModelFreeFlyer())
        else:
            model = pinocchio.buildModelFromUrdf(str(urdf))
    except (ValueError, RuntimeError) as exc:
        raise RobotFileError(f"URDF {urdf} does not parse: {exc}") from None
    if model.nv == 0:
        raise RobotFileError(f"URDF {urdf} has no movable joint")
    if not sum(model.inertias[j].mass for j in range(1, model.njoints)) > 0:
        raise RobotFileError(f"URDF {urdf}: its moving links have no mass (every <inertial><mass> after the "
                             "first joint is 0 or missing), so it has no dynamics to optimise")
    model.name = model.name or urdf.stem
    return model


# pinocchio's continuous joints (q = cos, sin of the angle) and the revolute joint of the same axis
_CONTINUOUS = {"JointModelRUBX": pinocchio.JointModelRX, "JointModelRUBY": pinocchio.JointModelRY,
               "JointModelRUBZ": pinocchio.JointModelRZ}


def continuous_as_revolute(model: pinocchio.Model) -> pinocchio.Model:
    """``model`` with each continuous joint (pinocchio's revolute-unbounded: two coordinates, cos
    and sin) a revolute joint about the same axis with unbounded limits, so that it takes one
    angle like every other joint (nq = nv); the same model (dynamics, frames) otherwise. Returns
    ``model`` itself when it has no continuous joint."""
    kinds = [model.joints[j].shortname() for j in range(1, model.njoints)]
    if not any(k in _CONTINUOUS or k == "JointModelRevoluteUnboundedUnaligned" for k in kinds):
        return model
    new = pinocchio.Model()
    new.name, new.gravity = model.name, model.gravity
    for j, kind in enumerate(kinds, start=1):
        jm = model.joints[j]
        iq, iv = jm.idx_q, jm.idx_v
        lo, hi = model.lowerPositionLimit[iq:iq + jm.nq], model.upperPositionLimit[iq:iq + jm.nq]
        joint = jm
        if kind in _CONTINUOUS:
            joint, lo, hi = _CONTINUOUS[kind](), np.array([-np.inf]), np.array([np.inf])
        elif kind == "JointModelRevoluteUnboundedUnaligned":
            joint, lo, hi = pinocchio.JointModelRevoluteUnaligned(jm.extract().axis), np.array([-np.inf]), np.array([np.inf])
        jid = new.addJoint(model.parents[j], joint, model.jointPlacements[j], model.names[j],
                           model.effortLimit[iv:iv + jm.nv], model.velocityLimit[iv:iv + jm.nv], lo, hi)
        new.appendBodyToJoint(jid, model.inertias[j], pinocchio.SE3.Identity())
    for f in model.frames[1:]:  # the same frames, in the same order (parent frame indices hold)
        new.addFrame(pinocchio.Frame(f.name, f.parentJoint, f.parentFrame, f.placement, f.type, f.inertia), False)
    for name in ("armature", "friction", "damping", "rotorInertia", "rotorGearRatio"):
        if hasattr(model, name):
            setattr(new, name, getattr(model, name).copy())
    return new
