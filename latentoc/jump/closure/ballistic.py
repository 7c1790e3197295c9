"""Ballistic flight of the sagittal base, integrated instead of collocated (Sect. 2, Eq. 4-5).

In flight no contact force acts, so the base rows of Eq. 3 are momentum conservation:

* the COM follows the parabola ``c(tau) = c_to + cd_to tau + g tau^2 / 2``;
* the angular momentum about the COM is constant. For a sagittal motion its y component is
  ``L = I(y) pd + h(y, yd)``: ``I`` the centroidal inertia about y and ``h`` the momentum of
  the joint motion with the base at rest, both independent of the base pose. So
  ``pd = (L_to - h) / I``, integrated in time for the pitch.

The base then follows from the COM: ``(x, z) = c - (R_y(pitch) r(y))_{x,z}`` with ``r`` the COM
in the base frame. The functions take the joint motion (y, yd, ydd), not latent points, so
they belong to the robot, not to the GPDM.
"""
from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from latentoc.dynamics import SymbolicModel
from latentoc.jump.robot.sagittal_base import _ry
from latentoc.jump.robot.feet import joint_embedding

GRAVITY = np.array([0.0, -9.81])  # (x, z)

__all__ = ["flight_functions", "ballistic_base", "cumulative_trapezoid_matrix", "GRAVITY"]


@lru_cache(maxsize=4)
def flight_functions(sym: SymbolicModel, smap) -> dict[str, ca.Function]:
    """SX Functions of the ballistic flight (module doc):

    * ``momentum(y, yd, b, bd) -> (c[2], cd[2], L)``: COM position and velocity (x, z) and the
      angular momentum about the COM (y axis);
    * ``pitch_rate(y, yd, ydd, L) -> (pd, pdd)`` from ``L = I pd + h``;
    * ``base(y, yd, ydd, p, pd, pdd, c, cd, cdd) -> (b, bd, bdd)`` of the sagittal base.
    """
    E = ca.DM(joint_embedding(smap))
    n = E.shape[1]
    y, yd, ydd = (ca.SX.sym(k, n) for k in ("y", "yd", "ydd"))
    q0 = ca.vertcat(0, 0, 0, 0, 0, 0, 1, E @ y)  # base at the origin, zero pitch
    r = sym.com(q0)  # COM in the base frame
    hg = sym.centroidal_momentum
    inertia = hg(q0, ca.vertcat(0, 0, 0, 0, 1, 0, ca.DM.zeros(E.shape[0])))[4]
    h_joint = hg(q0, ca.vertcat(ca.DM.zeros(6), E @ yd))[4]

    b, bd = ca.SX.sym("b", 3), ca.SX.sym("bd", 3)
    c3 = ca.vertcat(b[0], 0, b[1]) + _ry(b[2]) @ r
    c = c3[[0, 2]]
    momentum = ca.Function("flight_momentum", [y, yd, b, bd],
                           [c, ca.jtimes(c, ca.vertcat(y, b), ca.vertcat(yd, bd)), inertia * bd[2] + h_joint],
                           ["y", "yd", "b", "bd"], ["c", "cd", "L"])

    L = ca.SX.sym("L")
    pd = (L - h_joint) / inertia
    pdd = ca.jtimes(pd, ca.vertcat(y, yd), ca.vertcat(yd, ydd))
    pitch_rate = ca.Function("flight_pitch_rate", [y, yd, ydd, L], [pd, pdd], ["y", "yd", "ydd", "L"], ["pd", "pdd"])

    p, pv, pa = (ca.SX.sym(k) for k in ("p", "pd", "pdd"))
    cc, ccd, ccdd = (ca.SX.sym(k, 2) for k in ("c", "cd", "cdd"))
    rr = _ry(p) @ r
    bb = ca.vertcat(cc[0] - rr[0], cc[1] - rr[2], p)
    zz, zzd, zzdd = ca.vertcat(y, p, cc), ca.vertcat(yd, pv, ccd), ca.vertcat(ydd, pa, ccdd)
    bbd = ca.jtimes(bb, zz, zzd)
    bbdd = ca.jtimes(bb, zz, zzdd) + ca.jtimes(bbd, zz, zzd)
    base = ca.Function("flight_base", [y, yd, ydd, p, pv, pa, cc, ccd, ccdd], [bb, bbd, bbdd],
                       ["y", "yd", "ydd", "p", "pd", "pdd", "c", "cd", "cdd"], ["b", "bd", "bdd"])
    return {"momentum": momentum, "pitch_rate": pitch_rate, "base": base}


def cumulative_trapezoid_matrix(tau: np.ndarray) -> np.ndarray:
    """Matrix M (K x K) with ``(f @ M)[i] = int_0^tau_i f`` by the trapezoid rule on ``tau``."""
    K = len(tau)
    M = np.zeros((K, K))
    for i in range(1, K):
        h = tau[i] - tau[i - 1]
        M[:, i] = M[:, i - 1]
        M[i - 1, i] += h / 2
        M[i, i] += h / 2
    return M


def ballistic_base(fns: dict[str, ca.Function], Y, Yd, Ydd, tau: np.ndarray, b_to, bd_to, y_to, yd_to):
    """Numeric base (b, bd, bdd), each 3 x K, at flight times ``tau`` (0 = takeoff) of the joint
    motion (Y, Yd, Ydd: n x K) from the takeoff base and joint state; the pitch is the trapezoid
    integral of the pitch rate on the ``tau`` grid."""
    K = len(tau)
    c_to, cd_to, L_to = fns["momentum"](y_to, yd_to, b_to, bd_to)
    pd, pdd = fns["pitch_rate"].map(K)(Y, Yd, Ydd, ca.repmat(L_to, 1, K))
    p = b_to[2] + pd @ ca.DM(cumulative_trapezoid_matrix(np.asarray(tau, float)))
    tau_row = ca.DM(np.asarray(tau, float)).T
    g = ca.DM(GRAVITY)
    c = ca.repmat(c_to, 1, K) + cd_to @ tau_row + 0.5 * g @ (tau_row ** 2)
    cd = ca.repmat(cd_to, 1, K) + g @ tau_row
    return [np.asarray(v) for v in fns["base"].map(K)(Y, Yd, Ydd, p, pd, pdd, c, cd, ca.repmat(g, 1, K))]
