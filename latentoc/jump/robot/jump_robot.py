"""What the jump's row families know of the robot: models, feet, limits, friction, mass.

Nothing here depends on the GPDM: the row families (:mod:`..rows`) are Functions of the
joint motion y, yd, ydd (the 37 learned coordinates, right side mirrored by E) and the
node's other inputs, so they compile once per robot.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np

from latentoc.dynamics import SymbolicModel
from latentoc.min_torque.limits import Limits
from latentoc.mocap.symmetry import SymmetryMap
from latentoc.jump.robot.sagittal_base import base_function
from latentoc.jump.closure.planted_legs import LegClosure
from latentoc.jump.robot.feet import POINTS, FootGeometry, joint_embedding, points_function
from latentoc.jump.robot.torque_limits import TorqueLimits, TrainingDynamics
from latentoc.jump.robot.zmp import G

SAGITTAL_ROWS = [0, 2, 4]  # x force, z force, y moment of the base rows


@dataclass(eq=False)
class JumpRobot:
    """The symmetric humanoid as the row families see it."""

    sym: SymbolicModel
    smap: SymmetryMap
    geom: FootGeometry
    limits: TrainingDynamics | TorqueLimits
    mu: float
    mass: float
    joint_limits: bool = False  # the model's position and velocity limits as rows (:mod:`..rows.joint_limits`)
    closure: LegClosure | None = None  # the planted foot: closed legs and the base in contact (:mod:`..closure.planted_legs`)

    @property
    def weight(self) -> float:
        return self.mass * G

    @cached_property
    def E(self) -> np.ndarray:
        """q[7:] = E y (right side mirrored)."""
        return joint_embedding(self.smap)

    @property
    def n_learned(self) -> int:
        return int(self.E.shape[1])

    @cached_property
    def active(self) -> np.ndarray:
        """Joints with a torque range (the others vanish by symmetry; checked in verify)."""
        return np.where(self.limits.tau_max - self.limits.tau_min > 1e-6)[0]

    @cached_property
    def torque_scale(self) -> np.ndarray:
        a = self.active
        return np.maximum(self.limits.tau_max[a] - self.limits.tau_min[a], 1.0)

    @cached_property
    def force_free(self) -> np.ndarray:
        """Positions in :attr:`active` of the joints no foot force enters (trunk, neck, head,
        arms): their torque is the motion's alone, known without the force split."""
        m = self.sym.model
        frames = {self.geom.side_frame(side, c.frame) for c in self.geom.points for side in "lr"}
        legs = {j for f in frames for j in m.supports[m.frames[m.getFrameId(f)].parentJoint]}
        joint_of_v = np.concatenate([[j] * m.joints[j].nv for j in range(1, m.njoints)])
        return np.array([i for i, a in enumerate(self.active) if joint_of_v[6 + a] not in legs], int)

    @cached_property
    def unmirrored(self) -> np.ndarray:
        """Positions in :attr:`active` whose torque rows the NLP keeps: a right joint's torque is
        its left partner's times the mirror factor, so with mirrored limits its rows repeat the
        left's; limits that are not mirror images keep every row."""
        a = self.active
        pos = {int(j): k for k, j in enumerate(a)}
        lo, hi = self.limits.tau_min, self.limits.tau_max
        right = []
        for r_q, y_idx, f in self.smap.copied:
            r, left = r_q - 7, int(self.smap.learned_q[y_idx]) - 7
            mlo, mhi = (lo[left], hi[left]) if f > 0 else (-hi[left], -lo[left])
            tol = 1e-9 * max(1.0, abs(hi[left]), abs(lo[left]))
            if abs(lo[r] - mlo) > tol or abs(hi[r] - mhi) > tol:
                return np.arange(len(a))
            if r in pos:
                right.append(pos[r])
        return np.setdiff1d(np.arange(len(a)), right)

    @cached_property
    def joint_bounds(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(lo, hi, v_max) of each learned coordinate: the model's position and velocity limits of its
        joint and, mirrored, of its right partner's (the tighter); +-inf where the model has none."""
        m, held = self.sym.model, self.model_limits
        assert held.q_lo is not None and held.q_hi is not None and held.v_max is not None
        lower, upper, vel = held.q_lo, held.q_hi, held.v_max
        v_of_q = {m.joints[j].idx_q: m.joints[j].idx_v for j in range(1, m.njoints) if m.joints[j].nq == 1}
        qi = self.smap.learned_q
        lo, hi = lower[qi].copy(), upper[qi].copy()
        vmax = np.array([vel[v_of_q[int(q)]] for q in qi])
        for r_q, y_idx, f in self.smap.copied:
            r_lo, r_hi = sorted((lower[r_q] / f, upper[r_q] / f))
            lo[y_idx], hi[y_idx] = max(lo[y_idx], r_lo), min(hi[y_idx], r_hi)
            vmax[y_idx] = min(vmax[y_idx], vel[v_of_q[int(r_q)]])
        return lo, hi, vmax

    @property
    def has_joint_limits(self) -> bool:
        """Whether the NLP holds joint position and velocity limits (declared, and the model has some)."""
        lo, hi, vmax = self.joint_bounds
        return self.joint_limits and bool(np.isfinite(lo).any() or np.isfinite(hi).any() or np.isfinite(vmax).any())

    @cached_property
    def model_limits(self) -> Limits:
        """The model's joint position and velocity limits, read as the fixed-base kind reads them."""
        return Limits.of(self.sym.model, joint_limits=True, velocity_limits=True)

    # ------------------------------------------------------------- symbolic pieces
    def configuration(self, b, bd, bdd, y, yd, ydd):
        """Free-flyer (q, v, a) of the sagittal base (b, bd, bdd) and the joint motion."""
        E = ca.DM(self.E)
        q7, v6, a6 = base_function()(b, bd, bdd)
        return ca.vertcat(q7, E @ y), ca.vertcat(v6, E @ yd), ca.vertcat(a6, E @ ydd)

    def planted(self, y, yd, ydd, held, shift):
        """The contact phases' closed legs (y, yd, ydd) and sagittal base (b, bd, bdd): the planted body
        at its ground pose moved by ``shift`` along x, the hinge held where ``held`` (:mod:`..closure.planted_legs`)."""
        assert self.closure is not None, "the contact rows need the robot's leg closure"
        y, yd, ydd = self.closure.legs(y, yd, ydd, held)
        return (y, yd, ydd), self.closure.planted_base(y, yd, ydd, shift)

    def points(self, q, shift):
        """World heel, ball, toe and pad (3 x 4 columns) of pose q moved by the base translation (x, z)."""
        return points_function(self.sym, self.geom)(q) + ca.repmat(ca.vertcat(shift[0], 0, shift[1]), 1, len(POINTS))

    def torque_rows(self, tau_joint):
        """Torques of the active joints (N m; the NLP scales them by the limit range)."""
        return tau_joint[self.active.tolist()]


def galilean(b, bd):
    """The base pose and velocity without their translation: (0, 0, pitch), (0, 0, pitch rate).

    A uniform translation and velocity of the whole body change neither the joint torques, nor
    the base rows of RNEA, nor the contact Jacobians (uniform gravity, Galilean invariance), so
    the rows are computed about the base's position and the points moved back
    (:meth:`JumpRobot.points`)."""
    return ca.vertcat(0, 0, b[2]), ca.vertcat(0, 0, bd[2])
