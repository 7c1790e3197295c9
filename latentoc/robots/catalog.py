"""Robot models by name: example-robot-data URDFs and latentoc's own human models; or the user's own.

``load_robot("panda")`` finds the URDF inside the installed ``example-robot-data`` wheel
(``cmeel.prefix/share/example-robot-data/robots``) and builds a ``pinocchio.Model``,
with a free-flyer root for legged robots. ``cmu-humanoid`` and ``human-arm`` are built
from the CMU skeleton shipped in ``robots/cmu``.

A problem file's ``robot`` is such a name or a table naming the user's own model
(:data:`ROBOT`, :func:`robot_from_setting`), its paths relative to the problem file::

    robot = { urdf = "arm.urdf", free_flyer = false, package_dirs = ["."] }
    robot = { asf = "subject.asf", bones = ["lhumerus", "lradius"], mass = 70.0, height = 1.8 }

Only the URDF's kinematic and inertial tags are read (no meshes), so mesh-less URDFs work; its
masses, inertias and limits are checked (:mod:`latentoc.robot_checks`);
``package_dirs`` resolve a ``package://`` URDF path. An ASF skeleton becomes a fixed-base chain
of the listed bones with de Leva masses, as the CMU humanoid is built (:mod:`latentoc.mocap`).
"""

from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
import pinocchio

from .errors import LatentocError
from .robot_checks import check_urdf
from .schema import Check

__all__ = ["load_robot", "robot_names", "robot_urdf", "example_robot_data_dir", "UnknownRobotError", "RobotFileError", "ROBOT",
           "load_urdf", "robot_from_setting", "robot_files", "describe_robot", "continuous_as_revolute"]


class UnknownRobotError(LatentocError, LookupError):
    """A robot name latentoc does not know."""


class RobotFileError(LatentocError, ValueError):
    """A robot file that does not exist or cannot be read (URDF, ASF skeleton)."""


@dataclass(frozen=True)
class _URDFRobot:
    path: str  # relative to example-robot-data's robots/ folder
    free_flyer: bool


_EXAMPLE_ROBOTS: dict[str, _URDFRobot] = {
    "panda": _URDFRobot("panda_description/urdf/panda.urdf", False),
    "ur3": _URDFRobot("ur_description/urdf/ur3_robot.urdf", False),
    "ur5": _URDFRobot("ur_description/urdf/ur5_robot.urdf", False),
    "ur10": _URDFRobot("ur_description/urdf/ur10_robot.urdf", False),
    "kinova": _URDFRobot("kinova_description/robots/kinova.urdf", False),
    "xarm7": _URDFRobot("xarm_description/urdf/xarm7.urdf", False),
    "z1": _URDFRobot("z1_description/urdf/z1.urdf", False),
    "double-pendulum": _URDFRobot("double_pendulum_description/urdf/double_pendulum_simple.urdf", False),
    "talos": _URDFRobot("talos_data/robots/talos_reduced.urdf", True),
    "talos-full": _URDFRobot("talos_data/robots/talos_full_v2.urdf", True),
    "human": _URDFRobot("human_description/robots/human.urdf", True),
    "romeo": _URDFRobot("romeo_description/urdf/romeo_small.urdf", True),
    "icub": _URDFRobot("icub_description/robots/icub_reduced.urdf", True),
    "g1": _URDFRobot("g1_description/urdf/g1_29dof_rev_1_0.urdf", True),
    "simple-humanoid": _URDFRobot("simple_humanoid_description/urdf/simple_humanoid.urdf", True),
    "solo12": _URDFRobot("solo_description/robots/solo12.urdf", True),
    "anymal": _URDFRobot("anymal_b_simple_description/robots/anymal.urdf", True),
    "a1": _URDFRobot("a1_description/urdf/a1.urdf", True),
    "go1": _URDFRobot("go1_description/urdf/go1.urdf", True),
    "go2": _URDFRobot("go2_description/urdf/go2.urdf", True),
    "hyq": _URDFRobot("hyq_description/robots/hyq_no_sensors.urdf", True),
    "bolt": _URDFRobot("bolt_description/robots/bolt.urdf", True),
}


def _cmu_humanoid() -> pinocchio.Model:
    from latentoc.human_models import build_cmu_humanoid

    return build_cmu_humanoid()


def _human_arm() -> pinocchio.Model:
    from latentoc.human_models import build_human_arm

    return build_human_arm()


_OWN_ROBOTS: dict[str, Callable[[], pinocchio.Model]] = {
    "cmu-humanoid": _cmu_humanoid,
    "human-arm": _human_arm,
}


def robot_names() -> list[str]:
    """Every name :func:`load_robot` accepts."""
    return sorted(_OWN_ROBOTS) + sorted(_EXAMPLE_ROBOTS)


def example_robot_data_dir() -> Path:
    """The ``robots/`` folder of the installed example-robot-data wheel."""
    candidates = [Path(p) / "cmeel.prefix" / "share" / "example-robot-data" / "robots" for p in sys.path if p]
    try:
        import cmeel  # type: ignore[import-not-found]

        candidates.insert(0, Path(cmeel.__file__).resolve().parents[1] / "cmeel.prefix/share/example-robot-data/robots")
    except ImportError:
        pass
    for candidate in candidates:
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(
        "example-robot-data's robots folder was not found in site-packages; install it with "
        "`pip install example-robot-data`"
    )


def robot_urdf(name: str) -> Path | None:
    """The URDF of an example-robot-data robot name (its meshes are ``package://example-robot-data/...``
    under :func:`example_robot_data_dir`'s grandparent); None for latentoc's own models."""
    if name in _OWN_ROBOTS:
        return None
    if name not in _EXAMPLE_ROBOTS:
        raise UnknownRobotError(f"unknown robot {name!r}; known robots: {', '.join(robot_names())}")
    return example_robot_data_dir() / _EXAMPLE_ROBOTS[name].path


def load_robot(name: str, free_flyer: bool | None = None) -> pinocchio.Model:
    """A ``pinocchio.Model`` by name; ``free_flyer`` overrides the robot's default root joint."""
    if name in _OWN_ROBOTS:
        if free_flyer is not None:
            raise ValueError(f"robot {name!r} has a fixed root joint type; do not pass free_flyer")
        return _OWN_ROBOTS[name]()
    if name not in _EXAMPLE_ROBOTS:
        raise UnknownRobotError(f"unknown robot {name!r}; known robots: {', '.join(robot_names())}")
    entry = _EXAMPLE_ROBOTS[name]
    urdf = example_robot_data_dir() / entry.path
    if not urdf.is_file():
        raise FileNotFoundError(f"robot {name!r}: URDF {urdf} is missing from example-robot-data")
    use_ff = entry.free_flyer if free_flyer is None else free_flyer
    if use_ff:
        model = pinocchio.buildModelFromUrdf(str(urdf), pinocchio.JointModelFreeFlyer())
    else:
        model = pinocchio.buildModelFromUrdf(str(urdf))
    model.name = name
    return model


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
    model.name = model.name or urdf.stem
    return model


def _robot_table(value: Any) -> str | dict[str, Any]:
    """The ``robot`` setting normalised: a known name, or a urdf / asf table with every key."""
    if isinstance(value, str):
        if value not in robot_names():
            raise ValueError
        return value
    if not isinstance(value, dict):
        raise ValueError
    if "urdf" in value:
        allowed = {"urdf", "free_flyer", "package_dirs"}
        out = {"urdf": value["urdf"], "free_flyer": value.get("free_flyer", False),
               "package_dirs": list(value.get("package_dirs", []))}
        ok = isinstance(out["urdf"], str) and out["urdf"] and isinstance(out["free_flyer"], bool) \
            and all(isinstance(d, str) for d in out["package_dirs"])
    elif "asf" in value:
        allowed = {"asf", "bones", "mass", "height"}
        out = {"asf": value["asf"], "bones": list(value.get("bones", [])), "mass": value.get("mass", 63.86),
               "height": value.get("height", 1.75)}
        ok = isinstance(out["asf"], str) and out["asf"] and len(out["bones"]) > 0 \
            and all(isinstance(b, str) for b in out["bones"]) \
            and all(isinstance(out[k], (int, float)) and not isinstance(out[k], bool) and out[k] > 0
                    for k in ("mass", "height"))
    else:
        ok, allowed, out = False, set(), {}
    if not ok or set(value) - allowed:
        raise ValueError
    return out


#: the check of a problem file's ``robot``: a name, or a table naming a URDF or an ASF skeleton
ROBOT = Check(_robot_table, f"one of {', '.join(map(repr, robot_names()))}, "
                            '{ urdf = "path", free_flyer = false, package_dirs = [...] } '
                            'or { asf = "path", bones = [...], mass = kg, height = m }')


def robot_files(setting: str | dict[str, Any], base_dir: Path) -> list[Path]:
    """The files a ``robot`` setting names, resolved against ``base_dir`` (none for a name)."""
    if isinstance(setting, str):
        return []
    key = "urdf" if "urdf" in setting else "asf"
    if setting[key].startswith("package://"):
        return []
    return [base_dir / setting[key]]


def describe_robot(setting: str | dict[str, Any]) -> str:
    """A short name of a ``robot`` setting for messages: the name, or the file's."""
    if isinstance(setting, str):
        return setting
    return setting.get("urdf") or setting["asf"]


def robot_from_setting(setting: str | dict[str, Any], base_dir: str | Path = ".") -> pinocchio.Model:
    """The model a ``robot`` setting (:data:`ROBOT`) names, its paths relative to ``base_dir``."""
    base = Path(base_dir)
    if isinstance(setting, str):
        return load_robot(setting)
    if "urdf" in setting:
        return load_urdf(base / setting["urdf"] if not setting["urdf"].startswith("package://") else setting["urdf"],
                         setting["free_flyer"], [base / d for d in setting["package_dirs"]])
    from .human_models import skeleton_chain

    return skeleton_chain(base / setting["asf"], setting["bones"], setting["mass"], setting["height"])


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
