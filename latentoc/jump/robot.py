"""What the jump's row families know of the robot: models, feet, limits, friction, mass.

Nothing here depends on the GPDM: the row families (:mod:`.rows`) are Functions of the
joint motion y, yd, ydd (the 37 learned coordinates, right side mirrored by E) and the
node's other inputs, so they compile once per robot.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import casadi as ca
import numpy as np

from ..dynamics import SymbolicModel
from ..mocap.symmetry import SymmetryMap
from .base import base_function
from .contact import POINTS, FootGeometry, joint_embedding, points_function
from .torque_limits import TrainingDynamics
from .training import RIGHT_TOE, TOE
from .zmp import G

SAGITTAL_ROWS = [0, 2, 4]  # x force, z force, y moment of the base rows
CLOSURE_STEPS = 3  # Newton steps of the legs' sideways closure (:meth:`JumpRobot.closure`)
#: the bodies a contact phase's base is anchored on: their (front, back) points, both on the ground
ANCHORS = {"toes": ("toe", "pad"), "foot": ("ball", "heel")}


@dataclass(eq=False)
class JumpRobot:
    """The symmetric humanoid as the row families see it."""

    sym: SymbolicModel
    smap: SymmetryMap
    geom: FootGeometry
    limits: TrainingDynamics
    mu: float
    mass: float
    hinge: int  # learned index of the toe joint: the hinge between the anchors (:meth:`anchored`)
    lateral: tuple[int, int] = (0, 1)  # learned indices of the hip's joints that close the leg sideways (:meth:`closure`)
    _anchored: dict = field(default_factory=dict, repr=False)

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
        legs = {j for f in (TOE, RIGHT_TOE) for j in m.supports[m.frames[m.getFrameId(f)].parentJoint]}
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

    # ------------------------------------------------------------- symbolic pieces
    def anchored(self, anchor: str) -> ca.Function:
        """(y, yd, ydd, x_pin) -> (b, bd, bdd): the sagittal base that lays body ``anchor`` flat on the
        ground: "toes" (the toe and pad points level, the toe point at (x_pin, 0)) or "foot" (the
        heel and ball level, the ball where it is when the toes lie flat with the toe point at
        x_pin). The two points in the base frame (base at the origin, unpitched) fix the pitch that
        levels them, then the front one's ground point the position."""
        if anchor not in self._anchored:
            front, back = ANCHORS[anchor]
            n = self.n_learned
            y, yd, ydd = (ca.SX.sym(k, n) for k in ("y", "yd", "ydd"))
            x_pin = ca.SX.sym("x_pin")
            q0 = ca.vertcat(0, 0, 0, 0, 0, 0, 1, ca.DM(self.E) @ y)
            P = points_function(self.sym, self.geom)(q0)
            f, r = P[:, POINTS.index(front)], P[:, POINTS.index(back)]
            p = ca.atan2(f[2] - r[2], f[0] - r[0])
            c, s = ca.cos(p), ca.sin(p)
            x_front = x_pin - (self.geom.ball_back if front == "ball" else 0.0)
            b = ca.vertcat(x_front - (c * f[0] + s * f[2]), s * f[0] - c * f[2], p)
            bd = ca.jtimes(b, y, yd)
            bdd = ca.jtimes(b, y, ydd) + ca.jtimes(bd, y, yd)
            self._anchored[anchor] = ca.Function(f"anchored_{anchor}", [y, yd, ydd, x_pin], [b, bd, bdd],
                                                 ["y", "yd", "ydd", "x_pin"], ["b", "bd", "bdd"])
        return self._anchored[anchor]

    @cached_property
    def rolling(self) -> ca.Function:
        """(y, yd, ydd, x_pin, p, pd, pdd) -> (b, bd, bdd): the sagittal base pitched at p (rate pd,
        acceleration pdd) with the toe point at (x_pin, 0): the toes rolling on it."""
        n = self.n_learned
        y, yd, ydd = (ca.SX.sym(k, n) for k in ("y", "yd", "ydd"))
        x_pin, p, pd, pdd = (ca.SX.sym(k) for k in ("x_pin", "p", "pd", "pdd"))
        q0 = ca.vertcat(0, 0, 0, 0, 0, 0, 1, ca.DM(self.E) @ y)
        f = points_function(self.sym, self.geom)(q0)[:, POINTS.index("toe")]
        c, s = ca.cos(p), ca.sin(p)
        b = ca.vertcat(x_pin - (c * f[0] + s * f[2]), s * f[0] - c * f[2], p)
        z, zd, zdd = ca.vertcat(y, p), ca.vertcat(yd, pd), ca.vertcat(ydd, pdd)
        bd = ca.jtimes(b, z, zd)
        bdd = ca.jtimes(b, z, zdd) + ca.jtimes(bd, z, zd)
        return ca.Function("rolling_base", [y, yd, ydd, x_pin, p, pd, pdd], [b, bd, bdd],
                           ["y", "yd", "ydd", "x_pin", "p", "pd", "pdd"], ["b", "bd", "bdd"])

    @cached_property
    def closure(self) -> ca.Function:
        """(y, yd, ydd, flat, y_shift) -> (y, yd, ydd) with the two lateral hip joints closing the leg
        through the planted foot: the anchor's two points (heel and ball on the flat foot, else toe
        and pad) at their standing sideways positions shifted by y_shift, found by ``CLOSURE_STEPS``
        Newton steps from the path's values (quadratic: the path's are within degrees of them); the
        rates and accelerations are the time derivatives of that function of y. A sagittal base
        leaves the points' y unchanged, so the closure needs no base."""
        n = self.n_learned
        y, yd, ydd = (ca.SX.sym(k, n) for k in ("y", "yd", "ydd"))
        flat, shift = ca.SX.sym("flat"), ca.SX.sym("y_shift")
        a, b = self.lateral
        u = ca.SX.sym("u", 2)
        yu = ca.vertcat(*[u[self.lateral.index(i)] if i in self.lateral else y[i] for i in range(n)])
        P = points_function(self.sym, self.geom)(ca.vertcat(0, 0, 0, 0, 0, 0, 1, ca.DM(self.E) @ yu))
        gy = self.geom.ground_y
        r = flat * ca.vertcat(P[1, 0] - gy[0], P[1, 1] - gy[1]) + (1 - flat) * ca.vertcat(P[1, 2] - gy[2], P[1, 3] - gy[3])
        r = r - shift
        J = ca.jacobian(r, u)
        step = ca.Function("closure_step", [u, y, flat, shift],
                           [u - ca.vertcat(J[1, 1] * r[0] - J[0, 1] * r[1], J[0, 0] * r[1] - J[1, 0] * r[0])
                            / (J[0, 0] * J[1, 1] - J[0, 1] * J[1, 0])])
        uk = ca.vertcat(y[a], y[b])
        for _ in range(CLOSURE_STEPS):
            uk = step(uk, y, flat, shift)
        yc = ca.vertcat(*[uk[self.lateral.index(i)] if i in self.lateral else y[i] for i in range(n)])
        ydc = ca.jtimes(yc, y, yd)
        yddc = ca.jtimes(yc, y, ydd) + ca.jtimes(ydc, y, yd)
        return ca.Function("leg_closure", [y, yd, ydd, flat, shift], [yc, ydc, yddc],
                           ["y", "yd", "ydd", "flat", "y_shift"], ["yc", "ydc", "yddc"])

    @cached_property
    def opening(self) -> ca.Function:
        """(y, yd, flat, y_shift) -> (r, rd): the anchor's two points' sideways offsets from their
        closed positions (:meth:`closure`) and their rates, along the path itself: zero where the
        contact begins or ends, so the closed legs and the free ones meet."""
        n = self.n_learned
        y, yd = ca.SX.sym("y", n), ca.SX.sym("yd", n)
        flat, shift = ca.SX.sym("flat"), ca.SX.sym("y_shift")
        P = points_function(self.sym, self.geom)(ca.vertcat(0, 0, 0, 0, 0, 0, 1, ca.DM(self.E) @ y))
        gy = self.geom.ground_y
        r = flat * ca.vertcat(P[1, 0] - gy[0], P[1, 1] - gy[1]) + (1 - flat) * ca.vertcat(P[1, 2] - gy[2], P[1, 3] - gy[3])
        r = r - shift
        return ca.Function("leg_opening", [y, yd, flat, shift], [r, ca.jtimes(r, y, yd)],
                           ["y", "yd", "flat", "y_shift"], ["r", "rd"])

    def configuration(self, b, bd, bdd, y, yd, ydd):
        """Free-flyer (q, v, a) of the sagittal base (b, bd, bdd) and the joint motion."""
        E = ca.DM(self.E)
        q7, v6, a6 = base_function()(b, bd, bdd)
        return ca.vertcat(q7, E @ y), ca.vertcat(v6, E @ yd), ca.vertcat(a6, E @ ydd)

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
