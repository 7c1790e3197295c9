"""The broad jump's contact constraints over time, from the result schema alone.

From ``trajectory.npz`` (t, q, v, a, the per-foot ``wrench`` at the toe point, ``contact``,
``touchdown``, ``settle``, the contact points (:mod:`.contact_points`: ``contact_points``,
``contact_frames``, the ``*_offset`` arrays), ``friction``, optionally ``point_forces``)
:func:`contact_series` computes with numeric Pinocchio what the solver held: the normal force, the
friction ratio against mu (the cone), each point's, the centre of pressure inside the foot (heel to
toe point), the ZMP (from the centroidal momentum rate) and the ground-projected COM inside the
support polygon of both feet (the convex hull of each foot's heel and toe point, or of all its
points where it names no heel and toe), with the windows where each is enforced (ZMP: landing;
COM: once settled). A margin is the distance inside its region (negative: outside).
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.figure import Figure
from scipy.spatial import ConvexHull, QhullError

from latentoc.intervals import runs
from latentoc.jump.robot.support_polygon import margin, support_polygon
from latentoc.plots.contact_points import ContactPoints, contact_points_of
from latentoc.plots.figure import LIMIT_STYLE, new_figure, panel_axes

POINT_COLOURS = ("C0", "C1", "C2", "C4", "C5", "C6", "C8", "C9")  # no red: the limits' colour
RATIO_LOAD = 1e-3  # body weights: a point's friction ratio is drawn where its f_z is above this

__all__ = ["contact_series", "polygon_margin", "support_vertices", "plot_contact_forces", "plot_contact_margins",
           "plot_zmp_com"]


def polygon_margin(polygon: np.ndarray, p: np.ndarray) -> float:
    """Distance of point p (x, y) inside the convex polygon (k, 2), negative outside."""
    return margin(*support_polygon(polygon), p)


def _polygon_points(points: ContactPoints) -> list[int]:
    """Indices (among both feet's 2 k points) of the support polygon's corners: each foot's heel
    and toe point as the solver's polygon (:func:`latentoc.jump.robot.support_polygon.feet_polygon`), else all."""
    heel, toe = points.index("heel"), points.index("toe")
    ends = [heel, toe] if heel is not None and toe is not None else list(range(points.k))
    return [side * points.k + j for side in range(2) for j in ends]


def support_vertices(P: np.ndarray, count: int) -> np.ndarray:
    """The convex hull (counter-clockwise, x y) of ground points P (m, 2 or 3), its last vertex
    repeated up to ``count`` vertices (a fixed size for every sample); P itself if it has no area."""
    xy = np.asarray(P, dtype=float)[:, :2]
    try:
        V = xy[ConvexHull(xy).vertices]
    except (QhullError, ValueError):
        V = xy
    return np.vstack([V, np.repeat(V[-1:], count - len(V), axis=0)])[:count]


def contact_series(model: pin.Model, traj: Mapping[str, Any]) -> dict[str, Any]:
    """Per sample (NaN where it does not apply): ``normal`` (N, per foot), ``friction_ratio``
    (|f_xy| / f_z), ``point_ratio`` (n, k: each point's tangential / normal force where it
    carries more than ``RATIO_LOAD`` body weights, named by ``point_names``), ``cop_margin`` (m),
    ``zmp`` (n, 2), ``com`` (n, 3), ``zmp_margin``, ``com_margin`` (m), ``polygon`` (n, corners, 2:
    the support polygon, module doc), ``points`` (n, 2 k, 3: both feet's contact points), and the
    masks ``contact``, ``zmp_enforced``, ``com_enforced``."""
    t, Q, V, A = (np.asarray(traj[k], dtype=float) for k in ("t", "q", "v", "a"))
    W = np.asarray(traj["wrench"], dtype=float)
    contact = np.asarray(traj["contact"]).astype(bool)
    feet = contact_points_of(model, traj)
    k = feet.k
    corners = _polygon_points(feet)
    back, front = feet.index("heel"), feet.index("toe")  # the wrench acts at the toe point
    n = len(t)
    P = feet.positions(model, Q)
    data = model.createData()
    mass = sum(i.mass for i in model.inertias)
    g = float(-model.gravity.linear[2])
    nan = np.full(n, np.nan)
    out: dict[str, Any] = {
        "normal": nan.copy(), "friction_ratio": nan.copy(), "cop_margin": nan.copy(), "zmp_margin": nan.copy(),
        "com_margin": nan.copy(), "zmp": np.full((n, 2), np.nan), "com": np.zeros((n, 3)),
        "polygon": np.array([support_vertices(P[i, corners], len(corners)) for i in range(n)]),
        "point_ratio": np.full((n, k), np.nan), "point_names": list(feet.names), "points": P}
    for i in range(n):
        c = pin.centerOfMass(model, data, Q[i])
        out["com"][i] = c
        if not contact[i]:
            continue
        fx, fy, fz, _, my, _ = W[i]
        out["normal"][i] = fz
        if fz > 0:
            out["friction_ratio"][i] = np.hypot(fx, fy) / fz
            x = P[i, :k, 0]
            toe = P[i, front] if front is not None else P[i, int(np.argmax(x))]
            heel_x = x[back] if back is not None else x.min()
            cop = toe[0] - (my + toe[2] * fx) / fz  # on the ground: my = -(cop - toe_x) fz - toe_z fx
            out["cop_margin"][i] = min(cop - heel_x, toe[0] - cop)
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, Q[i], V[i], A[i]).vector
        fz_total = dh[2] + mass * g  # the ZMP on z = 0 (Kajita et al. 2014, Sect. 3.3)
        out["zmp"][i] = (c[0] - (c[2] * dh[0] + dh[4]) / fz_total, c[1] - (c[2] * dh[1] - dh[3]) / fz_total)
        out["zmp_margin"][i] = polygon_margin(out["polygon"][i], out["zmp"][i])
        out["com_margin"][i] = polygon_margin(out["polygon"][i], c)
    if "point_forces" in traj:
        F = np.asarray(traj["point_forces"], dtype=float)  # (n, k, 2): the left foot's (f_x, f_z) per point
        ft, fn = (np.hypot(F[..., 0], F[..., 1]), F[..., 2]) if F.shape[2] == 3 else (np.abs(F[..., 0]), F[..., 1])
        with np.errstate(divide="ignore", invalid="ignore"):  # the ratio of a vanishing force is noise
            out["point_ratio"] = np.where(contact[:, None] & (fn > RATIO_LOAD * mass * g), ft / fn, np.nan)
    out["contact"] = contact
    out["zmp_enforced"] = contact & (t >= float(traj["touchdown"]) - 1e-9)
    out["com_enforced"] = contact & (t >= float(traj.get("settle", traj["touchdown"])) - 1e-9)
    return out


def _shade(ax: Any, t: np.ndarray, mask: np.ndarray, label: str | None) -> None:
    """Shade the time spans where ``mask`` holds."""
    for k, (a, b) in enumerate(runs(mask)):
        ax.axvspan(t[a], t[b - 1], color="0.85", zorder=0, label=label if k == 0 else None)


def _point_names(names: Sequence[str] | None, k: int) -> list[str]:
    """The k points' names (``names``, else point 1, ...)."""
    names = list(names) if names is not None else []
    if len(names) != k:
        names = [f"point {j + 1}" for j in range(k)]
    return names


def plot_contact_forces(t: np.ndarray, wrench: np.ndarray, contact: np.ndarray,
                        point_forces: np.ndarray | None = None, axes: Any = None,
                        point_names: Sequence[str] | None = None) -> Figure:
    """Each foot's contact force at its toe point (world frame): normal f_z and tangential f_x,
    f_y, and with ``point_forces`` (n, k, 2: (f_x, f_z) of one foot's k points, named by
    ``point_names``) every point's normal and tangential force."""
    fig, (ax1, ax2) = panel_axes(axes, "contact_forces", 2, ncols=1)
    t, W = np.asarray(t, dtype=float), np.asarray(wrench, dtype=float)
    on = np.asarray(contact).astype(bool)
    ax1.plot(t, np.where(on, W[:, 2], np.nan), "k-", lw=1.8, label="each foot")
    ax2.plot(t, np.where(on, W[:, 0], np.nan), "k-", lw=1.5, label="$f_x$, each foot")
    ax2.plot(t, np.where(on, W[:, 1], np.nan), "-", color="0.55", lw=1, label="$f_y$, each foot")
    if point_forces is not None:
        F = np.asarray(point_forces, dtype=float)
        fx, fz = F[..., 0], F[..., -1]
        for k, name in enumerate(_point_names(point_names, F.shape[1])):
            colour = POINT_COLOURS[k % len(POINT_COLOURS)]
            ax1.plot(t, np.where(on, fz[:, k], np.nan), lw=1, color=colour, label=name)
            ax2.plot(t, np.where(on, fx[:, k], np.nan), lw=0.9, color=colour, label=f"$f_x$, {name}")
    ax1.axhline(0.0, label="limit $f_z \\geq 0$", **LIMIT_STYLE)
    ax1.set_ylabel("normal force $f_z$ [N]")
    ax2.set_ylabel("tangential force [N]")
    ax2.set_xlabel("t [s]")
    ax1.legend(fontsize=7, ncol=3)
    ax2.legend(fontsize=7, ncol=3)
    if axes is None:
        fig.subplots_adjust(left=0.1, right=0.97, bottom=0.09, top=0.97, hspace=0.12)
    return fig


def plot_contact_margins(t: np.ndarray, series: Mapping[str, Any], friction: float,
                         axes: Any = None) -> Figure:
    """Over time, against their limits (dotted red): the friction ratio of each foot and of each
    contact point (``point_ratio``, ``point_names``) and mu (the cone), the centre of pressure, ZMP
    and COM margins (>= 0 where enforced, shaded)."""
    fig, panels = panel_axes(axes, "contact_margins", 4, ncols=1)
    t = np.asarray(t, dtype=float)
    ax = panels[0]
    ax.plot(t, series["friction_ratio"], "k-", lw=1.5, label="$|f_{xy}| / f_z$, each foot")
    R = np.asarray(series["point_ratio"], dtype=float).reshape(len(t), -1)
    for k, name in enumerate(_point_names(series.get("point_names"), R.shape[1])):
        ax.plot(t, R[:, k], lw=0.8, color=POINT_COLOURS[k % len(POINT_COLOURS)], label=name)
    ax.axhline(friction, label=f"friction cone $\\mu$ = {friction:g}", **LIMIT_STYLE)
    ax.set_ylabel("friction ratio")
    ratios = np.concatenate([np.ravel(series["friction_ratio"]), np.ravel(R)])
    top = float(np.nanmax(ratios)) if np.isfinite(ratios).any() else friction
    ax.set_ylim(0.0, min(max(2.0 * friction, 1.1 * top), 4.0 * friction))  # a spike where f_z -> 0 stays readable
    rows = (("cop_margin", "contact", "centre of pressure\nin the foot [m]"),
            ("zmp_margin", "zmp_enforced", "ZMP in the support\npolygon [m]"),
            ("com_margin", "com_enforced", "COM in the support\npolygon [m]"))
    for ax, (key, window, label) in zip(panels[1:], rows):
        enforced = np.asarray(series[window], dtype=bool)
        values = np.where(series["contact"], series[key], np.nan)
        _shade(ax, t, enforced, "enforced")
        ax.plot(t, np.where(enforced, np.nan, values), "-", color="0.6", lw=1, label="not enforced")
        ax.plot(t, np.where(enforced, values, np.nan), "k-", lw=1.5, label="margin")
        ax.axhline(0.0, label="limit", **LIMIT_STYLE)
        ax.set_ylabel(label, fontsize=8)
        shown = values[enforced] if np.isfinite(values[enforced]).any() else values  # the y range of what is held
        if np.isfinite(shown).any():
            lo, hi = min(float(np.nanmin(shown)), 0.0), max(float(np.nanmax(shown)), 0.0)
            pad = 0.15 * (hi - lo) + 1e-4
            ax.set_ylim(lo - pad, hi + pad)
    for ax in panels:
        ax.legend(fontsize=7, ncol=3, loc="best")
        ax.tick_params(labelsize=7)
    panels[-1].set_xlabel("t [s]")
    if axes is None:
        fig.subplots_adjust(left=0.12, right=0.97, bottom=0.06, top=0.98, hspace=0.15)
    return fig


def plot_zmp_com(zmp: np.ndarray, com: np.ndarray, polygon: np.ndarray, t: np.ndarray | None = None,
                 axes: Any = None) -> Figure:
    """ZMP and ground-projected COM against the support polygon (k, 2) (Eq. 35-36). Left: top
    view (x, y); right: x against time (or sample) with the polygon's x extent shaded."""
    zmp, com = np.atleast_2d(zmp)[:, :2], np.atleast_2d(com)[:, :2]
    poly = np.asarray(polygon, dtype=float)[:, :2]
    if axes is None:
        fig = new_figure("zmp_com")
        ax, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
    else:
        fig, (ax, ax2) = panel_axes(axes, "zmp_com", 2)
    closed = np.vstack([poly, poly[:1]])
    ax.fill(closed[:, 0], closed[:, 1], color="lightgrey", alpha=0.6, label="support polygon")
    ax.plot(closed[:, 0], closed[:, 1], "k-", lw=1)
    ax.plot(zmp[:, 0], zmp[:, 1], "r.-", ms=3, lw=1, label="ZMP")
    ax.plot(com[:, 0], com[:, 1], "b.-", ms=3, lw=1, label="COM (ground projection)")
    ax.plot(com[-1, 0], com[-1, 1], "bs", label="COM at end")
    ax.set_xlabel("x [m]"), ax.set_ylabel("y [m]")
    ax.set_aspect("equal", "datalim")
    ax.legend(fontsize=7)
    ax.set_title("top view", fontsize=9)
    s = np.arange(len(zmp)) if t is None else np.asarray(t, dtype=float)
    ax2.axhspan(poly[:, 0].min(), poly[:, 0].max(), color="lightgrey", alpha=0.6, label="support polygon (x)")
    ax2.plot(s, zmp[:, 0], "r-", label="ZMP x")
    ax2.plot(s, com[:, 0], "b-", label="COM x")
    ax2.set_xlabel("t [s]" if t is not None else "sample")
    ax2.set_ylabel("x [m]")
    ax2.legend(fontsize=7)
    ax2.set_title("forward direction", fontsize=9)
    if axes is None:
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.11, top=0.93, wspace=0.22)
    return fig
