"""Robot models by name: example-robot-data's URDFs and latentoc's own human models.

``load_robot("panda")`` finds the URDF inside the installed ``example-robot-data`` wheel
(``cmeel.prefix/share/example-robot-data/robots``) and builds a ``pinocchio.Model``,
with a free-flyer root for legged robots. ``cmu-humanoid`` and ``human-arm`` are built
from the CMU skeleton shipped in ``robots/cmu`` (:mod:`.human_models`, :mod:`.human_arm`).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pinocchio

from latentoc.errors import LatentocError
from latentoc.robots.human_arm import build_human_arm
from latentoc.robots.human_models import build_cmu_humanoid

__all__ = ["load_robot", "robot_names", "robot_urdf", "example_robot_data_dir", "UnknownRobotError"]


class UnknownRobotError(LatentocError, LookupError):
    """A robot name latentoc does not know."""


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


#: latentoc's own models, built from the CMU skeleton in robots/cmu
_OWN_ROBOTS: dict[str, Callable[[], pinocchio.Model]] = {
    "cmu-humanoid": build_cmu_humanoid,
    "human-arm": build_human_arm,
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
