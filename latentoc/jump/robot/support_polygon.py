"""Support polygon inequalities A_S p + b_S <= 0 (Eq. 35, 36).

The polygon is the convex hull of the ground contact points of both feet.  For the
numeric check the hull is computed (scipy ConvexHull); inside the NLP the vertices are
given in counter-clockwise order (heel_R, toe_R, toe_L, heel_L: x forward, y left), which
is the hull of the two symmetric feet, and each edge (v_i, v_i+1) gives the row
``cross(v_i+1 - v_i, p - v_i) >= 0``, i.e. ``A_S p + b_S <= 0`` with the row normalised.
The margin of a point is ``-max(A_S p + b_S)`` (positive inside, in metres).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull


def polygon_from_vertices(V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A_S (k x 2), b_S (k) of a convex polygon with counter-clockwise vertices V (k x 2)."""
    V = np.asarray(V, float)
    E = np.roll(V, -1, axis=0) - V
    n = np.column_stack([E[:, 1], -E[:, 0]])  # outward normal of a CCW edge
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return n, -np.sum(n * V, axis=1)


def feet_polygon(heel_l: np.ndarray, toe_l: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A_S, b_S of the symmetric feet's polygon from the left heel and toe (x, y), edges in the NLP's
    order (:func:`symbolic_rows`: heel_R -> toe_R, the front, toe_L -> heel_L, the back)."""
    (hx, hy), (tx, ty) = heel_l[:2], toe_l[:2]
    return polygon_from_vertices(np.array([[hx, -hy], [tx, -ty], [tx, ty], [hx, hy]]))


def support_polygon(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A_S, b_S of the convex hull of ground points (n x 2 or n x 3, z ignored)."""
    P = np.asarray(points, float)[:, :2]
    hull = ConvexHull(P)
    return polygon_from_vertices(P[hull.vertices])  # scipy gives CCW order in 2-D


def margin(A: np.ndarray, b: np.ndarray, p: np.ndarray) -> float:
    """Distance-like margin -max(A p + b): > 0 inside."""
    return float(-np.max(A @ np.asarray(p, float)[:2] + b))


def symbolic_rows(heel_l, toe_l):
    """Rows A_S p + b_S (casadi/numpy) for the symmetric feet, from the left heel and toe (x, y).

    Returns a function p -> list of expressions, each <= 0 inside.
    """
    import casadi as ca
    V = [(heel_l[0], -heel_l[1]), (toe_l[0], -toe_l[1]), (toe_l[0], toe_l[1]), (heel_l[0], heel_l[1])]

    def rows(p):
        out = []
        for i in range(4):
            (x0, y0), (x1, y1) = V[i], V[(i + 1) % 4]
            ex, ey = x1 - x0, y1 - y0
            norm = ca.sqrt(ex * ex + ey * ey)
            out.append(-(ex * (p[1] - y0) - ey * (p[0] - x0)) / norm)
        return ca.vertcat(*out)
    return rows
