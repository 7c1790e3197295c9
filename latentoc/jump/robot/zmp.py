"""Zero-moment point on flat ground z = 0 from the centroidal momentum rate (Eq. 35).

With c the COM, dh = (dP, dL) the rate of the centroidal momentum (linear; angular about
the COM) and gravity g along -z, the total contact wrench is
``f = dP + m g e_z`` and ``n_c = dL`` about the COM.  The point p on z = 0 where the
horizontal moment of the contact wrench vanishes is (Kajita et al., "Introduction to
Humanoid Robotics", Springer 2014, Sect. 3.3; Sardain & Bessonnet, IEEE TSMC-A 2004):

    p_x = c_x - (c_z dP_x + dL_y) / (dP_z + m g)
    p_y = c_y - (c_z dP_y - dL_x) / (dP_z + m g)

For a static pose (dh = 0) the ZMP is the ground projection of the COM.  Works on numpy
arrays and casadi symbols.
"""
from __future__ import annotations

G = 9.81


def zmp(c, dh, mass: float, g: float = G):
    """(p_x, p_y) of the ZMP for COM c (3) and centroidal momentum rate dh (6)."""
    fz = dh[2] + mass * g
    px = c[0] - (c[2] * dh[0] + dh[4]) / fz
    py = c[1] - (c[2] * dh[1] - dh[3]) / fz
    return px, py
