"""The public API: what ``import latentoc`` offers, one error root, and notebooks that use only it."""

import inspect
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

import latentoc
from latentoc import errors

ROOT = Path(__file__).resolve().parents[1]
PUBLIC = {"load_problem", "problem_names", "Problem", "solve", "Result", "load_result", "sweep", "SweepResult",
          "learn_gpdm", "GPDM", "GPDMSettings", "load_robot", "SymbolicModel", "LatentocError", "__version__"}


def test_all_is_the_public_api_and_typed():
    assert set(latentoc.__all__) == PUBLIC and all(hasattr(latentoc, n) for n in PUBLIC)
    assert (ROOT / "latentoc" / "py.typed").is_file()
    for name in ("load_problem", "solve", "load_result", "sweep", "learn_gpdm", "load_robot"):
        sig = inspect.signature(getattr(latentoc, name))
        assert sig.return_annotation is not inspect.Signature.empty, name
        assert all(p.annotation is not inspect.Parameter.empty for p in sig.parameters.values()), name
    assert inspect.isfunction(latentoc.solve) and inspect.isfunction(latentoc.sweep)  # not the modules


def test_version_is_the_project_version():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert latentoc.__version__ == project["version"]
    assert project["requires-python"].startswith(">=3.11")  # tomllib
    assert "distributed" in project["optional-dependencies"]


def test_every_input_error_is_a_latentoc_error():
    from latentoc.gpdm import GPDMInputError
    from latentoc.mocap import MocapFormatError
    from latentoc.robots import UnknownRobotError
    from latentoc.latent.spline import SplineInputError

    for cls in (errors.ProblemError, errors.SolveError, errors.ResultFileError, errors.SweepError, GPDMInputError,
                MocapFormatError, UnknownRobotError, SplineInputError):
        assert issubclass(cls, latentoc.LatentocError), cls
    with pytest.raises(latentoc.LatentocError, match="unknown robot 'r2d2'"):
        latentoc.load_robot("r2d2")
    with pytest.raises(latentoc.LatentocError, match="too few frames"):
        latentoc.learn_gpdm(np.array([[0.0, 1.0]]), latentoc.GPDMSettings(latent_dim=1))
    with pytest.raises(latentoc.LatentocError, match="no result.json"):
        latentoc.load_result(ROOT / "problems")


def _notebook_code(path: Path) -> str:
    cells = json.loads(path.read_text())["cells"]
    return "\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")


@pytest.mark.parametrize("notebook", sorted((ROOT / "notebooks").glob("*.ipynb")), ids=lambda p: p.stem)
def test_notebooks_use_no_underscored_names(notebook):
    """The walkthroughs use what latentoc exports: no ``_name`` imported or reached as an attribute."""
    code = _notebook_code(notebook)
    assert not re.findall(r"import[^\n]*\b_[a-z]\w*|\._[a-z]\w*", code)
    assert "dataclasses.replace" not in code  # settings change through load_problem / Problem.replace
