"""Results built by hand for the tests of the result schema and the plots (no solve)."""
from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.environment import Environment
from latentoc.results import Result, Times
from latentoc.tube import TubeResult


def make_result(model: pin.Model | None = None, n: int = 11, *, tube: float | None = 0.5, method: str = "latent",
                gain: float = 12.5, success: bool = True, trajectory: dict[str, Any] | None = None,
                gpdm: Any = None, **details: Any) -> Result:
    """A Result of ``model`` (default: the human arm at rest for 1 s) with the given fields."""
    if model is None:
        from latentoc.robots import load_robot
        model = load_robot("human-arm")
    t = np.linspace(0.0, 1.0, n)
    q = np.tile(pin.neutral(model), (n, 1))
    arrays = {"t": t, "q": q, "v": np.zeros((n, model.nv)), "a": np.zeros((n, model.nv)),
              "tau": np.zeros((n, model.nv)), "model": np.str_(model.saveToString())}
    arrays.update(trajectory or {})
    tube_result = None if tube is None else TubeResult(spec=f"{tube:g}", delta=tube, relative=10 * tube,
                                                        training=tube / 5, max_sigma2=0.9 * tube)
    return Result(problem="test", kind="latent-min-torque", method=method, status="Solve_Succeeded" if success
                  else "Maximum_Iterations_Exceeded", success=success, iterations=7, cost_initial=2.0,
                  cost=2.0 * (1 - gain / 100), gain_pct=gain, cost_meaning="test cost", times=Times(solve_s=0.25),
                  tube=tube_result, violations={"tube": 0.0}, environment=Environment.current(),
                  settings={"latent_dim": 3}, details=details, trajectory=arrays, gpdm=gpdm)
