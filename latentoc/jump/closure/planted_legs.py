"""The planted foot by construction: the legs' out-of-plane joints and, in contact, the base.

For a left-right symmetric jump the base moves in the sagittal plane (:mod:`..robot.sagittal_base`), so the planted
body (the toe tip's: the CMU's toes, a rigid sole; :func:`..demonstration.planted.foot_bodies`) keeps its ground
pose exactly when, relative to the base, it keeps its standing sideways offset and its orientation
differs from the standing one by a rotation about y alone. These three conditions fix the leg's
three out-of-plane joints (axes not along y standing: hip roll and yaw, ankle roll) from the
others, at every time of the motion (dependent coordinates, as bioptim's holonomic models): Newton
from the GP mean's values, their velocities and accelerations by the implicit-function theorem.
While the heel is loaded the hinge between the heel's body and the planted one (the CMU's toe
joint) holds its standing angle. In contact the sagittal base then follows from the planted
body's ground pose (the standing one moved by ``shift`` along x): pitch = -theta, (x, z) = ground
- R_y(pitch) p_bf, so no base variable and no placement row is needed.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import casadi as ca
import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.errors import ProblemError
from latentoc.mocap.symmetry import SymmetryMap
from latentoc.jump.robot.sagittal_base import _ry
from latentoc.jump.robot.feet import FootGeometry, joint_embedding
from latentoc.jump.demonstration.planted import foot_bodies, leg_joints

__all__ = ["LegClosure", "NEWTON_STEPS"]

NEWTON_STEPS = 4  # from the GP mean's out-of-plane joints: quadratic convergence to rounding
IN_PLANE_COS = np.cos(np.radians(45.0))  # a joint axis this close to y standing is sagittal


def _select(n: int, idx: np.ndarray) -> ca.DM:
    S = np.zeros((n, len(idx)))
    S[np.asarray(idx, int), np.arange(len(idx))] = 1.0
    return ca.DM(S)


@dataclass(eq=False)
class LegClosure:
    """The left leg's dependent coordinates and the planted base (module doc); the right leg is
    the mirror image through the joint embedding E (q[7:] = E y)."""

    sym: SymbolicModel
    E: np.ndarray
    anchor: str  # the planted body's frame
    dependent: np.ndarray  # learned positions of the three out-of-plane leg joints
    hinge: int | None  # learned position of the heel body's hinge (None: a rigid sole)
    hinge_standing: float  # its standing angle (rad)
    R_ground: np.ndarray  # the planted body's standing world rotation
    p_ground: np.ndarray  # and position (m)

    @classmethod
    def of(cls, sym: SymbolicModel, smap: SymmetryMap, geom: FootGeometry, q_stand: np.ndarray) -> "LegClosure":
        """The closure of the robot ``sym`` standing at ``q_stand``; a ProblemError if its leg has
        not three out-of-plane joints among the learned coordinates."""
        model = sym.model
        anchor, hinge = foot_bodies(model, geom)
        data = model.createData()
        pin.computeJointJacobians(model, data, q_stand)
        pin.framesForwardKinematics(model, data, q_stand)
        leg = leg_joints(model, anchor)
        names = list(smap.learned_names)
        dependent = []
        for name in leg:
            j = model.getJointId(name)
            axis = pin.getJointJacobian(model, data, j, pin.WORLD)[3:, model.joints[j].idx_v]
            if abs(axis[1]) < IN_PLANE_COS * np.linalg.norm(axis) and name in names:
                dependent.append(names.index(name))
        if len(dependent) != 3:
            raise ProblemError(f"key 'robot.foot': the leg to {anchor!r} needs three learned out-of-plane joints "
                               f"(axes not along y standing) to hold its planted body, it has {len(dependent)}: "
                               f"{[names[k] for k in dependent]}")
        M = data.oMf[model.getFrameId(anchor)]
        h = names.index(hinge) if hinge is not None else None
        h_q = model.joints[model.getJointId(hinge)].idx_q if hinge is not None else 0
        return cls(sym, joint_embedding(smap), anchor, np.array(dependent, int), h,
                   float(q_stand[h_q]) if hinge is not None else 0.0, M.rotation.copy(), M.translation.copy())

    @property
    def n(self) -> int:
        return int(self.E.shape[1])

    def _placement(self, y):
        q0 = ca.vertcat(0, 0, 0, 0, 0, 0, 1, ca.DM(self.E) @ y)
        p, R = self.sym.frame_placement(self.anchor)(q0)
        return p, R @ ca.DM(self.R_ground.T)

    @cached_property
    def _lateral(self) -> tuple[ca.Function, ca.Function, ca.Function]:
        """c(y) (3): the planted body's sideways offset and roll/yaw against the standing pose
        relative to the base; its Jacobian; and v' (d2c/dy2) v."""
        y, v = ca.SX.sym("y", self.n), ca.SX.sym("v", self.n)
        p, M = self._placement(y)
        c = ca.vertcat(p[1] - float(self.p_ground[1]), (M[2, 1] - M[1, 2]) / 2, (M[1, 0] - M[0, 1]) / 2)
        J = ca.jacobian(c, y)
        quad = ca.jtimes(ca.jtimes(c, y, v), y, v)
        return (ca.Function("lateral", [y], [c]), ca.Function("lateral_jac", [y], [J]),
                ca.Function("lateral_quad", [y, v], [quad]))

    def residual(self, y):
        """The three closure conditions at y (zero where the closure holds)."""
        return self._lateral[0](y)

    def legs(self, y, yd, ydd, held):
        """(y, yd, ydd) with the hinge held at its standing angle where ``held`` (1; 0: free) and the
        out-of-plane joints closed (module doc); casadi expressions or numbers."""
        res, jac, quad = self._lateral
        n, dep = self.n, self.dependent
        Sd = _select(n, dep)
        if self.hinge is not None:
            Sh = _select(n, [self.hinge])
            y = y + Sh @ (held * (self.hinge_standing - y[self.hinge]))
            yd, ydd = yd - Sh @ (held * yd[self.hinge]), ydd - Sh @ (held * ydd[self.hinge])
        for _ in range(NEWTON_STEPS):
            J = jac(y)
            y = y - Sd @ ca.solve(J[:, dep.tolist()], res(y))
        J = jac(y)
        Jd = J[:, dep.tolist()]
        yd0, ydd0 = yd - Sd @ yd[dep.tolist()], ydd - Sd @ ydd[dep.tolist()]
        yd = yd0 - Sd @ ca.solve(Jd, J @ yd0)
        ydd = ydd0 - Sd @ ca.solve(Jd, J @ ydd0 + quad(y, yd))
        return y, yd, ydd

    @cached_property
    def _base(self) -> ca.Function:
        y, v, a, shift = ca.SX.sym("y", self.n), ca.SX.sym("v", self.n), ca.SX.sym("a", self.n), ca.SX.sym("shift")
        p, M = self._placement(y)
        pitch = -ca.atan2(M[0, 2], M[2, 2])
        pw = _ry(pitch) @ p
        b = ca.vertcat(float(self.p_ground[0]) + shift - pw[0], float(self.p_ground[2]) - pw[2], pitch)
        bd = ca.jtimes(b, y, v)
        bdd = ca.jtimes(b, y, a) + ca.jtimes(bd, y, v)
        return ca.Function("planted_base", [y, v, a, shift], [b, bd, bdd], ["y", "yd", "ydd", "shift"], ["b", "bd", "bdd"])

    def planted_base(self, y, yd, ydd, shift):
        """The sagittal base (b, bd, bdd) that puts the planted body at its ground pose moved by
        ``shift`` along x, for closed legs (:meth:`legs`)."""
        return self._base(y, yd, ydd, shift)

    @cached_property
    def numeric(self) -> ca.Function:
        """(y, yd, ydd, held, shift) -> (y, yd, ydd, b, bd, bdd): :meth:`legs` then :meth:`planted_base`,
        one time per column, for the export and the start."""
        n = self.n
        y, yd, ydd = (ca.SX.sym(k, n) for k in ("y", "yd", "ydd"))
        held, shift = ca.SX.sym("held"), ca.SX.sym("shift")
        yc, ydc, yddc = self.legs(y, yd, ydd, held)
        b, bd, bdd = self.planted_base(yc, ydc, yddc, shift)
        return ca.Function("leg_closure", [y, yd, ydd, held, shift], [yc, ydc, yddc, b, bd, bdd])

    def evaluate(self, Y: np.ndarray, Yd: np.ndarray, Ydd: np.ndarray, held: np.ndarray, shift: np.ndarray
                 ) -> tuple[np.ndarray, ...]:
        """Numeric :attr:`numeric` at K times (Y, Yd, Ydd: K x n; held, shift: K): six K x . arrays."""
        K = len(Y)
        out = self.numeric.map(K)(np.asarray(Y, float).T, np.asarray(Yd, float).T, np.asarray(Ydd, float).T,
                                  np.asarray(held, float).reshape(1, K), np.asarray(shift, float).reshape(1, K))
        return tuple(np.asarray(o).T for o in out)
