"""Problem declarations: TOML files in ``problems/`` by name or path, and problems as data.

A problem is a TOML file in ``problems/`` (``arm-raise`` -> ``problems/arm-raise.toml``) or any
path to a ``.toml`` file. Three top-level keys are common to every kind::

    name = "arm-raise"            # defaults to the file stem
    description = "..."
    kind = "latent-min-torque"    # a key of latentoc.problem.kinds.KINDS

Every other key belongs to the kind's :class:`~latentoc.problem.schema.Schema` (its
:class:`~latentoc.problem.kinds.Kind`'s), which gives each key's type, range, default and meaning. A key
the kind does not declare is an error naming it and the allowed ones; ``python -m latentoc show
PROBLEM`` prints every resolved setting. Errors are :class:`~latentoc.errors.ProblemError` naming
the file and key.
"""

from __future__ import annotations

import difflib
import tomllib
from pathlib import Path
from typing import Any

from latentoc.errors import ProblemError
from latentoc.problem.toml_limits import MAX_BYTES, toml_bounds_problem
from latentoc.problem.kinds import KINDS, kind_of
from latentoc.runtime.paths import data_dir
from latentoc.problem.declaration import Problem, check_name, checked

__all__ = ["load_problem", "problem_names", "problems_dir", "problem_from_dict"]

_COMMON = ("name", "description", "kind")


def problems_dir() -> Path:
    """The folder of the packaged problem declarations."""
    return data_dir("problems")


def problem_names() -> list[str]:
    """Names of the packaged problems (file stems of ``problems/*.toml``)."""
    return sorted(p.stem for p in problems_dir().glob("*.toml"))


def _resolve(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    shown = text if len(text) <= 200 else f"{text[:200]}... ({len(text)} characters)"
    path = Path(text)
    try:
        if text.endswith(".toml") or path.is_file() or "/" in text:
            if path.is_dir():
                raise ProblemError(f"problem file {shown} is a folder, not a .toml file")
            if path.exists() and not path.is_file():
                raise ProblemError(f"problem file {shown} is not a regular file (a pipe or device?)")
            if not path.is_file():
                raise ProblemError(f"problem file {shown} does not exist")
            return path
    except OSError as exc:
        raise ProblemError(f"problem file {shown} cannot be read: {exc.strerror}") from None
    candidate = problems_dir() / f"{text}.toml"
    if not candidate.is_file():
        names = problem_names()
        close = difflib.get_close_matches(text, names, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ProblemError(f"unknown problem {shown!r}; {hint}known problems: {', '.join(names)}, "
                           "or the path of a .toml file")
    return candidate


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        if not path.is_file():
            raise ProblemError(f"{path}: not a regular file (a problem file is a .toml file)")
        if path.stat().st_size > MAX_BYTES:
            raise ProblemError(f"{path}: {path.stat().st_size} bytes; a problem file needs a few kB")
        text = path.read_text(encoding="utf-8")
        if text.startswith("\ufeff"):
            raise ProblemError(f"{path}: starts with a byte-order mark, which TOML does not allow; save it as UTF-8 without BOM")
        if (problem := toml_bounds_problem(text)) is not None:
            raise ProblemError(f"{path}: {problem}")
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: not UTF-8 text, as TOML must be ({exc})") from None
    except OSError as exc:
        raise ProblemError(f"{path}: cannot be read: {exc}") from None


def load_problem(name_or_path: str | Path, **overrides: Any) -> Problem:
    """Read a problem by name (``problems/<name>.toml``) or path, validating every key against
    its kind's schema; ``overrides`` change settings by name (``tube="2x"``, ``max_iter=4``,
    ``options={"friction": 0.5}``), checked the same way."""
    path = _resolve(name_or_path)
    data = _read_toml(path)
    where = str(path)
    for key in _COMMON:
        if key in data and not (isinstance(data[key], str) and (data[key] or key == "description")):
            raise ProblemError(f"{where}: key '{key}' must be a non-empty string, got {data[key]!r}")
    if "name" in data:
        check_name(data["name"], f"{where}: key 'name'")
    if "kind" not in data:
        raise ProblemError(f"{where}: missing key 'kind'; known kinds: {', '.join(sorted(KINDS))}")
    if data["kind"] not in KINDS:
        raise ProblemError(f"{where}: key 'kind': unknown kind {data['kind']!r}; known: {', '.join(sorted(KINDS))}")
    schema = KINDS[data["kind"]].schema
    problem = Problem(name=data.get("name", path.stem), schema=schema, settings=schema.parse(data, where, ignore=_COMMON),
                      description=data.get("description", ""), source=str(path))
    return problem.replace(**overrides) if overrides else checked(problem, where)


def problem_from_dict(data: dict[str, Any]) -> Problem:
    """Inverse of :meth:`Problem.to_dict`, every setting checked again (a sweep task on a worker)."""
    where = f"problem {data.get('name')!r}"
    schema = kind_of(data["kind"]).schema
    settings = schema.resolve(schema.checked(data["settings"], where), where)
    return checked(Problem(name=data["name"], schema=schema, settings=settings,
                           description=data.get("description", ""), source=data.get("source", "")), where)
