"""AMC frames -> configurations q of the model from :mod:`.skeleton_model` (no IK).

Joint ``<bone>_<dof>`` gets exactly the AMC value in radians; the free-flyer gets the
root translation (converted to metres, rotated to world by ``P``) and the root rotation
``P @ C_root @ M_root @ inv(C_root) @ P.T`` with ``M_root`` composed from RX RY RZ in
the root ``axis`` order (XYZ -> Rz Ry Rx).
"""
from __future__ import annotations

import numpy as np
import pinocchio as pin

from latentoc.mocap.amc import Motion
from latentoc.mocap.asf import Skeleton
from latentoc.mocap.skeleton_model import P_ASF_TO_WORLD, euler_matrix, joint_q_index


def root_pose(skeleton: Skeleton, root_values: np.ndarray, degrees: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """World position (m) and rotation matrix of the root for one AMC root line."""
    order = skeleton.root.order
    vals = dict(zip(order, root_values))
    T = np.array([vals["TX"], vals["TY"], vals["TZ"]])
    ang = np.array([vals["RX"], vals["RY"], vals["RZ"]])
    if not degrees:
        ang = np.rad2deg(ang)
    Cr = euler_matrix(skeleton.root.orientation, skeleton.root.axis)
    Mr = euler_matrix(ang, skeleton.root.axis)
    G = Cr @ Mr @ Cr.T
    P = P_ASF_TO_WORLD
    pos = P @ (skeleton.root.position + T) * skeleton.unit_to_m
    return pos, P @ G @ P.T


def motion_to_q(model: pin.Model, skeleton: Skeleton, motion: Motion,
                frames: np.ndarray | slice | None = None) -> np.ndarray:
    """Configurations (n_frames, nq) for ``motion`` (optionally a subset of frames)."""
    idx = np.arange(motion.n_frames)[frames if frames is not None else slice(None)]
    idx = np.atleast_1d(idx)
    n = len(idx)
    Q = np.zeros((n, model.nq))
    jq = joint_q_index(model)
    conv = np.deg2rad if motion.degrees else (lambda x: x)
    for bn, b in skeleton.bones.items():
        vals = motion.channels[bn]
        for k, d in enumerate(b.dof):
            name = f"{bn}_{d}"
            if name in jq:
                Q[:, jq[name]] = conv(vals[idx, k])
    if model.joints[1].nq == 7:
        rv = motion.channels["root"][idx]
        for i in range(n):
            pos, R = root_pose(skeleton, rv[i], motion.degrees)
            Q[i, :3] = pos
            Q[i, 3:7] = pin.Quaternion(R).normalized().coeffs()  # x y z w
    return Q
