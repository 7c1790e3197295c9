"""Foot contact: points and contact forces (Sect. 4.2).

Each foot has four contact points, declared per robot (:mod:`.robot_declaration`; the right foot is the
left's mirror image); their roles in the rows:

* ``heel`` - the rearmost point (the CMU humanoid's: its ankle dropped to the ground standing);
* ``ball`` - under the front of the foot (the CMU's end of the foot bone);
* ``toe`` - the toe tip, the point the stance and the landing are pinned at;
* ``pad`` - a point just behind the toe tip on the ground standing (the CMU's 1 cm behind it, on
  its toes body): the toes' contact patch, so that a foot on its toes alone can hold a moment (with
  the toe tip alone every base row of such a sample would ask the motion for none).

In contact (stance and landing) the toe tip's body is planted at its ground pose by construction
(:mod:`..closure.planted_legs`): the toe tip and the pad do not move, and the heel and ball only with the toe joint
once the heel is off the ground.

Contact forces: four points per foot, each with a 2-D friction pyramid written with its two edge
generators ``lam1 (mu, 1) + lam2 (-mu, 1)``, ``lam >= 0``.  In the sagittal plane this pyramid *is*
the exact cone ``|fx| <= mu fz``; lateral forces are zero by symmetry.  Unilateral forces and the
centre of pressure inside the foot follow from ``lam >= 0``.  The heel and ball can push only when
they are on the ground, by the training motion's contact schedule (:mod:`..schedule.phases`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import pinocchio as pin

from latentoc.dynamics import SymbolicModel
from latentoc.robots.point_kinematics import point_jacobian
from latentoc.mocap.symmetry import SymmetryMap

POINTS = ("heel", "ball", "toe", "pad")
CMU_BODY = {"heel": 0, "ball": 1, "toe": 2, "pad": 2}  # a point's body among a foot's three in a CMU-layout result
MU = 0.4
EDGES = 2 * len(POINTS)  # friction-pyramid edge weights per foot


def joint_embedding(smap: SymmetryMap) -> np.ndarray:
    """Matrix E (nq - 7, n_learned) with q[7:] = E y (right side mirrored)."""
    E = np.zeros((smap.nq, smap.n_learned))
    E[smap.learned_q, np.arange(smap.n_learned)] = 1.0
    for r_idx, y_idx, f in smap.copied:
        E[r_idx, y_idx] = f
    return E[7:]


@dataclass(frozen=True)
class ContactPoint:
    """A contact point of the left foot, fixed in the frame ``frame`` at ``offset`` (in that frame's
    coordinates; None: the frame's origin)."""

    name: str
    frame: str
    offset: np.ndarray | None = None


@dataclass
class FootGeometry:
    """The left foot's points in :data:`POINTS`' order, each fixed in a frame, and each of those
    frames' mirror partner on the right (built from a problem's ``[robot]``,
    :meth:`.declaration.RobotDeclaration.geometry`)."""

    points: tuple[ContactPoint, ...]
    right: dict[str, str]  # left frame -> its mirror partner
    footprint: np.ndarray | None = None  # world heel, ball, toe, pad standing (3 x 4)
    right_points: tuple[ContactPoint, ...] = ()  # the mirror images of ``points`` in their right frames

    def offset(self, name: str) -> np.ndarray:
        """The point ``name``'s offset in its frame (zeros at the frame's origin)."""
        c = self.points[POINTS.index(name)]
        return np.zeros(3) if c.offset is None else np.asarray(c.offset, float)

    @property
    def pad_setback(self) -> float:
        """How far the pad stands behind the toe tip (m, to the nanometre): the rear edge of the centre
        of pressure while the toes carry the foot alone (:mod:`..rows.contact`)."""
        assert self.footprint is not None, "the pad's setback is measured on the standing footprint"
        return round(float(self.footprint[0, 2] - self.footprint[0, 3]), 9)

    @property
    def toe_x(self) -> float:
        """The toe tip's x standing (m): the landing's x_L less this is how far the planted body moved."""
        assert self.footprint is not None, "the toe tip's standing place is on the standing footprint"
        return float(self.footprint[0, 2])

    def planted_shift(self, landed: np.ndarray, x_L: float) -> np.ndarray:
        """How far the planted body stands along x from its standing place at contact times whose
        ``landed`` flags are given: 0 in the stance, ``x_L`` less :attr:`toe_x` in the landing (the
        rows wire the same, :func:`..rows.contact._planted_inputs`)."""
        return np.where(landed, x_L - self.toe_x, 0.0)

    @property
    def heel_offset(self) -> np.ndarray:
        return self.offset("heel")

    @property
    def pad_offset(self) -> np.ndarray:
        return self.offset("pad")

    def side_frame(self, side: str, frame: str) -> str:
        """The frame of the left foot's ``frame`` on ``side`` ("l" or "r"): its mirror partner on the right."""
        return frame if side == "l" else self.right[frame]

    @classmethod
    def from_result(cls, arrays: Any) -> "FootGeometry":
        """The geometry a contact result exports: ``contact_frames`` (the left foot's then the right's:
        one per point, or the foot, ball and toes bodies of the CMU layout) and ``{point}_offset``."""
        frames = [str(f) for f in np.asarray(arrays["contact_frames"])]
        half = len(frames) // 2
        body = {p: POINTS.index(p) for p in POINTS} if half == len(POINTS) else CMU_BODY
        pts = []
        for p in POINTS:
            off = np.asarray(arrays[f"{p}_offset"], float) if f"{p}_offset" in arrays else None
            pts.append(ContactPoint(p, frames[body[p]], off))
        return cls(tuple(pts), {frames[body[p]]: frames[half + body[p]] for p in POINTS})


def point_joint(model: pin.Model, geom: FootGeometry, name: str) -> int:
    """The joint that moves the left foot's point ``name`` (the parent joint of its frame)."""
    return int(model.frames[model.getFrameId(geom.points[POINTS.index(name)].frame)].parentJoint)


def points_function(sym: SymbolicModel, geom: FootGeometry) -> ca.Function:
    """(q) -> P (3 x 4): world heel, ball, toe, pad of the left foot as columns."""
    q = ca.SX.sym("q", sym.nq)
    placed: dict[str, Any] = {}
    columns = []
    for c in geom.points:
        if c.frame not in placed:  # each frame placed once (its expression shared by its points)
            placed[c.frame] = sym.frame_placement(c.frame)(q)
        p, R = placed[c.frame]
        columns.append(p if c.offset is None else p + R @ ca.DM(c.offset))
    return ca.Function("foot_points", [q], [ca.horzcat(*columns)], ["q"], ["P"])


def generator_matrix(mu: float = MU) -> np.ndarray:
    """G (2 x 2): columns are the pyramid edges (fx, fz) = (mu, 1), (-mu, 1)."""
    return np.array([[mu, -mu], [1.0, 1.0]])


def point_forces(lam, mu: float = MU):
    """(fx, fz) of heel, ball, toe, pad from their generator weights (numpy and casadi)."""
    G = generator_matrix(mu)
    out = []
    for k in range(len(POINTS)):
        l1, l2 = lam[2 * k], lam[2 * k + 1]
        out.append((G[0, 0] * l1 + G[0, 1] * l2, l1 + l2))
    return out


def toe_wrench(lam, P, mu: float = MU):
    """World-aligned wrench (6) at the toe tip of the point forces (casadi): force, moment about the toe."""
    f = point_forces(lam, mu)
    fx = sum(fk[0] for fk in f)
    fz = sum(fk[1] for fk in f)
    my = 0
    for k in (0, 1, 3):  # heel, ball, pad about the toe tip (column 2)
        rx, rz = P[0, k] - P[0, 2], P[2, k] - P[2, 2]
        my = my + rz * f[k][0] - rx * f[k][1]
    return ca.vertcat(fx, 0, fz, 0, my, 0)


MIRROR = np.diag([1.0, -1.0, 1.0])


def _skew(p):
    return ca.vertcat(ca.horzcat(0, -p[2], p[1]), ca.horzcat(p[2], 0, -p[0]), ca.horzcat(-p[1], p[0], 0))


def point_generalized_force(sym: SymbolicModel, geom: FootGeometry, q, forces) -> ca.SX:
    """sum_k J_k(q)^T f_k over the contact points of both feet (casadi, nv).

    ``forces`` are the left foot's (fx, fz) per point (:func:`point_forces`); the right foot
    carries their mirror image.  Each force acts on its own body (heel and ball on the foot,
    the toe tip and the pad on the toes), with the point Jacobian ``J_lin - [p - o]x J_ang`` of that body's
    frame (LOCAL_WORLD_ALIGNED), as in the training estimate (:mod:`.torque_limits`).
    """
    P = points_function(sym, geom)(q)
    gen: Any = 0
    for side in "lr":
        for k, c in enumerate(geom.points):
            name = geom.side_frame(side, c.frame)
            o = sym.frame_placement(name)(q)[0]
            p = P[:, k] if side == "l" else ca.DM(MIRROR) @ P[:, k]
            J = sym.frame_jacobian(name)(q)
            Jp = J[:3, :] - _skew(p - o) @ J[3:, :]
            fx, fz = forces[k]
            gen = gen + Jp.T @ ca.vertcat(fx, 0, fz)
    return gen


def foot_points(model: pin.Model, data: pin.Data, geom: FootGeometry) -> np.ndarray:
    """Numeric (3, 4): world heel, ball, toe, pad of the left foot as columns (frames already
    placed), the numeric twin of :func:`points_function`."""
    columns = []
    for c in geom.points:
        M = data.oMf[model.getFrameId(c.frame)]
        columns.append(M.translation if c.offset is None else M.translation + M.rotation @ c.offset)
    return np.column_stack(columns)


def point_jacobians(model: pin.Model, data: pin.Data, q: np.ndarray, geom: FootGeometry) -> np.ndarray:
    """Numeric (4, 3, nv): for heel, ball, toe, pad, the left point's linear Jacobian plus the
    mirrored right one's, so that ``sum_k J[k].T @ (fx_k, 0, fz_k)`` is :func:`point_generalized_force`.
    Leaves ``data`` with the joint Jacobians and frame placements of ``q``."""
    pin.computeJointJacobians(model, data, q)
    pin.framesForwardKinematics(model, data, q)
    out = np.zeros((len(POINTS), 3, model.nv))
    left = foot_points(model, data, geom).T
    for side in "lr":
        for k, c in enumerate(geom.points):
            p = left[k] if side == "l" else MIRROR @ left[k]
            out[k] += point_jacobian(model, data, model.getFrameId(geom.side_frame(side, c.frame)), p)
    return out


def generator_columns(Jp: np.ndarray, mu: float = MU) -> np.ndarray:
    """(nv, 8): generalized force of a unit weight on each friction-pyramid edge (heel, ball, toe, pad)."""
    G = generator_matrix(mu)
    return np.column_stack([Jp[k].T @ np.array([G[0, e], 0.0, G[1, e]]) for k in range(len(Jp)) for e in range(2)])
