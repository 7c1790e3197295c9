"""The spline a jump method solves along: the latent path, or the 37 joints themselves.

* ``"latent"``: the latent spline x(t) and the GPDM mean through it (Eq. 18, 23-28,
  :class:`~latentoc.latent.gp_layer.GPLayer`), the tube sigma^2 <= delta (Eq. 29) held;
* ``"joint-range"``: the full configuration-space baseline of Sect. 4.1.1 on the humanoid. The
  spline is the joint path (y = x, :class:`~latentoc.latent.gp_layer.IdentityLayer`) with as many
  control points and the same knots as the latent spline, starting from the least-squares fit of
  the training jump's 37 learned joints (:func:`..problem.setup`);
  each free control point stays within +-k degrees of that fit (Table 2's "joint range"), and the
  centre joints that flip sign under the mirror stay zero (a symmetric motion has none). No tube.

With ``[options] leg_residual`` (deg) the latent path carries a residual beside it: the path is
(x, r), the left leg's sagittal joints are the GP mean's plus r (:class:`~latentoc.latent.residual_layer.ResidualLayer`),
each free control point of r within +-leg_residual of zero, the tube on x alone. With the planted
foot by construction (:mod:`..closure.planted_legs`) the base follows the legs, and this residual is what lets them
carry a physical push-off (docs/broad-jump.md, "The path").

Every other row of the jump (contact, flight, ZMP, COM, torque limits, friction) is the same NLP.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from latentoc.gpdm import GPDM
from latentoc.latent.spline import BSpline
from latentoc.latent.gp_layer import GPLayer, IdentityLayer, Layer
from latentoc.latent.residual_layer import ResidualLayer

__all__ = ["JumpPath", "METHODS", "PATH_SMOOTHING", "initial_latent_path", "latent_path", "joint_range_path",
           "leg_residual_path"]

METHODS = ("latent", "joint-range")
PATH_SMOOTHING = 1e-3  # weight of int ||x''||^2 dt in the initial latent path fit


@dataclass(frozen=True)
class JumpPath:
    """A method's spline: its layer, start control points (the end points stay fixed) and the
    half-widths of the free control points' bounds around them (None: unbounded)."""

    method: str
    layer: Layer
    P: np.ndarray  # (n_control x d)
    P_range: np.ndarray | None = None  # (n_control - 2 x d)

    @property
    def has_tube(self) -> bool:
        """Whether the path carries the tube (Eq. 29): only the latent path has a sigma^2."""
        return self.layer.has_tube


def latent_path(layer: GPLayer, P: np.ndarray) -> JumpPath:
    """The latent spline from the control points P of the training fit."""
    return JumpPath("latent", layer, np.asarray(P, float))


def joint_range_path(P_joint: np.ndarray, joint_range_deg: float, fixed: np.ndarray) -> JumpPath:
    """The joint spline from the training joints' fit ``P_joint`` (n_control x 37), each free
    control point within +-``joint_range_deg`` (checked: :func:`latentoc.problem.kinds.joint_range`) of it;
    the joints ``fixed`` (indices) stay there."""
    P = np.asarray(P_joint, float)
    half = np.full((P.shape[0] - 2, P.shape[1]), np.radians(joint_range_deg))
    half[:, np.asarray(fixed, int)] = 0.0
    return JumpPath("joint-range", IdentityLayer(P.shape[1]), P, half)


def leg_residual_path(gpdm: GPDM, P: np.ndarray, joints: list[int], bound_deg: float) -> JumpPath:
    """The latent spline from the training fit's control points P with a residual on the learned
    joints ``joints``, zero at both ends, its free control points within +-``bound_deg``."""
    P = np.asarray(P, float)
    r = len(joints)
    half = np.hstack([np.full((P.shape[0] - 2, P.shape[1]), np.inf), np.full((P.shape[0] - 2, r), np.radians(bound_deg))])
    return JumpPath("latent", ResidualLayer(gpdm, np.asarray(joints, int)), np.hstack([P, np.zeros((P.shape[0], r))]), half)


def initial_latent_path(sp: BSpline, t: np.ndarray, X: np.ndarray, smoothing: float, keep: np.ndarray) -> np.ndarray:
    """Control points of the smoothed fit (:meth:`BSpline.fit` with ``smoothing * int ||x''||^2``)
    whose value and velocity at the times ``keep`` (takeoff, touchdown) equal the plain fit's, so
    the smoothing does not slow the push-off. Equality-constrained least squares (KKT system)."""
    plain = sp.fit(t, X)
    if smoothing <= 0:
        return plain
    S = sp.smoothing_rows(smoothing)
    A = np.vstack([sp.basis(t), S])
    b = np.vstack([X, np.zeros((S.shape[0], X.shape[1]))])
    C = np.vstack([sp.basis(keep, 0), sp.basis(keep, 1)])
    d = C @ plain
    P = plain.copy()  # the end control points stay (the end poses)
    b = b - A[:, [0, -1]] @ P[[0, -1]]
    d = d - C[:, [0, -1]] @ P[[0, -1]]
    A, C = A[:, 1:-1], C[:, 1:-1]
    n, m = A.shape[1], C.shape[0]
    K = np.block([[2 * A.T @ A, C.T], [C, np.zeros((m, m))]])
    P[1:-1] = np.linalg.solve(K, np.vstack([2 * A.T @ b, d]))[:n]
    return P
