"""Typed settings of a problem file: each kind declares its keys once, with type, range and default.

A :class:`Schema` is a list of :class:`Setting`. A setting's ``key`` is its place in the TOML file
(``"duration"``, ``"latent.dim"``; a :class:`Table` setting such as ``"options"`` is a whole table
of its own settings), its ``name`` the problem's attribute and the keyword of
``load_problem(..., **overrides)``. Each check returns the value normalised (an int given for a
float is a float) or raises ``ValueError`` with what the value must be; :meth:`Schema.parse`
turns that, an unknown key, a key the kind does not read, or a missing required key into one
:class:`~latentoc.errors.ProblemError` naming the key and the allowed ones. A kind's checks that
involve several settings (enough control points for the degree, files that exist) are the
schema's ``check``.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from latentoc.errors import ProblemError

__all__ = ["Check", "Setting", "Table", "Schema", "REQUIRED", "integer", "number", "boolean", "choice", "text",
           "list_of", "optional"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: the default of a setting the file must give
REQUIRED: Any = _Required()


@dataclass(frozen=True)
class Check:
    """A value check: ``convert(value)`` returns the normalised value or raises ValueError;
    ``what`` says what the value must be (in error messages and ``latentoc show``)."""

    convert: Callable[[Any], Any]
    what: str

    def __call__(self, value: Any) -> Any:
        try:
            return self.convert(value)
        except (TypeError, ValueError):
            raise ValueError(f"must be {self.what}, got {value!r}") from None


def _in_range(v: float, lo: float | None, hi: float | None, lo_open: bool) -> bool:
    return (lo is None or (v > lo if lo_open else v >= lo)) and (hi is None or v <= hi)


def _range_text(lo: float | None, hi: float | None, lo_open: bool) -> str:
    if lo is not None and hi is not None:
        return f" in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    if lo is not None:
        return f" {'>' if lo_open else '>='} {lo:g}"
    return f" <= {hi:g}" if hi is not None else ""


def integer(lo: int | None = None, hi: int | None = None) -> Check:
    """An int (not a bool) in ``[lo, hi]``."""
    def convert(v: Any) -> int:
        if isinstance(v, bool) or not isinstance(v, int) or not _in_range(v, lo, hi, False):
            raise ValueError
        return int(v)
    return Check(convert, "an integer" + _range_text(lo, hi, False))


def number(lo: float | None = None, hi: float | None = None, lo_open: bool = False) -> Check:
    """A finite int or float (returned as float) in ``[lo, hi]`` (``(lo, hi]`` with ``lo_open``)."""
    def convert(v: Any) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
                or not _in_range(v, lo, hi, lo_open):
            raise ValueError
        return float(v)
    return Check(convert, "a number" + _range_text(lo, hi, lo_open))


def _bool(v: Any) -> bool:
    if not isinstance(v, bool):
        raise ValueError
    return v


def boolean() -> Check:
    return Check(_bool, "true or false")


def choice(*values: Any) -> Check:
    """One of ``values``."""
    def convert(v: Any) -> Any:
        if isinstance(v, bool) or v not in values:
            raise ValueError
        return v
    return Check(convert, "one of " + ", ".join(repr(v) for v in values))


def text() -> Check:
    """A non-empty string."""
    def convert(v: Any) -> str:
        if not isinstance(v, str) or not v:
            raise ValueError
        return v
    return Check(convert, "a non-empty string")


def list_of(item: Check, min_len: int = 0) -> Check:
    """A list (a tuple from Python) of at least ``min_len`` items, each passing ``item``."""
    def convert(v: Any) -> list[Any]:
        if not isinstance(v, (list, tuple)) or len(v) < min_len:
            raise ValueError
        return [item.convert(x) for x in v]
    return Check(convert, f"a list{f' of at least {min_len}' if min_len else ''}, each {item.what}")


def optional(check: Check) -> Check:
    """``check``, or None (a setting the TOML file leaves out to mean "none")."""
    return Check(lambda v: None if v is None else check.convert(v), f"{check.what}, or none")


@dataclass(frozen=True)
class Setting:
    """One key of a problem file (module doc)."""

    key: str
    name: str
    check: Check
    default: Any = REQUIRED
    doc: str = ""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


@dataclass(frozen=True)
class Table:
    """A setting whose value is a whole TOML table of its own settings (``[gpdm]``, ``[options]``),
    kept as a dict on the problem, every key resolved (defaults filled in)."""

    key: str
    name: str
    settings: tuple[Setting, ...]
    doc: str = ""

    def parse(self, data: Any, where: str, base: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The table's values: ``base`` (default: every default) updated by ``data``, checked."""
        if not isinstance(data, Mapping):
            raise ProblemError(f"{where}: [{self.key}] must be a table, got {data!r}")
        by_key = {s.key: s for s in self.settings}
        values = dict(base) if base is not None else {s.key: s.default for s in self.settings}
        for k, v in data.items():
            if k not in by_key:
                raise ProblemError(f"{where}: unknown key '{self.key}.{k}'; [{self.key}] allows: "
                                   f"{', '.join(sorted(by_key))}")
            values[k] = _checked(by_key[k], v, f"{where}: key '{self.key}.{k}'")
        return values


def _checked(s: Setting, value: Any, where: str) -> Any:
    try:
        return s.check(value)
    except ValueError as exc:
        raise ProblemError(f"{where} {exc}") from None


@dataclass(frozen=True)
class Schema:
    """The settings of one problem kind (module doc) and its ``check`` across settings
    (``check(problem, where)`` raises a ProblemError naming ``where``; run on every load and
    change of a problem, :class:`latentoc.problem.declaration.Problem`)."""

    kind: str
    settings: tuple[Setting | Table, ...]
    doc: str = ""
    check: Callable[[Any, str], None] | None = field(default=None, compare=False)
    _by_key: dict[str, Setting | Table] = field(init=False, repr=False, compare=False)
    _by_name: dict[str, Setting | Table] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_by_key", {s.key: s for s in self.settings})
        object.__setattr__(self, "_by_name", {s.name: s for s in self.settings})
        if len(self._by_key) != len(self.settings) or len(self._by_name) != len(self.settings):
            raise ValueError(f"schema {self.kind!r}: duplicate setting keys or names")

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.settings]

    def _tables(self) -> dict[str, list[str]]:
        """TOML table -> its keys (top-level keys under "")."""
        tables: dict[str, list[str]] = {}
        for s in self.settings:
            table, _, key = s.key.rpartition(".")
            tables.setdefault(s.key if isinstance(s, Table) else table, []).append(
                "*" if isinstance(s, Table) else key)
        return tables

    def parse(self, data: Mapping[str, Any], where: str, ignore: Iterable[str] = ()) -> dict[str, Any]:
        """Every setting's value by name from a TOML document (defaults for the keys it leaves
        out); the keys in ``ignore`` (read by the caller, e.g. ``kind``) are skipped."""
        given: dict[str, Any] = {}
        tables = self._tables()
        for key, value in data.items():
            if key in ignore:
                continue
            entry = self._by_key.get(key)
            if isinstance(entry, Table):
                given[entry.name] = entry.parse(value, where)
            elif isinstance(entry, Setting):  # its value may be a table too (robot = { urdf = ... })
                given[entry.name] = _checked(entry, value, f"{where}: key '{key}'")
            elif isinstance(value, Mapping):
                if key not in tables or key == "":
                    raise ProblemError(f"{where}: unknown table [{key}]; a {self.kind} problem has the tables "
                                       f"{', '.join(f'[{t}]' for t in sorted(t for t in tables if t))}")
                for sub, v in value.items():
                    s = self._by_key.get(f"{key}.{sub}")
                    if not isinstance(s, Setting):
                        raise ProblemError(f"{where}: unknown key '{key}.{sub}'; [{key}] of a {self.kind} problem "
                                           f"allows: {', '.join(sorted(tables[key]))}")
                    given[s.name] = _checked(s, v, f"{where}: key '{key}.{sub}'")
            else:
                raise ProblemError(f"{where}: unknown key '{key}'; a {self.kind} problem allows the top-level keys "
                                   f"{', '.join(sorted([*ignore, *tables.get('', [])]))}")
        return self.resolve(given, where)

    def resolve(self, given: Mapping[str, Any], where: str) -> dict[str, Any]:
        """``given`` (by name, already checked) with the defaults of the rest."""
        values: dict[str, Any] = {}
        for s in self.settings:
            if s.name in given:
                values[s.name] = given[s.name]
            elif isinstance(s, Table):
                values[s.name] = s.parse({}, where)
            elif s.required:
                raise ProblemError(f"{where}: missing key '{s.key}' ({s.check.what})")
            else:
                values[s.name] = _copy(s.default)
        return values

    def checked(self, given: Mapping[str, Any], where: str,
                base: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """``given`` values (by name) checked; a table's dict is merged into ``base``'s table or,
        without a base, into its defaults."""
        out: dict[str, Any] = {}
        for name, v in given.items():
            s = self._by_name.get(name)
            if s is None:
                raise ProblemError(f"{where}: unknown setting {name!r}; a {self.kind} problem has "
                                   f"{', '.join(sorted(self._by_name))}")
            if isinstance(s, Table):
                out[name] = s.parse(v, where, base=None if base is None else base[name])
            else:
                out[name] = _checked(s, v, f"{where}: setting {name!r} (key '{s.key}')")
        return out

    def override(self, values: Mapping[str, Any], overrides: Mapping[str, Any], where: str) -> dict[str, Any]:
        """``values`` with ``overrides`` (by name; a table's dict merged into it), checked."""
        return {**values, **self.checked(overrides, where, base=values)}

    def describe(self, values: Mapping[str, Any]) -> list[tuple[str, Any, str]]:
        """(TOML key, value, what it must be / doc) of every setting, tables expanded."""
        rows: list[tuple[str, Any, str]] = []
        for s in self.settings:
            if isinstance(s, Table):
                rows += [(f"{s.key}.{t.key}", values[s.name][t.key], t.doc or t.check.what) for t in s.settings]
            else:
                rows.append((s.key, values[s.name], s.doc or s.check.what))
        return rows


def _copy(value: Any) -> Any:
    return list(value) if isinstance(value, (list, tuple)) else value

