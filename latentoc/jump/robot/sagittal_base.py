"""Sagittal-plane floating base (x, z, pitch) of the jumping humanoid.

Design choice: the base is *not* in the latent space and the jump is
left-right symmetric, so the base is restricted to the sagittal plane: position
(x, 0, z), orientation a rotation by ``pitch`` about the world y axis.  The
free-flyer configuration is built from it (quaternion (0, sin(p/2), 0, cos(p/2)),
so there are no raw quaternion decision variables), and a mirror-symmetric joint
motion on the symmetrised skeleton keeps every lateral quantity (y, roll, yaw,
lateral force, roll and yaw moments) identically zero.

Pinocchio's free-flyer velocity is expressed in the *local* base frame:
``v_lin = R^T [xd, 0, zd]``, ``w = [0, pd, 0]``, and its acceleration is the time
derivative of that local twist: ``a_lin = R^T [xdd, 0, zdd] - w x v_lin``,
``a_ang = [0, pdd, 0]`` (Eq. 3's floating-base rows use these coordinates).
"""
from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np


def _ry(p):
    c, s = ca.cos(p), ca.sin(p)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


@lru_cache(maxsize=1)
def base_function() -> ca.Function:
    """casadi.Function (b[3], bd[3], bdd[3]) -> (q7, v6, a6) of the free-flyer."""
    b, bd, bdd = ca.SX.sym("b", 3), ca.SX.sym("bd", 3), ca.SX.sym("bdd", 3)
    R = _ry(b[2])
    q7 = ca.vertcat(b[0], 0, b[1], 0, ca.sin(b[2] / 2), 0, ca.cos(b[2] / 2))
    vl = R.T @ ca.vertcat(bd[0], 0, bd[1])
    w = ca.vertcat(0, bd[2], 0)
    al = R.T @ ca.vertcat(bdd[0], 0, bdd[1]) - ca.cross(w, vl)
    v6 = ca.vertcat(vl, w)
    a6 = ca.vertcat(al, 0, bdd[2], 0)
    return ca.Function("sagittal_base", [b, bd, bdd], [q7, v6, a6], ["b", "bd", "bdd"], ["q", "v", "a"])


def base_to_freeflyer(b, bd=None, bdd=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Numeric (q7, v6, a6) for arrays b, bd, bdd of shape (n, 3) (or (3,))."""
    b = np.atleast_2d(np.asarray(b, float))
    bd = np.zeros_like(b) if bd is None else np.atleast_2d(np.asarray(bd, float))
    bdd = np.zeros_like(b) if bdd is None else np.atleast_2d(np.asarray(bdd, float))
    f = base_function().map(b.shape[0])
    q, v, a = f(b.T, bd.T, bdd.T)
    return np.array(q).T, np.array(v).T, np.array(a).T


def freeflyer_to_base(q7: np.ndarray) -> np.ndarray:
    """(x, z, pitch) of free-flyer poses (n, 7): pitch from the rotation's xz block.

    Lateral position, roll and yaw are dropped (they vanish for symmetric motions).
    """
    from scipy.spatial.transform import Rotation

    q7 = np.atleast_2d(np.asarray(q7, float))
    R = Rotation.from_quat(q7[:, 3:7]).as_matrix()
    pitch = np.arctan2(R[:, 0, 2], R[:, 2, 2])
    return np.column_stack([q7[:, 0], q7[:, 2], pitch])
