"""A problem as declared: what to optimise, never how (:class:`Problem`).

A problem is a kind's settings, resolved: every key of the kind's
:class:`~latentoc.problem.schema.Schema` with its value (the file's, an override's or the default),
readable by name (``problem.tube``). Problems are read from TOML files by
:func:`latentoc.problem.toml_files.load_problem`; a change (:meth:`Problem.replace`) is checked like
the file's keys and the kind's checks across settings. Errors are
:class:`~latentoc.errors.ProblemError` naming the file and key.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from latentoc.errors import ProblemError, SolveError
from latentoc.problem.schema import Schema

__all__ = ["Problem", "check_name", "checked", "apply_overrides", "describe_problem"]


@dataclass(frozen=True)
class Problem:
    """A problem of the kind ``schema`` declares, its settings resolved (``settings``, by name, also
    readable as attributes: ``problem.tube``). Change settings with :meth:`replace`, which checks
    them."""

    name: str
    schema: Schema = field(repr=False)
    settings: dict[str, Any] = field(default_factory=dict)
    description: str = ""
    source: str = ""

    @property
    def kind(self) -> str:
        """The kind's name (``"latent-min-torque"``, ``"broad-jump"``)."""
        return self.schema.kind

    def __getattr__(self, name: str) -> Any:
        settings = self.__dict__.get("settings", {})
        if name in settings:
            return settings[name]
        schema = self.__dict__.get("schema")
        raise AttributeError(f"a {getattr(schema, 'kind', '?')} problem has no setting {name!r}")

    def replace(self, **overrides: Any) -> Problem:
        """A copy with settings changed by name (a table's, e.g. ``options``, merged), checked
        like the file's keys."""
        name = check_name(overrides.pop("name", self.name), f"problem {self.name!r}: name")
        settings = self.schema.override(self.settings, overrides, f"problem {self.name!r}")
        return checked(Problem(name=name, schema=self.schema, settings=settings, description=self.description,
                               source=self.source), f"problem {name!r}")

    def validate(self) -> Problem:
        """This problem with every setting checked again, as the file's keys are (a ProblemError
        naming the key): its ``settings`` dict may have been changed in place since it was loaded."""
        return self.replace(**self.settings)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: name, kind, description, source and every setting (read back by
        :func:`latentoc.problem.toml_files.problem_from_dict`)."""
        return {"name": self.name, "kind": self.kind, "description": self.description, "source": self.source,
                "settings": dict(self.settings)}


def check_name(name: object, where: str) -> str:
    """A problem's name as it names output folders (``out/<name>-latent``): a ProblemError unless it
    is a plain file name: no path separator, not "." or "..", no control character, at most 200."""
    if not isinstance(name, str) or not name or name in (".", "..") or len(name) > 200 \
            or any(c in name for c in "/\\") or any(ord(c) < 32 or ord(c) == 127 for c in name):
        raise ProblemError(f"{where} = {name!r} must be a plain name: it names output folders, so no '/', "
                           "'\\', '.' or '..', no control characters, at most 200 characters")
    return name


def checked(problem: Problem, where: str) -> Problem:
    """``problem`` after its kind's checks across settings (its schema's ``check``)."""
    if problem.schema.check is not None:
        problem.schema.check(problem, where)
    return problem


def apply_overrides(problem: Problem, overrides: dict[str, Any]) -> Problem:
    """``problem`` with the settings in ``overrides`` that are not None; a SolveError if wrong."""
    given = {k: v for k, v in overrides.items() if v is not None}
    if not given:
        return problem
    try:
        return problem.replace(**given)
    except ProblemError as exc:
        raise SolveError(str(exc)) from None


def describe_problem(problem: Problem) -> str:
    """Every resolved setting of ``problem``, one ``key = value  # what`` line each."""
    lines = [f"# {problem.name} ({problem.kind}): {problem.description}", f"# from {problem.source}"]
    for key, value, doc in problem.schema.describe(problem.settings):
        lines.append(f"{key} = {json.dumps(value)}".ljust(40) + f"  # {doc}")
    return "\n".join(lines)
