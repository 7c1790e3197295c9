"""Left/right symmetry of the CMU humanoid for symmetric learning (Kang & Park 2015, Sect. 4.2).

The paper learns only the left half and the centre of the body: of the 62 DOF, the 6
of the base are excluded and the 19 of the right side are copied from the left, leaving
``62 - 19 - 6 = 37`` learned DOF.  For the CMU skeleton this is exactly the 18 spine,
neck and head DOF (lowerback, upperback, thorax, lowerneck, upperneck, head; rx ry rz
each) plus the 19 DOF of the left leg and arm.

Mirroring: the sagittal plane is ASF ``x = 0`` (world ``y = 0``); the reflection is
``S = diag(-1, 1, 1)`` in ASF axes.  A rotation by ``a`` about axis ``w`` reflects to a
rotation by ``-a`` about ``S w``.  For the dof of a left joint about the axis
``C_L e`` (``e`` the unit x, y or z of the bone's axis frame), the right joint's axis is
``C_R e``; with ``s = (C_R e) . (S C_L e)`` (checked to be +-1) the mirrored angle is
``-s * a``.  For CMU this gives: rx keeps its sign, ry and rz flip.
"""
from __future__ import annotations

import copy

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.mocap.asf import Skeleton
from latentoc.mocap.skeleton_model import euler_matrix, joint_q_index

S_ASF = np.diag([-1.0, 1.0, 1.0])
S_WORLD = np.diag([1.0, -1.0, 1.0])
MIRROR_TOLERANCE = 1e-6  # unit-axis dot products: what counts as mirror-image axes
ORIGIN_TOLERANCE = 1e-3  # m: mirror-image joint origins (URDFs print them rounded: the G1's differ by 10 um)


class MirrorError(LatentocError, ValueError):
    """A robot whose joints do not pair into a left/right mirror."""


def _joint_axis(joint: pin.JointModel, name: str) -> np.ndarray:
    """The rotation axis of a revolute joint in its own frame."""
    kind = joint.shortname()
    if kind in ("JointModelRX", "JointModelRY", "JointModelRZ"):
        return np.eye(3)["XYZ".index(kind[-1])]
    if kind == "JointModelRevoluteUnaligned":
        return np.asarray(joint.extract().axis, float)
    raise MirrorError(f"joint {name!r}: a {kind} joint, not a revolute one, cannot be mirrored")


def _factor(a_right: np.ndarray, a_left_mirrored: np.ndarray, what: str) -> float:
    """angle_right = factor * angle_left for the axes a_right and S a_left (module doc)."""
    s = float(a_right @ a_left_mirrored)
    if abs(abs(s) - 1.0) > MIRROR_TOLERANCE:
        raise MirrorError(f"{what}: the axes are not mirror images (dot {s:.3g})")
    return -float(np.sign(s))


def mirror_partner(bone: str, skeleton: Skeleton) -> str | None:
    """Name of the mirror bone (l<->r prefix) or None for a centre bone."""
    if bone[0] in "lr" and len(bone) > 1:
        other = ("r" if bone[0] == "l" else "l") + bone[1:]
        if other in skeleton.bones:
            return other
    return None


def mirror_sign(skeleton: Skeleton, left: str, right: str, dof: str) -> float:
    """Factor f with angle_right = f * angle_left for a mirror pose (see module doc)."""
    bl, br = skeleton.bones[left], skeleton.bones[right]
    e = np.eye(3)["xyz".index(dof[1])]
    a_l = S_ASF @ euler_matrix(bl.axis, bl.axis_order) @ e
    a_r = euler_matrix(br.axis, br.axis_order) @ e
    s = float(a_r @ a_l)
    if abs(abs(s) - 1.0) > 1e-6:
        raise ValueError(f"{left}/{right} {dof}: axes are not mirror images (dot {s:.3g})")
    return -float(np.sign(s))


class SymmetryMap:
    """Map between full humanoid configurations and the learned left+centre coordinates.

    ``learned_names`` lists the joints kept (centre and left, in q order).
    """

    def __init__(self, model: pin.Model, skeleton: Skeleton) -> None:
        jq = joint_q_index(model)
        pairs: dict[str, tuple[str, float]] = {}
        centre: dict[str, float] = {}
        for name in jq:
            bone, dof = name.rsplit("_", 1)
            partner = mirror_partner(bone, skeleton)
            if partner is None:
                centre[name] = mirror_sign(skeleton, bone, bone, dof)
            elif bone.startswith("r"):
                pairs[name] = (f"{partner}_{dof}", mirror_sign(skeleton, partner, bone, dof))
        self._build(model.nq, jq, pairs, centre)

    @classmethod
    def from_joint_names(cls, model: pin.Model, left: str = "left", right: str = "right") -> "SymmetryMap":
        """The map of a robot whose right joints are named as their left partners with ``right`` for
        ``left`` (``left_hip_pitch_joint``, ``leg_left_1_joint``); the factors from the joint axes at
        the neutral pose (module doc, with the world reflection). Raises :class:`MirrorError` naming
        the joint where a partner is missing or the two are not mirror images."""
        d = model.createData()
        pin.forwardKinematics(model, d, pin.neutral(model))
        jq = joint_q_index(model)
        jid = {model.names[j]: j for j in range(1, model.njoints)}
        for j in range(1, model.njoints):
            if model.joints[j].nq > 1 and model.joints[j].shortname() != "JointModelFreeFlyer":
                raise MirrorError(f"joint {model.names[j]!r}: only 1-DOF joints can be mirrored "
                                  f"({model.joints[j].shortname()})")

        def axis(name: str) -> np.ndarray:
            j = jid[name]
            M = d.oMi[j]
            return M.rotation @ _joint_axis(model.joints[j], name)

        def origin(name: str) -> np.ndarray:
            return d.oMi[jid[name]].translation

        pairs: dict[str, tuple[str, float]] = {}
        centre: dict[str, float] = {}
        for name in jq:
            if right in name:
                partner = name.replace(right, left)
                if partner not in jq:
                    raise MirrorError(f"joint {name!r}: no left partner {partner!r}")
                if np.linalg.norm(origin(name) - S_WORLD @ origin(partner)) > ORIGIN_TOLERANCE:
                    raise MirrorError(f"joints {partner!r} and {name!r}: their origins are not mirror images "
                                      f"({origin(partner).round(4)} and {origin(name).round(4)})")
                pairs[name] = (partner, _factor(axis(name), S_WORLD @ axis(partner), f"{partner}/{name}"))
            elif left in name:
                if name.replace(left, right) not in jq:
                    raise MirrorError(f"joint {name!r}: no right partner {name.replace(left, right)!r}")
            else:
                if abs(origin(name)[1]) > ORIGIN_TOLERANCE:
                    raise MirrorError(f"joint {name!r}: a centre joint off the sagittal plane (y = {origin(name)[1]:.4f} m)")
                centre[name] = _factor(axis(name), S_WORLD @ axis(name), name)
        out = cls.__new__(cls)
        out._build(model.nq, jq, pairs, centre)
        return out

    def _build(self, nq: int, jq: dict[str, int], pairs: dict[str, tuple[str, float]], centre: dict[str, float]) -> None:
        """The map from each right joint's (left partner, factor) and each centre joint's factor."""
        self.nq = nq
        names_by_q = sorted(jq, key=lambda n: jq[n])
        self.learned_names: list[str] = [n for n in names_by_q if n not in pairs]
        self.learned_q = np.array([jq[n] for n in self.learned_names], dtype=int)
        self.centre_factor: dict[str, float] = dict(centre)
        ypos = {n: k for k, n in enumerate(self.learned_names)}
        self.copied: list[tuple[int, int, float]] = []  # (right q idx, left y idx, factor)
        self.right_names: list[str] = []
        for name in names_by_q:
            if name in pairs:
                left, f = pairs[name]
                self.copied.append((jq[name], ypos[left], f))
                self.right_names.append(name)
        # full mirror map on q (joint part): q'[i] = factor * q[src]
        self._mirror_src = np.arange(nq)
        self._mirror_fac = np.ones(nq)
        for name, f in self.centre_factor.items():
            self._mirror_fac[jq[name]] = f
        for r_idx, y_idx, f in self.copied:
            l_idx = self.learned_q[y_idx]
            self._mirror_src[r_idx], self._mirror_fac[r_idx] = l_idx, f
            self._mirror_src[l_idx], self._mirror_fac[l_idx] = r_idx, f

    @property
    def n_learned(self) -> int:
        """Number of learned DOF (37 for CMU subject 01)."""
        return len(self.learned_names)

    def to_learned(self, q_full: np.ndarray) -> np.ndarray:
        """Left + centre joint coordinates, shape (..., n_learned); base dropped."""
        return np.asarray(q_full)[..., self.learned_q]

    def to_full(self, y: np.ndarray, base: np.ndarray) -> np.ndarray:
        """Full q (..., nq): learned values, right side mirrored from the left, given base."""
        y = np.asarray(y, dtype=float)
        base = np.asarray(base, dtype=float)
        shape = np.broadcast_shapes(y.shape[:-1], base.shape[:-1])
        q = np.zeros(shape + (self.nq,))
        q[..., :7] = base
        q[..., self.learned_q] = y
        for r_idx, y_idx, f in self.copied:
            q[..., r_idx] = f * y[..., y_idx]
        return q

    def mirror(self, q_full: np.ndarray) -> np.ndarray:
        """Mirror image of full configurations (left<->right, centre ry/rz flipped, base reflected)."""
        q_full = np.asarray(q_full, dtype=float)
        out = q_full[..., self._mirror_src] * self._mirror_fac
        out[..., :7] = mirror_base(q_full[..., :7])
        return out


def mirror_base(base: np.ndarray) -> np.ndarray:
    """Reflect free-flyer poses (..., 7) through the world plane y = 0."""
    base = np.asarray(base, dtype=float)
    out = np.array(base, copy=True)
    out[..., 1] *= -1.0
    # R -> S R S for a quaternion (x, y, z, w): x and z flip
    out[..., 3] *= -1.0
    out[..., 5] *= -1.0
    return out


def symmetrized_skeleton(skeleton: Skeleton) -> Skeleton:
    """A copy with exactly mirror-symmetric geometry (averaged left/right, centre in plane)."""
    sk = copy.deepcopy(skeleton)
    sk.root.position = sk.root.position * np.array([0.0, 1.0, 1.0])
    for name, b in sk.bones.items():
        partner = mirror_partner(name, sk)
        if partner is None:
            d = b.direction * np.array([0.0, 1.0, 1.0])
            b.direction = d / np.linalg.norm(d)
        elif name.startswith("l"):
            r = sk.bones[partner]
            d = 0.5 * (b.direction + S_ASF @ r.direction)
            d /= np.linalg.norm(d)
            length = 0.5 * (b.length + r.length)
            b.direction, r.direction = d, S_ASF @ d
            b.length = r.length = length
    return sk
