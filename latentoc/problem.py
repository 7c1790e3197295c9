"""Problem declarations: what to optimise, never how.

A problem is a TOML file in ``problems/`` (``arm-raise`` -> ``problems/arm-raise.toml``) or any
path to a ``.toml`` file. Three top-level keys are common to every kind::

    name = "arm-raise"            # defaults to the file stem
    description = "..."
    kind = "latent-min-torque"    # a key of KIND_MODULES

Every other key belongs to the kind's :class:`~latentoc.schema.Schema` (its module's ``SCHEMA``:
``latentoc.min_torque_problem`` for ``latent-min-torque``, ``latentoc.jump.problem`` for
``broad-jump``), which gives each key's type, range and default. A key the kind does not
declare is an error naming it and the allowed ones; ``python -m latentoc show PROBLEM`` prints
every resolved setting. Errors are :class:`~latentoc.errors.ProblemError` naming the file and key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from importlib import import_module
from pathlib import Path
from typing import Any

from .errors import ProblemError
from .paths import data_dir
from .schema import Check, Schema

__all__ = ["Problem", "ProblemError", "load_problem", "problem_names", "problems_dir", "KIND_MODULES",
           "kind_schema", "parse_tube", "describe_problem", "TUBE", "check_name"]

#: problem kind -> the module declaring its ``SCHEMA`` and registering its solver
KIND_MODULES: dict[str, str] = {"latent-min-torque": "latentoc.min_torque_problem",
                                "broad-jump": "latentoc.jump.problem"}

_COMMON = ("name", "description", "kind")


@dataclass(frozen=True)
class Problem:
    """A problem as declared: its kind's settings resolved (``settings``, by name, also readable
    as attributes: ``problem.tube``). Change settings with :meth:`replace`, which checks them."""

    name: str
    kind: str
    settings: dict[str, Any] = field(default_factory=dict)
    description: str = ""
    source: str = ""

    def __getattr__(self, name: str) -> Any:
        settings = self.__dict__.get("settings", {})
        if name in settings:
            return settings[name]
        raise AttributeError(f"a {self.__dict__.get('kind')} problem has no setting {name!r}")

    @property
    def schema(self) -> Schema:
        return kind_schema(self.kind)

    def replace(self, **overrides: Any) -> Problem:
        """A copy with settings changed by name (a table's, e.g. ``options``, merged), checked
        like the file's keys."""
        name = check_name(overrides.pop("name", self.name), f"problem {self.name!r}: name")
        settings = self.schema.override(self.settings, overrides, f"problem {self.name!r}")
        return _checked(Problem(name=name, kind=self.kind, settings=settings, description=self.description,
                                source=self.source), f"problem {name!r}")

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: name, kind, description, source and every setting."""
        return {"name": self.name, "kind": self.kind, "description": self.description, "source": self.source,
                "settings": dict(self.settings)}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Problem:
        """Inverse of :meth:`to_dict`, every setting checked again (a sweep task on a worker)."""
        where = f"problem {data.get('name')!r}"
        schema = kind_schema(data["kind"])
        settings = schema.resolve(schema.checked(data["settings"], where), where)
        return _checked(cls(name=data["name"], kind=data["kind"], settings=settings,
                            description=data.get("description", ""), source=data.get("source", "")), where)


def check_name(name: object, where: str) -> str:
    """A problem's name as it names output folders (``out/<name>-latent``): a ProblemError unless it
    is a plain file name: no path separator, not "." or "..", no control character, at most 200."""
    if not isinstance(name, str) or not name or name in (".", "..") or len(name) > 200 \
            or any(c in name for c in "/\\") or any(ord(c) < 32 or ord(c) == 127 for c in name):
        raise ProblemError(f"{where} = {name!r} must be a plain name: it names output folders, so no '/', "
                           "'\\', '.' or '..', no control characters, at most 200 characters")
    return name


def _checked(problem: Problem, where: str) -> Problem:
    """``problem`` after its kind's checks across settings (the module's ``check_problem``)."""
    check = getattr(import_module(KIND_MODULES[problem.kind]), "check_problem", None)
    if check is not None:
        check(problem, where)
    return problem


def kind_schema(kind: str) -> Schema:
    """The schema of a problem kind (importing the module that declares it)."""
    if kind not in KIND_MODULES:
        raise ProblemError(f"unknown problem kind {kind!r}; known kinds: {', '.join(sorted(KIND_MODULES))}")
    schema: Schema = import_module(KIND_MODULES[kind]).SCHEMA
    return schema


def parse_tube(spec: float | int | str) -> tuple[float, bool]:
    """A tube spec as (value, relative): ``1e-3`` -> (1e-3, False); ``"1.5x"`` -> (1.5, True).

    Raises :class:`ProblemError` (a ValueError) for anything else, zero or negative values.
    """
    if isinstance(spec, bool):
        raise ProblemError(f"tube {spec!r} is not a number")
    if isinstance(spec, (int, float)):
        value, relative = float(spec), False
    elif isinstance(spec, str):
        s = spec.strip().lower()
        relative = s.endswith("x")
        try:
            value = float(s[:-1] if relative else s)
        except ValueError:
            raise ProblemError(f'tube {spec!r} is neither a number nor a relative spec like "1.5x"') from None
    else:
        raise ProblemError(f"tube {spec!r} is not a number")
    if not math.isfinite(value) or value <= 0:
        raise ProblemError(f"tube {spec!r} must be positive (delta bounds sigma^2 >= 0 from above)")
    return value, relative


def _tube_spec(v: Any) -> float | str:
    parse_tube(v)
    return v if isinstance(v, str) else float(v)


#: the check of a tube setting: a positive number (absolute delta) or "<k>x"
TUBE = Check(_tube_spec, 'a positive number or a relative tube like "1.5x"')


def problems_dir() -> Path:
    """The folder of the packaged problem declarations."""
    return data_dir("problems")


def problem_names() -> list[str]:
    """Names of the packaged problems (file stems of ``problems/*.toml``)."""
    return sorted(p.stem for p in problems_dir().glob("*.toml"))


def _resolve(name_or_path: str | Path) -> Path:
    text = str(name_or_path)
    path = Path(text)
    if text.endswith(".toml") or path.is_file() or "/" in text:
        if not path.is_file():
            raise ProblemError(f"problem file {text} does not exist")
        return path
    candidate = problems_dir() / f"{text}.toml"
    if not candidate.is_file():
        raise ProblemError(f"unknown problem {text!r}; known problems: {', '.join(problem_names())}")
    return candidate


def load_problem(name_or_path: str | Path, **overrides: Any) -> Problem:
    """Read a problem by name (``problems/<name>.toml``) or path, validating every key against
    its kind's schema; ``overrides`` change settings by name (``tube="2x"``, ``max_iter=4``,
    ``options={"friction": 0.5}``), checked the same way."""
    path = _resolve(name_or_path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ProblemError(f"{path}: not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ProblemError(f"{path}: not UTF-8 text, as TOML must be ({exc})") from None
    except OSError as exc:
        raise ProblemError(f"{path}: cannot be read: {exc}") from None
    where = str(path)
    for key in _COMMON:
        if key in data and not (isinstance(data[key], str) and (data[key] or key == "description")):
            raise ProblemError(f"{where}: key '{key}' must be a non-empty string, got {data[key]!r}")
    if "name" in data:
        check_name(data["name"], f"{where}: key 'name'")
    if "kind" not in data:
        raise ProblemError(f"{where}: missing key 'kind'; known kinds: {', '.join(sorted(KIND_MODULES))}")
    if data["kind"] not in KIND_MODULES:
        raise ProblemError(f"{where}: key 'kind': unknown kind {data['kind']!r}; known: "
                           f"{', '.join(sorted(KIND_MODULES))}")
    schema = kind_schema(data["kind"])
    settings = schema.parse(data, where, ignore=_COMMON)
    problem = Problem(name=data.get("name", path.stem), kind=data["kind"], settings=settings,
                      description=data.get("description", ""), source=str(path))
    return problem.replace(**overrides) if overrides else _checked(problem, where)


def describe_problem(problem: Problem) -> str:
    """Every resolved setting of ``problem``, one ``key = value  # what`` line each."""
    import json

    lines = [f"# {problem.name} ({problem.kind}): {problem.description}", f"# from {problem.source}"]
    for key, value, doc in problem.schema.describe(problem.settings):
        lines.append(f"{key} = {json.dumps(value)}".ljust(40) + f"  # {doc}")
    return "\n".join(lines)
