"""The running costs L of a fixed-base motion (Eq. 22: J = int_0^T L dt) and the joint-velocity rows.

Each objective is a robot block (:mod:`latentoc.nlp.blocks`) of the joint motion (y, yd, ydd)
and, for the exchange's 1 kHz check and the reported cost, the same integrand in numpy:

* ``"torque"``: L = |tau|^2 with tau = RNEA(y, yd, ydd) (Eq. 1-2), the paper's minimum torque;
* ``"energy"``: L = sqrt((tau . yd)^2 + eps^2) - eps, the mechanical power |tau . qdot| made
  smooth where it changes sign (within eps W of |tau . qdot| everywhere);
* ``"acceleration"``: L = |ydd|^2.

Squared joint jerk is not offered: the GP layer gives the joint motion up to ydd (Eq. 26-28).
With torque limits the block also outputs tau, so RNEA runs once per node for both.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import casadi as ca
import numpy as np

from latentoc.dynamics import SymbolicModel
from latentoc.nlp.blocks import RobotBlock, block_inputs

__all__ = ["RUNNING_COSTS", "Objective", "velocity_block"]

#: objective name -> what its cost J means (the result's cost_meaning)
RUNNING_COSTS = {
    "torque": "integral of |tau|^2 dt, N^2 m^2 s (minimised, Eq. 22)",
    "energy": "integral of sqrt((tau . qdot)^2 + eps^2) - eps dt, J: mechanical energy |tau . qdot| made smooth "
              "(minimised)",
    "acceleration": "integral of |qddot|^2 dt, rad^2 s^-3 (minimised)",
}


@dataclass(frozen=True)
class Objective:
    """A running cost L (module doc); ``epsilon`` (W) smooths ``"energy"``."""

    name: str = "torque"
    epsilon: float = 0.1

    def __post_init__(self) -> None:
        if self.name not in RUNNING_COSTS:
            raise ValueError(f"unknown objective {self.name!r}; choose one of {', '.join(RUNNING_COSTS)}")
        if not self.epsilon > 0:
            raise ValueError(f"the energy's smoothing epsilon must be positive, got {self.epsilon!r}")

    @property
    def meaning(self) -> str:
        return RUNNING_COSTS[self.name].replace("eps", f"eps (eps = {self.epsilon:g} W)") if self.name == "energy" \
            else RUNNING_COSTS[self.name]

    def _L(self, tau, yd, ydd, sqrt, dot, sumsqr):
        if self.name == "torque":
            return sumsqr(tau)
        if self.name == "energy":
            return sqrt(dot(tau, yd) ** 2 + self.epsilon ** 2) - self.epsilon
        return sumsqr(ydd)

    def block(self, model: SymbolicModel, latent_dim: int, with_torques: bool = False) -> RobotBlock:
        """The block L (rows (L, tau) ``with_torques``) at a node of the joint motion."""
        y, yd, ydd, r = block_inputs(model.nv, 0)
        tau = model.rnea(y, yd, ydd)
        L = self._L(tau, yd, ydd, ca.sqrt, ca.dot, ca.sumsqr)
        parts = {"L": L, "tau": tau} if with_torques else {"L": L}
        # the torque block keeps its name (and so its compiled libraries in the cache)
        stem = {"torque": "min_torque", "energy": f"min_energy_{self.epsilon:g}", "acceleration": "min_accel"}
        name = re.sub(r"\W", "_", stem[self.name].replace(".", "p")) + ("_L_tau" if with_torques else "_L")
        return RobotBlock.from_parts(name, (y, yd, ydd, r), parts, latent_dim)

    def integrand(self, tau: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """L at each sample of a motion (rows of tau, v, a)."""
        return self._L(tau, v, a, np.sqrt, lambda x, y: np.sum(x * y, axis=1),
                       lambda x: np.sum(x * x, axis=1))


def velocity_block(nv: int, latent_dim: int) -> RobotBlock:
    """The rows yd (the joint velocities) at a node, for the velocity limits."""
    y, yd, ydd, r = block_inputs(nv, 0)
    return RobotBlock.from_parts("joint_velocity", (y, yd, ydd, r), {"v": yd}, latent_dim)
