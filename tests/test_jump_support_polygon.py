"""Support polygon A_S p + b_S <= 0 (Eq. 35, 36) against known inside/outside points."""
import casadi as ca
import numpy as np

from latentoc.jump.robot.support_polygon import margin, support_polygon, symbolic_rows


def test_rectangle_inside_outside():
    pts = np.array([[-0.1, -0.2], [0.15, -0.2], [0.15, 0.2], [-0.1, 0.2], [0.0, 0.0]])
    A, b = support_polygon(pts)
    assert np.isclose(margin(A, b, [0.0, 0.0]), 0.1)
    assert margin(A, b, [0.14, 0.19]) > 0
    assert margin(A, b, [0.2, 0.0]) < 0 and np.isclose(margin(A, b, [0.2, 0.0]), -0.05)
    assert margin(A, b, [0.0, -0.25]) < 0


def test_symbolic_rows_match_numeric_hull():
    heel, toe = np.array([-0.12, 0.18]), np.array([0.05, 0.21])
    rows = symbolic_rows(heel, toe)
    V = np.array([[heel[0], -heel[1]], [toe[0], -toe[1]], toe, heel])
    A, b = support_polygon(V)
    rng = np.random.default_rng(0)
    for p in rng.uniform(-0.3, 0.3, size=(50, 2)):
        r = np.array(ca.DM(rows(p))).ravel()
        assert (np.max(r) <= 0) == (margin(A, b, p) >= 0)
