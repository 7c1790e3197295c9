"""Reader for Acclaim skeleton files (ASF), as used by the CMU mocap database.

Only the parts of the format that the CMU files use are supported: ``:version``,
``:name``, ``:units``, ``:documentation``, ``:root``, ``:bonedata`` and
``:hierarchy``.  Line endings may be LF or CRLF; ``#`` starts a comment.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from latentoc.mocap.format_errors import MocapFormatError, parse_number

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


class _Parser:
    """The state of one :func:`parse_asf` pass: the current section, the open bone and what is read."""

    def __init__(self, path: str | None) -> None:
        self.p = path
        self.name, self.version = "", ""
        self.mass_u, self.length_u, self.angle_u = 1.0, 1.0, "deg"
        self.root = Root()
        self.bones: dict[str, Bone] = {}
        self.bone_line: dict[str, int] = {}
        self.hierarchy: dict[str, list[str]] = {}
        self.parent_of: dict[str, str] = {}
        self.section: str | None = None
        self.seen: set[str] = set()  # the sections that must appear: :root, :bonedata, :hierarchy
        self.cur: dict[str, Any] | None = None  # the bone between begin and end
        self.in_limits = False  # a "(lo hi)" line continues the limits
        self.in_hier_block = False

    def error(self, line: int | None, message: str) -> MocapFormatError:
        return MocapFormatError(self.p, line, message)

    def line(self, ln: int, toks: list[str]) -> None:
        """Read one line (its tokens) in the current section."""
        key = toks[0]
        if key.startswith(":"):
            self.section_header(ln, toks)
        elif self.section is None:
            raise self.error(ln, "text before the first section")
        elif self.section == ":units":
            self.units(ln, toks)
        elif self.section == ":root":
            self.root_line(ln, toks)
        elif self.section == ":bonedata":
            self.bone_data(ln, toks)
        elif self.section == ":hierarchy":
            self.hierarchy_line(ln, toks)

    def section_header(self, ln: int, toks: list[str]) -> None:
        key = toks[0]
        if self.cur is not None:
            raise self.error(ln, "section starts inside an unfinished bone")
        self.in_limits = False
        self.section = key
        if key == ":version":
            self.version = " ".join(toks[1:])
        elif key == ":name":
            self.name = " ".join(toks[1:])
        elif key in (":root", ":bonedata", ":hierarchy"):
            self.seen.add(key)
        elif key not in (":units", ":documentation"):
            raise self.error(ln, f"unknown section {key!r}")
        if len(toks) > 1 and key not in (":version", ":name"):
            raise self.error(ln, f"unexpected text after {key}")

    def units(self, ln: int, toks: list[str]) -> None:
        key = toks[0]
        if len(toks) != 2:
            raise self.error(ln, "units line needs a name and a value")
        if key == "mass":
            self.mass_u = parse_number(toks[1], self.p, ln)
        elif key == "length":
            self.length_u = parse_number(toks[1], self.p, ln)
            if self.length_u <= 0:
                raise self.error(ln, "length unit must be positive")
        elif key == "angle":
            if toks[1] not in ("deg", "rad"):
                raise self.error(ln, f"unknown angle unit {toks[1]!r}")
            self.angle_u = toks[1]
        else:
            raise self.error(ln, f"unknown unit {key!r}")

    def root_line(self, ln: int, toks: list[str]) -> None:
        key, p = toks[0], self.p
        if key == "order":
            order = [t.upper() for t in toks[1:]]
            if sorted(order) != sorted(ROOT_ORDER_NAMES):
                raise self.error(ln, f"root order must be a permutation of {ROOT_ORDER_NAMES}")
            self.root.order = order
        elif key == "axis":
            if len(toks) != 2 or not _AXIS_ORDER.match(toks[1].upper()) or len(set(toks[1].upper())) != 3:
                raise self.error(ln, "root axis must be a rotation order such as XYZ")
            self.root.axis = toks[1].upper()
        elif key == "position":
            self.root.position = _nums(toks[1:], 3, p, ln, "root position")
        elif key == "orientation":
            self.root.orientation = _nums(toks[1:], 3, p, ln, "root orientation")
        else:
            raise self.error(ln, f"unknown root keyword {key!r}")

    def bone_data(self, ln: int, toks: list[str]) -> None:
        key = toks[0]
        if key == "begin":
            if self.cur is not None or len(toks) != 1:
                raise self.error(ln, "unexpected 'begin'")
            self.cur, self.in_limits = {}, False
        elif self.cur is None:
            raise self.error(ln, f"{key!r} outside a bone begin/end block")
        elif key == "end":
            if len(toks) != 1:
                raise self.error(ln, "unexpected text after 'end'")
            self.finish_bone(ln)
            self.in_limits = False
        elif key == "limits" or (key.startswith("(") and self.in_limits):
            self.limit(ln, toks, self.cur)
            self.in_limits = True
        else:
            self.bone_keyword(ln, toks, self.cur)
            self.in_limits = False

    def bone_keyword(self, ln: int, toks: list[str], cur: dict[str, Any]) -> None:
        """One of a bone's id, name, direction, length, axis and dof lines."""
        key, p = toks[0], self.p
        if key == "id":
            v = _nums(toks[1:], 1, p, ln, "id")[0]
            if v != int(v):
                raise self.error(ln, "bone id must be an integer")
            cur["id"] = int(v)
        elif key == "name":
            if len(toks) != 2:
                raise self.error(ln, "name needs one word")
            cur["name"], cur["name_line"] = toks[1], ln
        elif key == "direction":
            cur["direction"], cur["dir_line"] = _nums(toks[1:], 3, p, ln, "direction"), ln
        elif key == "length":
            cur["length"] = float(_nums(toks[1:], 1, p, ln, "length")[0])
            if cur["length"] < 0:
                raise self.error(ln, "negative bone length")
        elif key == "axis":
            if len(toks) != 5:
                raise self.error(ln, "axis needs 3 angles and an order")
            order = toks[4].upper()
            if not _AXIS_ORDER.match(order) or len(set(order)) != 3:
                raise self.error(ln, f"bad axis order {toks[4]!r}")
            cur["axis"], cur["axis_order"] = _nums(toks[1:4], 3, p, ln, "axis"), order
        elif key == "dof":
            cur["dof"] = self.dof(ln, toks)
        else:
            raise self.error(ln, f"unknown bone keyword {key!r}")

    def dof(self, ln: int, toks: list[str]) -> list[str]:
        dof = [t.lower() for t in toks[1:]]
        if not dof:
            raise self.error(ln, "empty dof line")
        for d in dof:
            if d not in ("rx", "ry", "rz"):
                raise self.error(ln, f"unknown or unsupported dof name {d!r}")
        if len(set(dof)) != len(dof):
            raise self.error(ln, "repeated dof name")
        return dof

    def limit(self, ln: int, toks: list[str], cur: dict[str, Any]) -> None:
        """A "limits (lo hi)" line or a "(lo hi)" line after it."""
        rest = " ".join(toks[1:] if toks[0] == "limits" else toks)
        m = re.fullmatch(r"\(\s*(\S+)\s+(\S+)\s*\)", rest)
        if m is None:
            raise self.error(ln, "limits must look like (lo hi)")
        lo, hi = parse_number(m.group(1), self.p, ln), parse_number(m.group(2), self.p, ln)
        if lo > hi:
            raise self.error(ln, "lower limit above upper limit")
        if "dof" not in cur:
            raise self.error(ln, "limits before dof")
        cur.setdefault("limits", []).append((lo, hi))
        if len(cur["limits"]) > len(cur["dof"]):
            raise self.error(ln, "more limits than dof")

    def finish_bone(self, ln: int) -> None:
        cur = self.cur
        assert cur is not None
        for key in ("id", "name", "direction", "length", "axis"):
            if key not in cur:
                raise self.error(ln, f"bone ending here lacks '{key}'")
        dof = cur.get("dof", [])
        limits = cur.get("limits", [])
        if limits and len(limits) != len(dof):
            raise self.error(ln, f"bone {cur['name']!r} has {len(dof)} dof but {len(limits)} limits")
        nm = cur["name"]
        if nm in self.bones or nm == "root":
            raise self.error(cur["name_line"], f"duplicate bone name {nm!r}")
        d = cur["direction"]
        nrm = float(np.linalg.norm(d))
        if nrm < 1e-12:
            raise self.error(cur["dir_line"], "zero bone direction")
        self.bones[nm] = Bone(id=int(cur["id"]), name=nm, direction=d / nrm, length=cur["length"],
                              axis=cur["axis"], axis_order=cur["axis_order"], dof=list(dof), limits=list(limits))
        self.bone_line[nm] = cur["name_line"]
        self.cur = None

    def hierarchy_line(self, ln: int, toks: list[str]) -> None:
        key = toks[0]
        if key in ("begin", "end") and len(toks) == 1:
            self.in_hier_block = key == "begin"
            return
        if not self.in_hier_block:
            raise self.error(ln, "hierarchy line outside begin/end")
        if key != "root" and key not in self.bones:
            raise self.error(ln, f"hierarchy names unknown bone {key!r}")
        if len(toks) < 2:
            raise self.error(ln, "hierarchy line without children")
        for ch in toks[1:]:
            if ch not in self.bones:
                raise self.error(ln, f"hierarchy names unknown bone {ch!r}")
            if ch in self.parent_of:
                raise self.error(ln, f"bone {ch!r} has two parents")
            self.parent_of[ch] = key
            self.hierarchy.setdefault(key, []).append(ch)

    def skeleton(self, last_line: int) -> Skeleton:
        """The skeleton read, its tree checked: every bone in the hierarchy and reached from the root."""
        if self.cur is not None:
            raise self.error(last_line, "file ends inside a bone block")
        if len(self.seen) != 3:
            raise self.error(last_line or None, "missing :root, :bonedata or :hierarchy section")
        for nm in self.bones:
            if nm not in self.parent_of:
                raise self.error(self.bone_line[nm], f"bone {nm!r} is not in the hierarchy")
        reached: set[str] = set()  # reachability from root (no cycles)
        stack = list(self.hierarchy.get("root", []))
        while stack:
            b = stack.pop()
            reached.add(b)
            stack.extend(self.hierarchy.get(b, []))
        for nm in self.bones:
            if nm not in reached:
                raise self.error(self.bone_line[nm], f"bone {nm!r} is not connected to the root")
        for nm, bone in self.bones.items():
            bone.parent = self.parent_of[nm]
            bone.children = list(self.hierarchy.get(nm, []))
        return Skeleton(name=self.name, version=self.version, mass_unit=self.mass_u, length_unit=self.length_u,
                        angle_unit=self.angle_u, root=self.root, bones=self.bones, hierarchy=self.hierarchy,
                        path=self.p)


def parse_asf(text: str, path: str | Path | None = None) -> Skeleton:
    """Parse ASF text; raise :class:`MocapFormatError` naming ``path`` and line."""
    parser = _Parser(None if path is None else str(path))
    last_line = 0
    for ln, toks in _lines(text):
        last_line = ln
        parser.line(ln, toks)
    return parser.skeleton(last_line)


def read_asf(path: str | Path) -> Skeleton:
    """Read an ASF file (see :func:`parse_asf`)."""
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8", errors="strict")
    except UnicodeDecodeError as e:
        raise MocapFormatError(path, None, f"not UTF-8 text: {e}") from None
    return parse_asf(text, path)
