"""A keypoint map file: which source frames the target robot's points follow (``latentoc retarget``).

TOML: ``source`` and ``target`` robots (names from ``latentoc list --robots``), ``scale_chain``
(keypoints whose segment lengths give the scale, hip, knee, ankle), optionally ``scale`` (a number
instead), ``rise`` and ``speed`` (when a source foot rests, :func:`.retargeting.resting`), and one
``[keypoints.NAME]`` table per keypoint with the fields of :class:`.retargeting.Keypoint`. Every
problem is a :class:`.retargeting.RetargetError` naming the key.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from latentoc.motions.retargeting import Keypoint, RetargetError

__all__ = ["RetargetMap", "load_retarget_map"]

_TOP = {"source", "target", "scale_chain", "scale", "rise", "speed", "keypoints", "description"}
_FIELDS = {"source", "target", "offset", "weight", "orientation", "height", "parent"}


@dataclass(frozen=True)
class RetargetMap:
    source: str
    target: str
    keypoints: list[Keypoint]
    scale_chain: list[str]
    scale: float | None
    rise: float
    speed: float


def _number(value: Any, key: str, lo: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < lo:
        raise RetargetError(f"{key}: must be a finite number >= {lo:g}, got {value!r}")
    return float(value)


def _text(value: Any, key: str) -> str:
    if not isinstance(value, str) or not value:
        raise RetargetError(f"{key}: must be a non-empty string, got {value!r}")
    return value


def _keypoint(name: str, table: Any, where: str) -> Keypoint:
    key = f"{where}: keypoints.{name}"
    if not isinstance(table, dict):
        raise RetargetError(f"{key}: must be a table with source and target frames")
    unknown = sorted(set(table) - _FIELDS)
    if unknown:
        raise RetargetError(f"{key}: unknown key {unknown[0]!r}; a keypoint has {', '.join(sorted(_FIELDS))}")
    for need in ("source", "target"):
        if need not in table:
            raise RetargetError(f"{key}.{need}: missing (the frame of the {need} model)")
    offset = table.get("offset", [0.0, 0.0, 0.0])
    if not (isinstance(offset, list) and len(offset) == 3):
        raise RetargetError(f"{key}.offset: must be three numbers (m, in the target frame), got {offset!r}")
    return Keypoint(name, _text(table["source"], f"{key}.source"), _text(table["target"], f"{key}.target"),
                    tuple(_number(v, f"{key}.offset", -math.inf) for v in offset),  # type: ignore[arg-type]
                    _number(table.get("weight", 1.0), f"{key}.weight"),
                    _number(table.get("orientation", 0.0), f"{key}.orientation"),
                    None if "height" not in table else _number(table["height"], f"{key}.height"),
                    None if "parent" not in table else _text(table["parent"], f"{key}.parent"))


def load_retarget_map(path: str | Path) -> RetargetMap:
    """The keypoint map of the TOML file ``path`` (module doc)."""
    path = Path(path)
    if not path.is_file():
        raise RetargetError(f"keypoint map {path} does not exist")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise RetargetError(f"{path}: not a TOML file: {exc}") from None
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise RetargetError(f"{path}: unknown key {unknown[0]!r}; a keypoint map has {', '.join(sorted(_TOP))}")
    for need in ("source", "target", "keypoints"):
        if need not in data:
            raise RetargetError(f"{path}: {need}: missing")
    if not isinstance(data["keypoints"], dict) or not data["keypoints"]:
        raise RetargetError(f"{path}: keypoints: must hold at least one [keypoints.NAME] table")
    keypoints = [_keypoint(n, t, str(path)) for n, t in data["keypoints"].items()]
    names = {k.name for k in keypoints}
    chain = data.get("scale_chain", [])
    if not isinstance(chain, list) or any(c not in names for c in chain):
        raise RetargetError(f"{path}: scale_chain: must list keypoints ({', '.join(sorted(names))}), got {chain!r}")
    scale = None if "scale" not in data else _number(data["scale"], f"{path}: scale")
    if scale is None and len(chain) < 2:
        raise RetargetError(f"{path}: give scale_chain (two or more keypoints) or scale")
    if scale == 0:
        raise RetargetError(f"{path}: scale: must be > 0")
    return RetargetMap(_text(data["source"], f"{path}: source"), _text(data["target"], f"{path}: target"), keypoints,
                       list(chain), scale, _number(data.get("rise", 0.02), f"{path}: rise"),
                       _number(data.get("speed", 0.5), f"{path}: speed"))
