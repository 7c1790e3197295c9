"""An end-effector goal: a frame's position at the end of the motion, exactly or within a tolerance.

With a goal the motion's end pose is no longer the demonstration's: the last control point
p_m becomes a decision variable (:class:`FreeEndPath`; with ``boundary = "rest"`` p_(m-1) is
tied to it, so the motion still ends at rest), and one row family at t = T holds

* ``tolerance = 0``: p_frame(y(T)) - target = 0 (3 rows);
* ``tolerance > 0``: |p_frame(y(T)) - target|^2 / tolerance^2 <= 1 (one row, relative).

The frame position is Pinocchio's forward kinematics on the joint motion (a robot block of y,
with the target as its node input r), so the goal works in the latent space and in joint space.
"""
from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import pinocchio as pin
import scipy.sparse as sp

from latentoc.dynamics import SymbolicModel
from latentoc.latent import Layer
from latentoc.nlp.assemble import Family
from latentoc.nlp.blocks import RobotBlock, block_inputs
from latentoc.nlp.evaluators import BlockEvaluator
from latentoc.nlp.inputs import NodeInputs
from latentoc.latent.spline_path import SplinePath

__all__ = ["EndGoal", "FreeEndPath", "goal_block", "goal_family", "goal_error"]


@dataclass(frozen=True)
class EndGoal:
    """Frame ``frame`` at ``position`` (world, m) at t = T, within ``tolerance`` m (0: exactly)."""

    frame: str
    position: tuple[float, float, float]
    tolerance: float = 0.0


@dataclass(frozen=True)
class FreeEndPath(SplinePath):
    """A spline path whose last control point is free; the rows ``tied`` equal it."""

    tied: tuple[int, ...] = ()

    @classmethod
    def release_end(cls, path: SplinePath, boundary: str) -> "FreeEndPath":
        """``path`` with p_m free (and p_(m-1) tied to it for ``boundary = "rest"``)."""
        m = path.spline.n_control
        tied = (m - 2,) if boundary == "rest" else ()
        free = np.array(sorted((set(path.free.tolist()) - set(tied)) | {m - 1}), dtype=int)
        return cls(path.spline, path.P_init, free, tied)

    @property
    def index(self) -> np.ndarray:
        index = super().index
        index[list(self.tied)] = index[-1]
        return index

    def control_points(self, w: np.ndarray) -> np.ndarray:
        P = super().control_points(w)
        P[list(self.tied)] = P[-1]
        return P


def goal_block(model: SymbolicModel, frame: str, latent_dim: int) -> RobotBlock:
    """Rows (e, |e|^2) with e = p_frame(y) - r, r the target position (the node input)."""
    y, yd, ydd, r = block_inputs(model.nv, 3)
    e = model.frame_placement(frame)(y)[0] - r
    return RobotBlock.from_parts(f"goal_{frame}", (y, yd, ydd, r), {"e": e, "e2": ca.sumsqr(e)}, latent_dim)


def goal_family(model: SymbolicModel, layer: Layer, path: SplinePath,
                goal: EndGoal) -> tuple[Family, np.ndarray, np.ndarray]:
    """The goal's rows at t = T and their bounds (module doc)."""
    block = goal_block(model, goal.frame, layer.latent_dim)
    ni = NodeInputs(1, path.n_w)
    T = np.array([path.spline.duration])
    ni.spline([path.spline.basis(T, r) for r in range(3)], path.index, path.P_init)
    ni.constant(np.asarray(goal.position, dtype=float)[None, :])
    S, s0 = ni.build()
    if goal.tolerance > 0:
        Cg = sp.csr_matrix(([1.0 / goal.tolerance ** 2], ([0], [3])), shape=(1, 4))
        lb, ub = np.array([-np.inf]), np.array([1.0])
    else:
        Cg = sp.csr_matrix((np.ones(3), (np.arange(3), np.arange(3))), shape=(3, 4))
        lb, ub = np.zeros(3), np.zeros(3)
    return Family("goal", BlockEvaluator(block, layer), S, s0, Cg=Cg), lb, ub


def goal_error(robot: pin.Model, goal: EndGoal, q_end: np.ndarray) -> float:
    """|p_frame(q_end) - target| (m), by numeric forward kinematics."""
    data = robot.createData()
    pin.framesForwardKinematics(robot, data, np.asarray(q_end, dtype=float))
    return float(np.linalg.norm(data.oMf[robot.getFrameId(goal.frame)].translation - np.asarray(goal.position)))
