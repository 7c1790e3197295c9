"""The transcription settings of a minimum-torque problem: spline, node densities, limits, cost, goal."""
from __future__ import annotations

from dataclasses import dataclass

import pinocchio as pin

from latentoc.problem.declaration import Problem
from latentoc.latent.spline import BSpline
from latentoc.min_torque.goal import EndGoal
from latentoc.min_torque.limits import Limits
from latentoc.min_torque.objectives import Objective

__all__ = ["MinTorqueSettings"]


@dataclass(frozen=True)
class MinTorqueSettings:
    """The transcription: spline size and boundary, node densities per knot interval, limits."""

    duration: float
    control_points: int = 9
    spline_degree: int = 3
    boundary: str = "rest"
    quadrature_points: int = 8
    constraint_points: int = 24
    joint_limits: bool = True
    torque_limits: tuple[float, ...] | str = ()  # or "urdf": the model's effort limits
    velocity_limits: bool = False
    objective: Objective = Objective()
    goal: EndGoal | None = None

    @classmethod
    def from_problem(cls, problem: Problem, control_points: int | None = None,
                     duration: float | None = None) -> "MinTorqueSettings":
        """The settings a :class:`~latentoc.problem.declaration.Problem` declares (``control_points`` overrides m,
        ``duration`` the problem's when it gives none)."""
        m = problem.control_points if control_points is None else control_points
        T = problem.duration if problem.duration is not None else duration
        if T is None:
            raise ValueError("the problem gives no duration: pass the training motion's")
        goal = None
        if problem.settings.get("goal_frame") is not None:
            goal = EndGoal(problem.goal_frame, tuple(problem.goal_position), problem.goal_tolerance)
        limits = problem.torque_limits
        return cls(duration=float(T), control_points=int(m), spline_degree=problem.spline_degree,
                   boundary=problem.boundary, quadrature_points=problem.quadrature_points,
                   constraint_points=problem.constraint_points, joint_limits=problem.joint_limits,
                   torque_limits=limits if isinstance(limits, str) else tuple(limits),
                   velocity_limits=problem.settings.get("velocity_limits", False),
                   objective=Objective(problem.settings.get("objective", "torque"),
                                       problem.settings.get("energy_epsilon", Objective.epsilon)), goal=goal)

    def limits(self, model: pin.Model) -> Limits:
        """The limits these settings switch on, from ``model``."""
        return Limits.of(model, self.joint_limits, self.velocity_limits, self.torque_limits)

    def spline(self) -> BSpline:
        return BSpline(self.control_points, self.duration, self.spline_degree)
