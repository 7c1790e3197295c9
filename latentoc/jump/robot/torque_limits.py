"""Joint torque limits tau_min, tau_max of Eq. 34 from the training motion's inverse dynamics.

The training motion is smoothed by a cubic B-spline fit (``n_control`` points, Eq. 23) of
its learned coordinates and sagittal base, giving v and a.  At each frame in contact the
contact forces are estimated by non-negative least squares: the heel, ball and toe of both
feet each push with ``lam1 (mu, 1) + lam2 (-mu, 1)``, ``lam >= 0`` (so the fitted forces are
unilateral, inside the friction cone mu = 0.4 and the centre of pressure is inside the foot)
and the base rows of RNEA are matched, ``rnea_base = sum J^T f``; with ``loaded`` only the
points the contact schedule loads push (:mod:`..schedule.phases`), as in the NLP.  In flight f = 0.  The
joint torques are ``tau = rnea_joint - (J^T f)_joint``; the limits are their per-joint
minimum and maximum over the motion, widened by ``margin`` times the joint's peak |tau|, at
least ``floor`` N m: the head and neck carry 2-10 N m, and 10 % of that bound the whole jump
(the head's limit had the largest multiplier at the optimum, docs/broad-jump-history.md).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.optimize import nnls

from latentoc.errors import ProblemError
from latentoc.latent.spline import BSpline
from latentoc.jump.robot.sagittal_base import base_to_freeflyer
from latentoc.jump.robot.feet import MU, POINTS, FootGeometry, generator_columns, generator_matrix, joint_embedding, point_jacobians
from latentoc.jump.demonstration.training import JumpTraining


@dataclass
class TrainingDynamics:
    """Training inverse dynamics: torques (n, nv - 6), forces (n, 4 points, 2), residual (n, 6)."""

    t: np.ndarray
    tau: np.ndarray
    forces: np.ndarray
    base_residual: np.ndarray
    tau_min: np.ndarray
    tau_max: np.ndarray


@dataclass(frozen=True)
class TorqueLimits:
    """Joint torque limits (nv - 6) from the robot description."""

    tau_min: np.ndarray
    tau_max: np.ndarray


def urdf_torque_limits(model: pin.Model) -> TorqueLimits:
    """The model's effort limits |tau| <= effort of its actuated joints (the URDF's ``<limit effort>``);
    a ProblemError naming ``robot.limits`` if a joint has none."""
    effort = np.asarray(model.effortLimit[6:], float)
    missing = [model.names[j] for j in range(2, model.njoints)
               if not 0 < effort[model.joints[j].idx_v - 6] < 1e30]
    if missing:
        raise ProblemError(f"key 'robot.limits': \"urdf\" needs an effort limit on every joint; {missing[0]!r} "
                           f"has none ({len(missing)} joints without)")
    return TorqueLimits(-effort, effort.copy())


def smoothed_motion(tr: JumpTraining, E: np.ndarray, n_control: int = 40):
    """q, v, a of the training motion from a B-spline fit (base and learned DOFs)."""
    sp = BSpline(n_control, tr.duration)
    Z = np.column_stack([tr.base, tr.Y])
    P = sp.fit(tr.t, Z)
    Zs, Zd, Zdd = (sp.evaluate(P, tr.t, k) for k in range(3))
    q7, v6, a6 = base_to_freeflyer(Zs[:, :3], Zd[:, :3], Zdd[:, :3])
    return (np.column_stack([q7, Zs[:, 3:] @ E.T]), np.column_stack([v6, Zd[:, 3:] @ E.T]),
            np.column_stack([a6, Zdd[:, 3:] @ E.T]))


def contact_torques(model: pin.Model, geom: FootGeometry, Q: np.ndarray, V: np.ndarray, A: np.ndarray,
                    in_contact: np.ndarray, loaded: np.ndarray | None = None, mu: float = MU
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint torques (n, nv - 6), point forces (n, 4, 2) and base residual (n, 6) of the motion Q, V, A
    with NNLS contact forces (module doc) on the frames ``in_contact``: on the points ``loaded`` marks
    (n frames x 4: heel, ball, toe, pad; default all)."""
    d = model.createData()
    G = generator_matrix(mu)
    n, npt = len(Q), len(POINTS)
    taus, forces, res = np.zeros((n, model.nv - 6)), np.zeros((n, npt, 2)), np.zeros((n, 6))
    for i in range(n):
        tau = pin.rnea(model, d, Q[i], V[i], A[i])
        if in_contact[i]:
            Acols = generator_columns(point_jacobians(model, d, Q[i], geom), mu)
            rows = [0, 2, 4]
            cols = np.repeat(np.ones(npt, bool) if loaded is None else np.asarray(loaded[i], bool), 2)
            lam = np.zeros(2 * npt)
            lam[cols] = nnls(Acols[rows][:, cols], tau[rows])[0]
            gf = Acols @ lam
            forces[i] = (G @ lam.reshape(npt, 2).T).T
        else:
            gf = np.zeros(model.nv)
        res[i] = tau[:6] - gf[:6]
        taus[i] = tau[6:] - gf[6:]
    return taus, forces, res


def estimate_training_dynamics(model: pin.Model, smap, tr: JumpTraining, geom: FootGeometry,
                               in_contact: np.ndarray, mu: float = MU, margin: float = 0.1,
                               n_control: int = 40, loaded: np.ndarray | None = None,
                               floor: float = 0.0) -> TrainingDynamics:
    """Least-squares (NNLS) contact forces and joint torques of the training motion.

    ``loaded`` (n frames x 4: heel, ball, toe, pad) marks the points that may push; default all.
    Each loaded joint's range is widened by ``max(margin * peak, floor)`` on both sides."""
    Q, V, A = smoothed_motion(tr, joint_embedding(smap), n_control)
    taus, forces, res = contact_torques(model, geom, Q, V, A, in_contact, loaded, mu)
    peak = np.max(np.abs(taus), axis=0)
    pad = np.where(peak > 1e-9, np.maximum(margin * peak, floor), 0.0)  # unloaded (mirrored) joints stay 0
    return TrainingDynamics(tr.t, taus, forces, res, taus.min(0) - pad, taus.max(0) + pad)
