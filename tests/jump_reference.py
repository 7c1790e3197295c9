"""Numeric references for the broad jump's row families: Pinocchio on numpy arrays only.

Nothing here uses the row blocks, the flight Functions or the NLP: the full-body state is
built with :meth:`SymmetryMap.to_full` and :func:`latentoc.jump.robot.sagittal_base.base_to_freeflyer`
(checked against Pinocchio's Lie-group difference in test_jump_base), the point forces act
through ``pinocchio.rnea``'s external forces, and momentum, COM, mass matrix and frames come
from Pinocchio.
"""
import numpy as np
import pinocchio as pin

from latentoc.jump.robot.sagittal_base import base_to_freeflyer

SAGITTAL = [0, 2, 4]
POINT_FRAMES = ("lfoot", "lfoot_end", "ltoes_end", "ltoes_end")  # heel (on the foot), ball, toe tip, pad (on the toes)
MIRROR = np.array([1.0, -1.0, 1.0])


def joint_motion(layer, spline, P, t, left=False):
    """y, yd, ydd (each K x n) of the GP layer along the latent spline with control points P (where
    ``left``, the spline's limits from the left)."""
    t = np.atleast_1d(np.asarray(t, float))
    m = layer.motion(np.hstack([spline.basis(t, k, left) @ P for k in range(3)]))
    return m.y, m.yd, m.ydd


def full_state(smap, b, bd, bdd, y, yd, ydd):
    """Free-flyer q, v, a of the sagittal base (b, bd, bdd) and the learned joint motion."""
    q7, v6, a6 = (u[0] for u in base_to_freeflyer(b, bd, bdd))
    z7 = np.zeros(7)
    return (smap.to_full(y, q7), np.concatenate([v6, smap.to_full(yd, z7)[7:]]),
            np.concatenate([a6, smap.to_full(ydd, z7)[7:]]))


def foot_points(model, data, q, geom):
    """World heel, ball, toe tip and pad of the left foot (3 x 4 columns) by forward kinematics."""
    pin.framesForwardKinematics(model, data, q)
    M = data.oMf[model.getFrameId("lfoot")]
    T = data.oMf[model.getFrameId("ltoes_end")]
    return np.column_stack([M.act(np.asarray(geom.heel_offset, float)),
                            data.oMf[model.getFrameId("lfoot_end")].translation,
                            T.translation, T.act(np.asarray(geom.pad_offset, float))])


def point_forces(lam, mu):
    """(fx, fz) of heel, ball, toe, pad (4 x 2) from the eight friction-pyramid edge weights."""
    lam = np.asarray(lam, float).reshape(4, 2)
    return np.column_stack([mu * (lam[:, 0] - lam[:, 1]), lam[:, 0] + lam[:, 1]])


def generalized_force(model, data, q, geom, forces):
    """sum J^T f of the left foot's point forces (4 x 2: fx, fz of heel, ball, toe, pad), each on its
    own body, and their mirror images on the right foot: rnea without minus rnea with them as
    external forces (at rest, so only the forces differ)."""
    P = foot_points(model, data, q, geom).T
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    pin.forwardKinematics(model, data, q)
    for side in "lr":
        for k, frame in enumerate(POINT_FRAMES):
            j = model.frames[model.getFrameId(side + frame[1:])].parentJoint
            p = P[k] if side == "l" else MIRROR * P[k]
            f = np.array([forces[k][0], 0.0, forces[k][1]])
            fext[j] += data.oMi[j].actInv(pin.Force(f, np.cross(p, f)))
    z = np.zeros(model.nv)
    return pin.rnea(model, data, q, z, z) - pin.rnea(model, data, q, z, z, fext)


def mass_of(model):
    return sum(i.mass for i in model.inertias)


def momentum(model, data, q, v):
    """COM (x, z), COM velocity (x, z) and the angular momentum about the COM (y)."""
    hg = pin.computeCentroidalMomentum(model, data, q, v)
    return data.com[0][[0, 2]].copy(), hg.linear[[0, 2]] / mass_of(model), float(hg.angular[1])


def pitch_rate_for(model, data, smap, y, yd, L):
    """The base pitch rate at which the angular momentum about the COM is L (y): affine in the
    pitch rate, so from the momenta at pitch rates 0 and 1 (base at rest otherwise)."""
    q, v0, _ = full_state(smap, np.zeros(3), np.zeros(3), np.zeros(3), y, yd, np.zeros_like(y))
    v1 = v0.copy()
    v1[4] = 1.0
    L0, L1 = momentum(model, data, q, v0)[2], momentum(model, data, q, v1)[2]
    return (L - L0) / (L1 - L0)


def flight_base(model, data, smap, y, yd, pitch, L, c, cd):
    """Base pose and velocity (x, z, pitch) of a flight state: pitch and angular momentum L, the
    COM at c (x, z) moving at cd; the base translation moves the COM by the same amount."""
    pd = pitch_rate_for(model, data, smap, y, yd, L)
    q, v, _ = full_state(smap, np.array([0.0, 0.0, pitch]), np.array([0.0, 0.0, pd]), np.zeros(3), y, yd,
                         np.zeros_like(y))
    c0, cd0, _ = momentum(model, data, q, v)
    return np.array([*(c - c0), pitch]), np.array([*(cd - cd0), pd])


def polygon_rows(heel, toe, p):
    """Rows of the feet's support polygon (vertices heel_R, toe_R, toe_L, heel_L) at p (x, y)."""
    from latentoc.jump.robot.support_polygon import polygon_from_vertices

    A, b = polygon_from_vertices([[heel[0], -heel[1]], [toe[0], -toe[1]], toe[:2], heel[:2]])
    return A @ np.asarray(p, float)[:2] + b
