"""Build a :class:`pinocchio.Model` from an Acclaim skeleton (Kang & Park 2015, Sect. 4.2).

Conventions
-----------
* World frame is Z up (gravity -z).  ASF files are Y up; a fixed proper rotation
  ``P`` maps ASF axes to world: ``world = P @ asf = (asf_z, asf_x, asf_y)``, so the
  CMU subject faces world +x, its left is world +y and up is world +z.
* Acclaim kinematics (column vectors): the global rotation of bone ``b`` is
  ``G_b = G_parent @ C_b @ M_b @ inv(C_b)``, where ``C_b`` is the ``axis`` rotation
  (for order ``XYZ``: ``Rz(az) @ Ry(ay) @ Rx(ax)``, X applied first) and ``M_b`` the dof
  rotations, first listed dof applied first (``rx ry rz`` -> ``Rz(rz) @ Ry(ry) @ Rx(rx)``).
  Bone ``b`` starts at the end of its parent and ends at
  ``start + G_b @ direction_b * length_b``; the root's children start at the root.
* The body frame of bone ``b`` is ``P @ G_b @ C_b`` in world (its own axis frame), so
  each dof is a revolute joint about a body axis (``JointModelRX/RY/RZ``) and the joint
  angle in radians equals the AMC value.  Because ``M = ... Ry Rx`` the chain is built
  last dof first: for ``rx ry rz`` the joints are ``<bone>_rz``, ``<bone>_ry``,
  ``<bone>_rx`` in that order (see :func:`joint_q_index`).
* The root is a free-flyer whose frame is world-aligned at rest: its pose is
  ``(P @ (position + T) * unit, P @ G_root @ P.T)``.
* Bones without dof are fixed bodies merged into their parent joint (a ``FIXED_JOINT``
  frame plus a ``BODY`` frame).  Every bone has a ``BODY`` frame ``<bone>`` and an
  ``OP_FRAME`` ``<bone>_end`` at its end point.

Sizes for CMU subject 01: 31 links (BODY frames: root + 30 bones).  The paper's
"62 degrees of freedom" include the 6 of the root: the ASF bones carry 56 revolute
dofs (lhipjoint/rhipjoint have none), so the model has nq = 56 + 7 = 63, nv = 62.
Revolute joints of a multi-dof bone before the last are massless.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np
import pinocchio as pin

from latentoc.mocap.asf import Skeleton

#: Proper rotation from ASF axes (Y up) to world axes (Z up): world = P @ asf.
P_ASF_TO_WORLD = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def axis_rotation(axis: str, angle: float) -> np.ndarray:
    """Rotation matrix about ``'x'``, ``'y'`` or ``'z'`` by ``angle`` radians."""
    c, s = np.cos(angle), np.sin(angle)
    a = axis.lower()
    if a == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if a == "y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    if a == "z":
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    raise ValueError(f"unknown axis {axis!r}")


def euler_matrix(angles_deg: np.ndarray, order: str) -> np.ndarray:
    """Acclaim ``axis`` rotation: first letter of ``order`` applied first (XYZ -> Rz Ry Rx)."""
    R = np.eye(3)
    for letter in order.upper():
        R = axis_rotation(letter, np.deg2rad(angles_deg["XYZ".index(letter)])) @ R
    return R


def dof_matrix(dofs: list[str], values_rad: np.ndarray) -> np.ndarray:
    """Acclaim motion rotation M: first listed dof applied first."""
    R = np.eye(3)
    for d, v in zip(dofs, values_rad):
        R = axis_rotation(d[1], v) @ R
    return R


_JOINTS = {"x": pin.JointModelRX, "y": pin.JointModelRY, "z": pin.JointModelRZ}


def _add_base(model: pin.Model, fixed_base: bool, base_placement: pin.SE3 | None, root_inertia: pin.Inertia | None,
              lowers: list[float], uppers: list[float]) -> tuple[int, pin.SE3, int]:
    """The base the first bones attach to: (joint, placement, frame): the world (at
    ``base_placement``) or a free-flyer ``root`` with ``root_inertia``."""
    if fixed_base:
        return 0, base_placement if base_placement is not None else pin.SE3.Identity(), 0
    base_joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    lowers += [-np.inf] * 7
    uppers += [np.inf] * 7
    jf0 = model.addJointFrame(base_joint, 0)
    base_frame = model.addBodyFrame("root", base_joint, pin.SE3.Identity(), jf0)
    if root_inertia is not None:
        model.appendBodyToJoint(base_joint, root_inertia, pin.SE3.Identity())
    return base_joint, pin.SE3.Identity(), base_frame


def _add_bone(model: pin.Model, bn: str, dofs: list[str], limits: list[tuple[float, float]], inertia: pin.Inertia,
              parent: tuple[int, pin.SE3, int], lowers: list[float], uppers: list[float]) -> tuple[int, pin.SE3, int]:
    """Bone ``bn``: a revolute joint per free dof (``limits`` in degrees, in the order added:
    reversed dofs) or a fixed frame, and its body; returns its (joint, body placement, frame)."""
    pj, placement, pf = parent
    if not dofs:
        jf = model.addFrame(pin.Frame(f"{bn}_joint", pj, pf, placement, pin.FrameType.FIXED_JOINT))
        fid = model.addFrame(pin.Frame(bn, pj, jf, placement, pin.FrameType.BODY))
        model.appendBodyToJoint(pj, inertia, placement)
        return pj, placement, fid
    jid, jp, jf = pj, placement, pf
    for d, (lo, hi) in zip(reversed(dofs), limits):
        jid = model.addJoint(jid, _JOINTS[d[1]](), jp, f"{bn}_{d}")
        jp = pin.SE3.Identity()
        lowers.append(np.deg2rad(lo))
        uppers.append(np.deg2rad(hi))
        jf = model.addJointFrame(jid, jf)
    fid = model.addBodyFrame(bn, jid, pin.SE3.Identity(), jf)
    model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
    return jid, pin.SE3.Identity(), fid


def build_model(skeleton: Skeleton,
                inertias: Mapping[str, pin.Inertia] | None = None,
                root_inertia: pin.Inertia | None = None,
                bones: list[str] | None = None,
                fixed_base: bool = False,
                base_placement: pin.SE3 | None = None,
                locked: Mapping[str, list[str]] | None = None,
                name: str = "cmu") -> pin.Model:
    """Pinocchio model of ``skeleton`` (see the module docstring for conventions).

    ``inertias`` maps bone name -> spatial inertia in that bone's body frame.
    ``bones`` restricts the model to a connected subset (the first one is attached to
    the base); with ``fixed_base`` the base is the world itself, otherwise a free-flyer
    named ``root``.  ``locked`` lists dofs per bone that are frozen at zero (the bone
    keeps its geometry).  Joint limits are the ASF ``limits`` in radians.
    """
    inertias = dict(inertias or {})
    locked = {k: list(v) for k, v in (locked or {}).items()}
    u = skeleton.unit_to_m
    P = P_ASF_TO_WORLD
    model = pin.Model()
    model.name = name
    model.gravity = pin.Motion(np.array([0, 0, -9.81, 0, 0, 0]))
    order = skeleton.topological_order()
    if bones is not None:
        keep = set(bones)
        order = [b for b in order if b in keep]
    C = {n: euler_matrix(b.axis, b.axis_order) for n, b in skeleton.bones.items()}
    lowers: list[float] = []
    uppers: list[float] = []
    # (joint id, body frame placement in joint frame, frame id) per bone
    attach: dict[str, tuple[int, pin.SE3, int]] = {}
    base = _add_base(model, fixed_base, base_placement, root_inertia, lowers, uppers)
    for bn in order:
        b = skeleton.bones[bn]
        par = b.parent
        if par is not None and par in attach:
            pj, pM, pf = attach[par]
            Cp = C[par]
            pb = skeleton.bones[par]
            placement = pM * pin.SE3(Cp.T @ C[bn], Cp.T @ (pb.direction * pb.length * u))
        else:  # attached to the base (root child, or first bone of a sub-chain)
            pj, _, pf = base
            placement = base[1] * pin.SE3(P @ C[bn], np.zeros(3))
        dofs = [d for d in b.dof if d not in locked.get(bn, [])]
        limits = [dict(zip(b.dof, b.limits)).get(d, (-180.0, 180.0)) for d in reversed(dofs)]
        attach[bn] = _add_bone(model, bn, dofs, limits, inertias.get(bn, pin.Inertia.Zero()), (pj, placement, pf),
                               lowers, uppers)
        jid, M, fid = attach[bn]
        end = M * pin.SE3(np.eye(3), C[bn].T @ (b.direction * b.length * u))
        model.addFrame(pin.Frame(f"{bn}_end", jid, fid, end, pin.FrameType.OP_FRAME))
    model.lowerPositionLimit = np.array(lowers)
    model.upperPositionLimit = np.array(uppers)
    if not fixed_base:
        model.lowerPositionLimit[:3] = -np.inf
        model.upperPositionLimit[:3] = np.inf
        model.lowerPositionLimit[3:7] = -1.0
        model.upperPositionLimit[3:7] = 1.0
    return model


def joint_q_index(model: pin.Model) -> dict[str, int]:
    """Map revolute joint name (``<bone>_<dof>``) -> its index in q."""
    return {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)
            if model.joints[j].nq == 1}


def body_frame_names(model: pin.Model) -> list[str]:
    """Names of the BODY frames (the links: root and the bones)."""
    return [f.name for f in model.frames if f.type == pin.FrameType.BODY]
