"""Reader for Acclaim skeleton files (ASF), as used by the CMU mocap database.

Only the parts of the format that the CMU files use are supported: ``:version``,
``:name``, ``:units``, ``:documentation``, ``:root``, ``:bonedata`` and
``:hierarchy``.  Line endings may be LF or CRLF; ``#`` starts a comment.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import MocapFormatError, parse_number

INCH = 0.0254
DOF_NAMES = ("rx", "ry", "rz", "tx", "ty", "tz", "l")
ROOT_ORDER_NAMES = ("TX", "TY", "TZ", "RX", "RY", "RZ")
_AXIS_ORDER = re.compile(r"^[XYZ]{3}$")


@dataclass
class Root:
    """The ASF ``:root`` section."""

    order: list[str] = field(default_factory=lambda: list(ROOT_ORDER_NAMES))
    axis: str = "XYZ"
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    orientation: np.ndarray = field(default_factory=lambda: np.zeros(3))


@dataclass
class Bone:
    """One ASF bone; angles in degrees, direction a unit vector in ASF global axes."""

    id: int
    name: str
    direction: np.ndarray
    length: float
    axis: np.ndarray
    axis_order: str
    dof: list[str]
    limits: list[tuple[float, float]]
    parent: str | None = None
    children: list[str] = field(default_factory=list)


@dataclass
class Skeleton:
    """A parsed ASF skeleton.

    ``length_unit`` is the ASF ``length`` multiplier: one file unit is
    ``(1/length_unit)`` inch, see :attr:`unit_to_m`.
    """

    name: str
    version: str
    mass_unit: float
    length_unit: float
    angle_unit: str
    root: Root
    bones: dict[str, Bone]
    hierarchy: dict[str, list[str]]
    path: str | None = None

    @property
    def unit_to_m(self) -> float:
        """Metres per ASF length unit (0.05644 m for ``length 0.45``)."""
        return INCH / self.length_unit

    @property
    def n_dof(self) -> int:
        """Total DOF: 6 for the root plus all bone dofs (62 for CMU subject 01)."""
        return 6 + sum(len(b.dof) for b in self.bones.values())

    def topological_order(self) -> list[str]:
        """Bone names in depth-first hierarchy order (parents before children)."""
        out: list[str] = []
        stack = list(reversed(self.hierarchy.get("root", [])))
        while stack:
            b = stack.pop()
            out.append(b)
            stack.extend(reversed(self.hierarchy.get(b, [])))
        return out


def _nums(toks: list[str], n: int, path: str | None, line: int, what: str) -> np.ndarray:
    if len(toks) != n:
        raise MocapFormatError(path, line, f"{what} needs {n} values, got {len(toks)}")
    return np.array([parse_number(t, path, line) for t in toks], dtype=float)


def _lines(text: str) -> list[tuple[int, list[str]]]:
    out = []
    for i, raw in enumerate(text.splitlines(), start=1):
        s = raw.split("#", 1)[0].strip()
        if s:
            out.append((i, s.split()))
    return out


def parse_asf(text: str, path: str | Path | None = None) -> Skeleton:
    """Parse ASF text; raise :class:`MocapFormatError` naming ``path`` and line."""
    p = None if path is None else str(path)
    lines = _lines(text)
    name, version = "", ""
    mass_u, length_u, angle_u = 1.0, 1.0, "deg"
    root = Root()
    bones: dict[str, Bone] = {}
    bone_line: dict[str, int] = {}
    hierarchy: dict[str, list[str]] = {}
    parent_of: dict[str, str] = {}
    section = None
    seen_root = seen_bones = seen_hier = False
    cur: dict | None = None
    in_limits = False
    in_hier_block = False
    last_line = 0

    def finish_bone(ln: int) -> None:
        nonlocal cur
        assert cur is not None
        for key in ("id", "name", "direction", "length", "axis"):
            if key not in cur:
                raise MocapFormatError(p, ln, f"bone ending here lacks '{key}'")
        dof = cur.get("dof", [])
        limits = cur.get("limits", [])
        if limits and len(limits) != len(dof):
            raise MocapFormatError(p, ln, f"bone {cur['name']!r} has {len(dof)} dof but {len(limits)} limits")
        nm = cur["name"]
        if nm in bones or nm == "root":
            raise MocapFormatError(p, cur["name_line"], f"duplicate bone name {nm!r}")
        d = cur["direction"]
        nrm = float(np.linalg.norm(d))
        if nrm < 1e-12:
            raise MocapFormatError(p, cur["dir_line"], "zero bone direction")
        bones[nm] = Bone(id=int(cur["id"]), name=nm, direction=d / nrm, length=cur["length"],
                         axis=cur["axis"], axis_order=cur["axis_order"], dof=list(dof),
                         limits=list(limits))
        bone_line[nm] = cur["name_line"]
        cur = None

    for ln, toks in lines:
        last_line = ln
        key = toks[0]
        if key.startswith(":"):
            if cur is not None:
                raise MocapFormatError(p, ln, "section starts inside an unfinished bone")
            in_limits = False
            section = key
            if key == ":version":
                version = " ".join(toks[1:])
            elif key == ":name":
                name = " ".join(toks[1:])
            elif key == ":root":
                seen_root = True
            elif key == ":bonedata":
                seen_bones = True
            elif key == ":hierarchy":
                seen_hier = True
            elif key in (":units", ":documentation"):
                pass
            else:
                raise MocapFormatError(p, ln, f"unknown section {key!r}")
            if len(toks) > 1 and key not in (":version", ":name"):
                raise MocapFormatError(p, ln, f"unexpected text after {key}")
            continue
        if section is None:
            raise MocapFormatError(p, ln, "text before the first section")
        if section in (":version", ":name", ":documentation"):
            continue
        if section == ":units":
            if len(toks) != 2:
                raise MocapFormatError(p, ln, "units line needs a name and a value")
            if key == "mass":
                mass_u = parse_number(toks[1], p, ln)
            elif key == "length":
                length_u = parse_number(toks[1], p, ln)
                if length_u <= 0:
                    raise MocapFormatError(p, ln, "length unit must be positive")
            elif key == "angle":
                if toks[1] not in ("deg", "rad"):
                    raise MocapFormatError(p, ln, f"unknown angle unit {toks[1]!r}")
                angle_u = toks[1]
            else:
                raise MocapFormatError(p, ln, f"unknown unit {key!r}")
            continue
        if section == ":root":
            if key == "order":
                order = [t.upper() for t in toks[1:]]
                if sorted(order) != sorted(ROOT_ORDER_NAMES):
                    raise MocapFormatError(p, ln, f"root order must be a permutation of {ROOT_ORDER_NAMES}")
                root.order = order
            elif key == "axis":
                if len(toks) != 2 or not _AXIS_ORDER.match(toks[1].upper()) or len(set(toks[1].upper())) != 3:
                    raise MocapFormatError(p, ln, "root axis must be a rotation order such as XYZ")
                root.axis = toks[1].upper()
            elif key == "position":
                root.position = _nums(toks[1:], 3, p, ln, "root position")
            elif key == "orientation":
                root.orientation = _nums(toks[1:], 3, p, ln, "root orientation")
            else:
                raise MocapFormatError(p, ln, f"unknown root keyword {key!r}")
            continue
        if section == ":bonedata":
            if key == "begin":
                if cur is not None or len(toks) != 1:
                    raise MocapFormatError(p, ln, "unexpected 'begin'")
                cur = {}
                in_limits = False
                continue
            if cur is None:
                raise MocapFormatError(p, ln, f"{key!r} outside a bone begin/end block")
            if key == "end":
                if len(toks) != 1:
                    raise MocapFormatError(p, ln, "unexpected text after 'end'")
                finish_bone(ln)
                in_limits = False
                continue
            if key == "id":
                v = _nums(toks[1:], 1, p, ln, "id")[0]
                if v != int(v):
                    raise MocapFormatError(p, ln, "bone id must be an integer")
                cur["id"] = int(v)
            elif key == "name":
                if len(toks) != 2:
                    raise MocapFormatError(p, ln, "name needs one word")
                cur["name"], cur["name_line"] = toks[1], ln
            elif key == "direction":
                cur["direction"] = _nums(toks[1:], 3, p, ln, "direction")
                cur["dir_line"] = ln
            elif key == "length":
                cur["length"] = float(_nums(toks[1:], 1, p, ln, "length")[0])
                if cur["length"] < 0:
                    raise MocapFormatError(p, ln, "negative bone length")
            elif key == "axis":
                if len(toks) != 5:
                    raise MocapFormatError(p, ln, "axis needs 3 angles and an order")
                order = toks[4].upper()
                if not _AXIS_ORDER.match(order) or len(set(order)) != 3:
                    raise MocapFormatError(p, ln, f"bad axis order {toks[4]!r}")
                cur["axis"] = _nums(toks[1:4], 3, p, ln, "axis")
                cur["axis_order"] = order
            elif key == "dof":
                dof = [t.lower() for t in toks[1:]]
                if not dof:
                    raise MocapFormatError(p, ln, "empty dof line")
                for d in dof:
                    if d not in ("rx", "ry", "rz"):
                        raise MocapFormatError(p, ln, f"unknown or unsupported dof name {d!r}")
                if len(set(dof)) != len(dof):
                    raise MocapFormatError(p, ln, "repeated dof name")
                cur["dof"] = dof
            elif key == "limits" or (key.startswith("(") and in_limits):
                rest = " ".join(toks[1:] if key == "limits" else toks)
                m = re.fullmatch(r"\(\s*(\S+)\s+(\S+)\s*\)", rest)
                if m is None:
                    raise MocapFormatError(p, ln, "limits must look like (lo hi)")
                lo, hi = parse_number(m.group(1), p, ln), parse_number(m.group(2), p, ln)
                if lo > hi:
                    raise MocapFormatError(p, ln, "lower limit above upper limit")
                if "dof" not in cur:
                    raise MocapFormatError(p, ln, "limits before dof")
                cur.setdefault("limits", []).append((lo, hi))
                if len(cur["limits"]) > len(cur["dof"]):
                    raise MocapFormatError(p, ln, "more limits than dof")
                in_limits = True
                continue
            else:
                raise MocapFormatError(p, ln, f"unknown bone keyword {key!r}")
            in_limits = False
            continue
        if section == ":hierarchy":
            if key == "begin" and len(toks) == 1:
                in_hier_block = True
                continue
            if key == "end" and len(toks) == 1:
                in_hier_block = False
                continue
            if not in_hier_block:
                raise MocapFormatError(p, ln, "hierarchy line outside begin/end")
            par = key
            if par != "root" and par not in bones:
                raise MocapFormatError(p, ln, f"hierarchy names unknown bone {par!r}")
            if len(toks) < 2:
                raise MocapFormatError(p, ln, "hierarchy line without children")
            for ch in toks[1:]:
                if ch not in bones:
                    raise MocapFormatError(p, ln, f"hierarchy names unknown bone {ch!r}")
                if ch in parent_of:
                    raise MocapFormatError(p, ln, f"bone {ch!r} has two parents")
                parent_of[ch] = par
                hierarchy.setdefault(par, []).append(ch)
            continue
    if cur is not None:
        raise MocapFormatError(p, last_line, "file ends inside a bone block")
    if not (seen_root and seen_bones and seen_hier):
        raise MocapFormatError(p, last_line or None, "missing :root, :bonedata or :hierarchy section")
    for nm in bones:
        if nm not in parent_of:
            raise MocapFormatError(p, bone_line[nm], f"bone {nm!r} is not in the hierarchy")
    # reachability from root (no cycles)
    seen: set[str] = set()
    stack = list(hierarchy.get("root", []))
    while stack:
        b = stack.pop()
        seen.add(b)
        stack.extend(hierarchy.get(b, []))
    for nm in bones:
        if nm not in seen:
            raise MocapFormatError(p, bone_line[nm], f"bone {nm!r} is not connected to the root")
    for nm, b in bones.items():
        b.parent = parent_of[nm]
        b.children = list(hierarchy.get(nm, []))
    return Skeleton(name=name, version=version, mass_unit=mass_u, length_unit=length_u,
                    angle_unit=angle_u, root=root, bones=bones, hierarchy=hierarchy, path=p)


def read_asf(path: str | Path) -> Skeleton:
    """Read an ASF file (see :func:`parse_asf`)."""
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="strict")
    except UnicodeDecodeError as e:
        raise MocapFormatError(path, None, f"not UTF-8 text: {e}") from None
    return parse_asf(text, path)
