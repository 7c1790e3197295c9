"""Numeric kinematics shared by the contact checks, the planting and the retargeting."""
from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["point_jacobian"]


def point_jacobian(model: pin.Model, data: pin.Data, frame_id: int, point: np.ndarray) -> np.ndarray:
    """Linear Jacobian (3, nv), world axes, of the world point ``point`` fixed to frame ``frame_id``'s
    body: ``J_v - [p - o]x J_w`` (its velocity is v - (p - o) x w). ``data`` holds the joint
    Jacobians and frame placements."""
    J = pin.getFrameJacobian(model, data, frame_id, pin.LOCAL_WORLD_ALIGNED)
    return J[:3] - pin.skew(np.asarray(point) - data.oMf[frame_id].translation) @ J[3:]
