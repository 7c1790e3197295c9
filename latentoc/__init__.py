"""latentoc: motion optimization in a learned GPDM latent space (Kang & Park 2015).

The public API (docs/api.md)::

    import latentoc
    problem = latentoc.load_problem("arm-raise", tube="2x")
    result = latentoc.solve(problem)          # a Result: result.gain_pct, result.trajectory["q"], ...
    result.save("out/arm-raise")              # result.json, trajectory.npz, gpdm.npz
    again = latentoc.load_result("out/arm-raise")
    sweep = latentoc.sweep(problem, ["2x", "5x"], executor=None)  # or a dask.distributed Client

Every error about the input is a :class:`LatentocError`. The names are imported at their first use
(``python -m latentoc --help`` loads none of them).
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from latentoc.version import __version__

#: public name -> the module that defines it
_WHERE = {"solve": "api", "SymbolicModel": "dynamics", "LatentocError": "errors", "GPDM": "gpdm",
          "GPDMSettings": "gpdm", "learn_gpdm": "gpdm", "Problem": "problem.declaration",
          "load_problem": "problem.toml_files", "problem_names": "problem.toml_files", "Result": "results",
          "load_result": "results", "load_robot": "robots", "SweepResult": "sweeps", "sweep": "sweeps"}

__all__ = ["__version__", "load_problem", "problem_names", "Problem", "solve", "Result", "load_result", "sweep",
           "SweepResult", "learn_gpdm", "GPDM", "GPDMSettings", "load_robot", "SymbolicModel", "LatentocError"]


def __getattr__(name: str) -> Any:
    if name not in _WHERE:
        raise AttributeError(f"module 'latentoc' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:
    from latentoc.api import solve
    from latentoc.dynamics import SymbolicModel
    from latentoc.errors import LatentocError
    from latentoc.gpdm import GPDM, GPDMSettings, learn_gpdm
    from latentoc.problem.declaration import Problem
    from latentoc.problem.toml_files import load_problem, problem_names
    from latentoc.results import Result, load_result
    from latentoc.robots import load_robot
    from latentoc.sweeps import SweepResult, sweep
