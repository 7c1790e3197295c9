"""The one root of latentoc's errors: every error about the user's input derives from
:class:`LatentocError`, and the CLI shows it as ``latentoc: error: ...`` (exit code 2).
Anything else that escapes is a bug: the CLI shows its traceback and exits with code 1.

The tree (the domain errors live beside the code that raises them)::

    LatentocError
    ├── ProblemError        a problem file or override (latentoc.problem.declaration)
    ├── SolveError          a solve's arguments, or a provably infeasible tube (latentoc.solve)
    ├── ResultFileError     a result folder that cannot be read (latentoc.results)
    ├── OutputError         an output folder that cannot be written (latentoc.runtime.files)
    ├── SweepError          a sweep's tubes, workers or failed tasks (latentoc.sweep)
    ├── SimulationError     a replay's settings, or a model or result MuJoCo cannot replay (latentoc.simulate)
    ├── GPDMInputError      training data or GPDM settings (latentoc.gpdm)
    ├── MocapFormatError    a malformed ASF/AMC file (latentoc.mocap)
    ├── UnknownRobotError   a robot name (latentoc.robots)
    └── SplineInputError    spline settings or data (latentoc.latent.spline)

Input errors that are about a value also derive from :class:`ValueError` (``UnknownRobotError``
from :class:`LookupError`), so ``except ValueError`` around a call keeps working.
"""
from __future__ import annotations

__all__ = ["LatentocError", "ProblemError", "SolveError", "ResultFileError", "SweepError", "SimulationError",
           "ArgumentError"]


class LatentocError(Exception):
    """Input latentoc cannot use: a problem file, motion, robot, model or setting."""


class ProblemError(LatentocError, ValueError):
    """A problem declaration that cannot be used (file, key and reason in the message)."""


class SolveError(LatentocError, ValueError):
    """Input that cannot be solved (bad parameter or a provably infeasible tube)."""


class ResultFileError(LatentocError, ValueError):
    """A result folder that is missing, incomplete, or of another schema version."""


class SweepError(LatentocError):
    """A sweep that cannot run (no Dask installed, no scheduler) or whose tasks failed."""


class SimulationError(LatentocError, ValueError):
    """A physics replay that cannot run: its gains or settings, or a model or result it cannot take."""


class ArgumentError(LatentocError, ValueError):
    """An argument of a public function or a command of the wrong type or outside its range (the
    argument and what it must be in the message)."""
