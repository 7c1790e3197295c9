"""latentoc: motion optimization in a learned GPDM latent space (Kang & Park 2015).

The public API (docs/api.md)::

    import latentoc
    problem = latentoc.load_problem("arm-raise", tube="2x")
    result = latentoc.solve(problem)          # a Result: result.gain_pct, result.trajectory["q"], ...
    result.save("out/arm-raise")              # result.json, trajectory.npz, gpdm.npz
    again = latentoc.load_result("out/arm-raise")
    sweep = latentoc.sweep(problem, ["2x", "5x"], executor=None)  # or a dask.distributed Client

Every error about the input is a :class:`LatentocError`.
"""

from .version import __version__

from .api import solve
from .dynamics import SymbolicModel
from .errors import LatentocError
from .gpdm import GPDM, GPDMSettings, learn_gpdm
from .problem import Problem
from .problem_files import load_problem, problem_names
from .results import Result, load_result
from .robots import load_robot
from .tube_sweep import SweepResult, sweep

__all__ = ["__version__", "load_problem", "problem_names", "Problem", "solve", "Result", "load_result", "sweep",
           "SweepResult", "learn_gpdm", "GPDM", "GPDMSettings", "load_robot", "SymbolicModel", "LatentocError"]
