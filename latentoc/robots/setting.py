"""A problem file's ``robot``: a registered name, or a table naming the user's own model.

Its paths are relative to the problem file (:data:`ROBOT`, :func:`robot_from_setting`)::

    robot = { urdf = "arm.urdf", free_flyer = false, package_dirs = ["."] }
    robot = { asf = "subject.asf", bones = ["lhumerus", "lradius"], mass = 70.0, height = 1.8 }

An ASF skeleton becomes a fixed-base chain of the listed bones with de Leva masses, as the CMU
humanoid is built (:func:`.human_models.skeleton_chain`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pinocchio

from latentoc.problem.schema import Check
from latentoc.robots.catalog import load_robot, robot_names
from latentoc.robots.human_models import skeleton_chain
from latentoc.robots.urdf import load_urdf

__all__ = ["ROBOT", "robot_from_setting", "robot_files", "describe_robot"]


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
    return skeleton_chain(base / setting["asf"], setting["bones"], setting["mass"], setting["height"])
