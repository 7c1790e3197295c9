"""The latent space: training points, paths and control points in the variance tube (Fig. 1, 3).

A 3-D latent space shows the tube's surface sigma^2(x) = delta (:func:`tube_mesh`), a 2-D one
the region sigma^2 <= delta; both at equal scale on every axis, so a tube looks as wide as it is.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from latentoc.plots.figure import new_figure

__all__ = ["tube_mesh", "plot_latent_tube", "resample"]


def resample(P: np.ndarray, n: int) -> np.ndarray:
    """n points equally spaced by arc length along the polyline P."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
    if s[-1] <= 0.0:
        return np.repeat(P[:1], n, axis=0)
    u = np.linspace(0.0, s[-1], n)
    return np.column_stack([np.interp(u, s, P[:, k]) for k in range(P.shape[1])])


def _normal_frames(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation-minimising unit normals (n1, n2) along the 3-D curve C."""
    T = np.gradient(C, axis=0)
    T /= np.maximum(np.linalg.norm(T, axis=1, keepdims=True), 1e-12)
    n1 = np.empty_like(C)
    a = np.eye(3)[int(np.argmin(np.abs(T[0])))]
    v = a - (a @ T[0]) * T[0]
    n1[0] = v / np.linalg.norm(v)
    for i in range(1, len(C)):
        v = n1[i - 1] - (n1[i - 1] @ T[i]) * T[i]
        nv = np.linalg.norm(v)
        if nv < 1e-9:  # tangent reversed: take any perpendicular
            a = np.eye(3)[int(np.argmin(np.abs(T[i])))]
            v = a - (a @ T[i]) * T[i]
            nv = np.linalg.norm(v)
        n1[i] = v / nv
    return n1, np.cross(T, n1)


def _variance(gpdm: Any, pts: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """gpdm.variance on many points, in chunks to bound memory."""
    pts = np.asarray(pts, dtype=float).reshape(-1, gpdm.latent_dim)
    return np.concatenate([np.atleast_1d(gpdm.variance(pts[i:i + chunk])) for i in range(0, len(pts), chunk)])


def tube_mesh(gpdm: Any, delta: float, centre: np.ndarray | None = None, n_along: int = 60,
              n_around: int = 18, r_max: float | None = None, n_scan: int = 16,
              iterations: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Surface sigma^2(x) = delta of the variance tube (Eq. 29) around a 3-D curve.

    Rays leave ``n_along`` points of ``centre`` (default: the first training latent trajectory)
    in ``n_around`` directions normal to the curve; on each, the first radius where sigma^2
    reaches delta is bracketed on ``n_scan`` radii in (0, r_max] and bisected. Returns ``points``
    (n_along, n_around, 3) and ``on_surface`` (n_along, n_around): a ray starting outside the tube
    gets radius 0 and one that never leaves it within r_max gets r_max; both are marked False.
    """
    if gpdm.latent_dim != 3:
        raise ValueError("tube_mesh needs a 3-D latent space (use contours in 2-D)")
    C = resample(np.asarray(gpdm.latent_trajectories()[0] if centre is None else centre, dtype=float), int(n_along))
    if r_max is None:
        r_max = 0.5 * float(np.max(np.ptp(gpdm.X, axis=0)))
    n1, n2 = _normal_frames(C)
    th = np.linspace(0.0, 2.0 * np.pi, int(n_around), endpoint=False)
    U = np.cos(th)[None, :, None] * n1[:, None, :] + np.sin(th)[None, :, None] * n2[:, None, :]
    na, nr = U.shape[:2]
    radii = np.linspace(0.0, r_max, int(n_scan) + 1)
    pts = C[:, None, None, :] + radii[None, None, :, None] * U[:, :, None, :]
    outside = _variance(gpdm, pts).reshape(na, nr, -1) > delta
    first = np.argmax(outside, axis=2)  # index of the first radius outside
    crosses = outside.any(axis=2) & (first > 0)
    lo = np.where(crosses, radii[np.maximum(first - 1, 0)], 0.0)
    hi = np.where(crosses, radii[first], 0.0)
    for _ in range(int(iterations)):
        mid = 0.5 * (lo + hi)
        out = _variance(gpdm, C[:, None, :] + mid[..., None] * U).reshape(na, nr) > delta
        hi = np.where(out, mid, hi)
        lo = np.where(out, lo, mid)
    r = np.where(crosses, 0.5 * (lo + hi), np.where(outside[:, :, 0], 0.0, r_max))
    return C[:, None, :] + r[..., None] * U, crosses


def _as_dict(x: Mapping[str, np.ndarray] | np.ndarray | None, label: str) -> dict[str, np.ndarray]:
    if x is None:
        return {}
    if isinstance(x, Mapping):
        return {k: np.asarray(v, dtype=float) for k, v in x.items()}
    return {label: np.asarray(x, dtype=float)}


def _equal_box(ax: Any, points: np.ndarray, pad: float = 0.05) -> None:
    """3-D limits around ``points`` at one scale on every axis: each axis spans its data plus the
    same margin (``pad`` x the largest span), and the box's sides are proportional to those spans."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    margin = pad * max(float(np.max(hi - lo)), 1e-9)
    lo, hi = lo - margin, hi + margin
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))


def plot_latent_tube(gpdm: Any, delta: float, paths: Mapping[str, np.ndarray] | np.ndarray | None = None,
                     control_points: Mapping[str, np.ndarray] | np.ndarray | None = None,
                     title: str | None = None, axes: Axes | None = None) -> Figure:
    """Training latent points, optional paths ({label: (n, d)}) and control points, and the tube
    sigma^2 <= delta (Fig. 1, 3), at equal scale on every axis. ``axes``: a 3-D axes for a 3-D
    latent space (``projection="3d"``), a 2-D one for d = 2."""
    d = gpdm.latent_dim
    if d not in (2, 3):
        raise ValueError(f"latent_dim must be 2 or 3, got {d}")
    curves, ctrl = _as_dict(paths, "path"), _as_dict(control_points, "control points")
    styles = ["-", "--", ":", "-."]
    colour = {name: f"C{i}" for i, name in enumerate(curves)}
    for j, name in enumerate(ctrl):  # control points take the colour of their path
        colour[name] = next((colour[c] for c in curves if name.startswith(c)), f"C{len(curves) + j}")
    ax: Any  # a 3-D axes (mpl_toolkits.mplot3d) or a 2-D one
    fig: Any
    if axes is None:
        fig = new_figure("latent_tube")
        ax = fig.add_subplot(projection="3d") if d == 3 else fig.add_subplot()
    else:
        ax, fig = axes, axes.get_figure()
    if (d == 3) != (getattr(ax, "name", "") == "3d"):
        raise ValueError(f"a {d}-D latent space needs {'a 3-D' if d == 3 else 'a 2-D'} axes")
    shown = [gpdm.X] + list(curves.values()) + list(ctrl.values())
    if d == 3:
        ax.computed_zorder = False  # paths and points over the translucent tube
        for T in gpdm.latent_trajectories():
            P, ok = tube_mesh(gpdm, delta, centre=T)
            shown.append(P[ok])
            P = np.concatenate([P, P[:, :1]], axis=1)  # close the tube around
            ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="gold", alpha=0.35, linewidth=0, shade=True,
                            zorder=1)
        X = gpdm.X
        ax.scatter(X[:, 0], X[:, 1], X[:, 2], s=1.5, c="k", label="training latent points", zorder=2)
        for i, (name, c) in enumerate(curves.items()):
            ax.plot(c[:, 0], c[:, 1], c[:, 2], styles[i % 4], color=colour[name], lw=2, label=name, zorder=3)
        for name, c in ctrl.items():
            ax.scatter(c[:, 0], c[:, 1], c[:, 2], s=40, color=colour[name], edgecolors="k", depthshade=False,
                       label=name, zorder=4)
        ax.set_xlabel("$x_1$"), ax.set_ylabel("$x_2$"), ax.set_zlabel("$x_3$")
        _equal_box(ax, np.vstack(shown))
        ax.locator_params(nbins=5)  # short axes keep readable ticks
    else:
        allp = np.vstack(shown)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        pad = 0.3 * float(np.max(hi - lo)) + 1e-9
        g1, g2 = np.meshgrid(np.linspace(lo[0] - pad, hi[0] + pad, 200), np.linspace(lo[1] - pad, hi[1] + pad, 200))
        V = _variance(gpdm, np.column_stack([g1.ravel(), g2.ravel()])).reshape(g1.shape)
        ax.contourf(g1, g2, V, levels=[V.min() - 1.0, delta], colors=["gold"], alpha=0.35)
        ax.contour(g1, g2, V, levels=[delta], colors=["goldenrod"], linewidths=1)
        ax.plot(gpdm.X[:, 0], gpdm.X[:, 1], "k.", ms=3, label="training latent points")
        for i, (name, c) in enumerate(curves.items()):
            ax.plot(c[:, 0], c[:, 1], styles[i % 4], color=colour[name], lw=2, label=name)
        for name, c in ctrl.items():
            ax.plot(c[:, 0], c[:, 1], "o", color=colour[name], mec="k", ms=7, label=name)
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        ax.set_aspect("equal", "datalim")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or f"variance tube $\\sigma^2(x) \\leq \\delta = {delta:.3g}$")
    return fig
