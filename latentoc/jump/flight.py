"""Ballistic flight of the sagittal base, integrated instead of collocated (Sect. 2, Eq. 4-5).

In flight no contact force acts, so the base rows of Eq. 3 are momentum conservation:

* the COM follows the parabola ``c(tau) = c_to + cd_to tau + g tau^2 / 2`` (linear rows);
* the angular momentum about the COM is constant (pitch row).  For a sagittal motion its
  y component is ``L = I(y) pd + h(y, yd)``: ``I`` is the centroidal inertia about the y axis
  and ``h`` the momentum of the joint motion with the base at rest, both independent of the
  base pose (a rotation about y keeps the yy component; base translation adds no angular
  momentum about the COM).  So ``pd = (L_to - h) / I``, integrated in time for the pitch.

The base then follows from the COM: ``(x, z) = c - (R_y(pitch) r(y))_{x,z}`` with ``r`` the
COM in the base frame.  The linear rows hold exactly at every instant and the pitch row up
to the quadrature of ``pd`` (trapezoid), so the flight needs no base variables and no
collocation, which let the old base spline alias between nodes (1 kHz residual 0.3-0.5
body weights with 12 flight nodes, measured in issue 6).
"""
from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from ..dynamics import SymbolicModel
from ..gpdm import GPDM
from .base import _ry
from .contact import joint_embedding

GRAVITY = np.array([0.0, -9.81])  # (x, z)


@lru_cache(maxsize=4)
def flight_functions(sym: SymbolicModel, smap, gpdm: GPDM) -> dict[str, ca.Function]:
    """casadi Functions of the ballistic flight (see module doc).

    * ``momentum(x, xd, b, bd) -> (c[2], cd[2], L)``: COM position and velocity (x, z) and the
      angular momentum about the COM (y) of a state;
    * ``pitch_rate(x, xd, xdd, L) -> (pd, pdd)`` from ``L = I pd + h``;
    * ``base(x, xd, xdd, p, pd, pdd, c, cd, cdd) -> (b, bd, bdd)`` of the sagittal base.

    Cached per (sym, smap, gpdm) objects: the NLP and the 1 kHz export share them.
    """
    d = gpdm.latent_dim
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    E = ca.DM(joint_embedding(smap))
    y = gpdm.mean_function()(x)
    yd = ca.jtimes(y, x, xd)
    q0 = ca.vertcat(0, 0, 0, 0, 0, 0, 1, E @ y)  # base at the origin, zero pitch
    r = sym.com(q0)  # COM in the base frame
    hg = sym.centroidal_momentum
    inertia = hg(q0, ca.vertcat(0, 0, 0, 0, 1, 0, ca.DM.zeros(E.shape[0])))[4]
    h_joint = hg(q0, ca.vertcat(ca.DM.zeros(6), E @ yd))[4]

    b, bd = ca.SX.sym("b", 3), ca.SX.sym("bd", 3)
    R = _ry(b[2])
    c3 = ca.vertcat(b[0], 0, b[1]) + R @ r
    c = c3[[0, 2]]
    z, zd = ca.vertcat(x, b), ca.vertcat(xd, bd)
    momentum = ca.Function("flight_momentum", [x, xd, b, bd], [c, ca.jtimes(c, z, zd), inertia * bd[2] + h_joint],
                           ["x", "xd", "b", "bd"], ["c", "cd", "L"])

    L = ca.SX.sym("L")
    pd = (L - h_joint) / inertia
    pdd = ca.jtimes(pd, ca.vertcat(x, xd), ca.vertcat(xd, xdd))
    pitch_rate = ca.Function("flight_pitch_rate", [x, xd, xdd, L], [pd, pdd], ["x", "xd", "xdd", "L"], ["pd", "pdd"])

    p, pv, pa = (ca.SX.sym(n) for n in ("p", "pd", "pdd"))
    cc, ccd, ccdd = (ca.SX.sym(n, 2) for n in ("c", "cd", "cdd"))
    rr = _ry(p) @ r
    bb = ca.vertcat(cc[0] - rr[0], cc[1] - rr[2], p)
    zz, zzd, zzdd = ca.vertcat(x, p, cc), ca.vertcat(xd, pv, ccd), ca.vertcat(xdd, pa, ccdd)
    bbd = ca.jtimes(bb, zz, zzd)
    bbdd = ca.jtimes(bb, zz, zzdd) + ca.jtimes(bbd, zz, zzd)
    base = ca.Function("flight_base", [x, xd, xdd, p, pv, pa, cc, ccd, ccdd], [bb, bbd, bbdd],
                       ["x", "xd", "xdd", "p", "pd", "pdd", "c", "cd", "cdd"], ["b", "bd", "bdd"])
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


def ballistic_base(fns: dict[str, ca.Function], X, Xd, Xdd, tau: np.ndarray, b_to, bd_to, x_to, xd_to):
    """Base (b, bd, bdd), each 3 x K, at flight times ``tau`` (0 = takeoff) on a latent path.

    ``X, Xd, Xdd`` (d x K) are the latent path at ``tau`` (numeric or casadi); ``b_to, bd_to``
    the base state and ``x_to, xd_to`` the latent state at takeoff.  Works on casadi symbols
    (inside the NLP) and on numbers (the 1 kHz export); the pitch is the trapezoid integral
    of the pitch rate on the ``tau`` grid.
    """
    K = len(tau)
    c_to, cd_to, L_to = fns["momentum"](x_to, xd_to, b_to, bd_to)
    pd, pdd = fns["pitch_rate"].map(K)(X, Xd, Xdd, ca.repmat(L_to, 1, K))
    p = b_to[2] + pd @ ca.DM(cumulative_trapezoid_matrix(np.asarray(tau, float)))
    tau_row = ca.DM(np.asarray(tau, float)).T
    g = ca.DM(GRAVITY)
    c = ca.repmat(c_to, 1, K) + cd_to @ tau_row + 0.5 * g @ (tau_row ** 2)
    cd = ca.repmat(cd_to, 1, K) + g @ tau_row
    cdd = ca.repmat(g, 1, K)
    return fns["base"].map(K)(X, Xd, Xdd, p, pd, pdd, c, cd, cdd)


__all__ = ["flight_functions", "ballistic_base", "cumulative_trapezoid_matrix", "GRAVITY"]
