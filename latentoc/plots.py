"""Figures of latentoc results as PNG files (Kang & Park 2015, Fig. 1, 3, 4, 5, 7).

Every ``plot_*`` function draws on its own :class:`matplotlib.figure.Figure`
(no pyplot state), writes a PNG of a fixed pixel size (``FIGSIZES[name]`` inches
times ``DPI``) and returns the path.  :func:`plot_solution` writes the set that
fits a solved problem from its ``result.json`` and ``trajectory.npz``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from .results import Result

__all__ = [
    "DPI", "FIGSIZES", "pixel_size", "tube_mesh", "joint_positions", "skeleton_segments",
    "plot_latent_tube", "plot_joint_curves", "plot_torques", "plot_contact_forces",
    "plot_zmp_com", "plot_gain_vs_tube", "plot_start_poses", "plot_stick_frames", "plot_solution",
    "frame_indices", "PLANES", "SIDE_COLOURS",
]

DPI = 100
FIGSIZES: dict[str, tuple[float, float]] = {
    "latent_tube": (8.0, 7.0),
    "joint_curves": (12.0, 8.0),
    "torques": (12.0, 8.0),
    "contact_forces": (10.0, 6.0),
    "zmp_com": (12.0, 5.0),
    "gain_vs_tube": (10.0, 4.5),
    "start_poses": (12.0, 5.0),
    "stick_frames": (14.0, 3.5),  # per row of frames
}
PLANES = {"xz": (0, 2), "yz": (1, 2), "xy": (0, 1)}


def pixel_size(name: str, rows: int = 1) -> tuple[int, int]:
    """(width, height) in pixels of the PNG written by ``plot_<name>``.

    ``rows`` (motions drawn) only matters for ``stick_frames``, whose height is
    per row.
    """
    w, h = FIGSIZES[name]
    if name == "stick_frames":
        h *= rows
    return int(round(w * DPI)), int(round(h * DPI))


def _figure(name: str) -> Figure:
    return Figure(figsize=FIGSIZES[name], dpi=DPI)


def _save(fig: Figure, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=DPI, format="png")
    return path


# ----------------------------------------------------------------- tube mesh
def _resample(P: np.ndarray, n: int) -> np.ndarray:
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
            v, nv = a - (a @ T[i]) * T[i], np.linalg.norm(a - (a @ T[i]) * T[i])
        n1[i] = v / nv
    n2 = np.cross(T, n1)
    return n1, n2


def _variance(gpdm: Any, pts: np.ndarray, chunk: int = 2048) -> np.ndarray:
    """gpdm.variance on many points, in chunks to bound memory."""
    pts = np.asarray(pts, dtype=float).reshape(-1, gpdm.latent_dim)
    return np.concatenate([np.atleast_1d(gpdm.variance(pts[i:i + chunk]))
                           for i in range(0, len(pts), chunk)])


def tube_mesh(gpdm: Any, delta: float, centre: np.ndarray | None = None, n_along: int = 60,
              n_around: int = 18, r_max: float | None = None, n_scan: int = 16,
              iterations: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """Surface sigma^2(x) = delta of the variance tube (Eq. 29) around a 3-D curve.

    Rays leave ``n_along`` points of ``centre`` (default: the first training
    latent trajectory) in ``n_around`` directions normal to the curve; on each,
    the first radius where sigma^2 reaches delta is bracketed on a scan of
    ``n_scan`` radii in (0, r_max] and bisected.  Returns ``points``
    (n_along, n_around, 3) and ``on_surface`` (n_along, n_around) booleans: a
    ray whose start lies outside the tube gets radius 0 and one that never
    leaves it within r_max gets r_max; both are marked False.
    """
    if gpdm.latent_dim != 3:
        raise ValueError("tube_mesh needs a 3-D latent space (use contours in 2-D)")
    C = np.asarray(gpdm.latent_trajectories()[0] if centre is None else centre, dtype=float)
    C = _resample(C, int(n_along))
    if r_max is None:
        r_max = 0.5 * float(np.max(np.ptp(gpdm.X, axis=0)))
    n1, n2 = _normal_frames(C)
    th = np.linspace(0.0, 2.0 * np.pi, int(n_around), endpoint=False)
    U = np.cos(th)[None, :, None] * n1[:, None, :] + np.sin(th)[None, :, None] * n2[:, None, :]
    na, nr = U.shape[:2]
    radii = np.linspace(0.0, r_max, int(n_scan) + 1)
    pts = C[:, None, None, :] + radii[None, None, :, None] * U[:, :, None, :]
    var = _variance(gpdm, pts).reshape(na, nr, -1) - delta
    outside = var > 0.0
    first = np.argmax(outside, axis=2)  # index of the first radius outside
    crosses = outside.any(axis=2) & (first > 0)
    lo = np.where(crosses, radii[np.maximum(first - 1, 0)], 0.0)
    hi = np.where(crosses, radii[first], 0.0)
    for _ in range(int(iterations)):
        mid = 0.5 * (lo + hi)
        v = _variance(gpdm, C[:, None, :] + mid[..., None] * U)
        out = v.reshape(na, nr) > delta
        hi = np.where(out, mid, hi)
        lo = np.where(out, lo, mid)
    r = np.where(crosses, 0.5 * (lo + hi), np.where(outside[:, :, 0], 0.0, r_max))
    return C[:, None, :] + r[..., None] * U, crosses


# ---------------------------------------------------------------- kinematics
def joint_positions(model: pin.Model, q: np.ndarray) -> np.ndarray:
    """World positions (njoints, 3) of every joint placement oMi (numeric FK)."""
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    return np.array([data.oMi[i].translation for i in range(model.njoints)])


def _bones(model: pin.Model) -> list[tuple[str, int, str, int, str]]:
    """(parent kind, index, child kind, index, child name) of every stick-figure bone."""
    out = [("joint", int(model.parents[i]), "joint", i, model.names[i])
           for i in range(1, model.njoints)
           if not (model.parents[i] == 0 and model.joints[i].nq == 7)]  # free flyer: no bone
    out += [("joint", int(f.parentJoint), "frame", k, f.name)
            for k, f in enumerate(model.frames) if f.type == pin.FrameType.OP_FRAME]
    return out


def _side(model: pin.Model, name: str) -> str:
    """'left', 'right' or 'centre' from CMU-style l/r name prefixes."""
    names = set(model.names) | {f.name for f in model.frames}
    if name[:1] in "lr" and ("rl"["lr".index(name[0])] + name[1:]) in names:
        return "left" if name[0] == "l" else "right"
    return "centre"


def skeleton_segments(model: pin.Model, q: np.ndarray,
                      return_names: bool = False) -> np.ndarray | tuple[np.ndarray, list[str]]:
    """Bones of the stick figure as (k, 2, 3) world segments (numeric FK).

    Each joint is joined to its parent joint (not a free-flyer base to the
    world), and each operational frame (the bone ends, e.g. ``lhand_end``) to
    its parent joint; zero-length segments are dropped.  With
    ``return_names`` also the child joint/frame name of each segment.
    """
    data = model.createData()
    pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
    pin.updateFramePlacements(model, data)
    segs, names = [], []
    for _, a, kind, b, name in _bones(model):
        end = data.oMi[b] if kind == "joint" else data.oMf[b]
        seg = (data.oMi[a].translation, end.translation)
        if np.linalg.norm(seg[1] - seg[0]) > 1e-9:
            segs.append(seg)
            names.append(name)
    S = np.array(segs, dtype=float).reshape(-1, 2, 3)
    return (S, names) if return_names else S


# ------------------------------------------------------------------- figures
def _as_dict(x: Any, label: str) -> dict[str, np.ndarray]:
    if x is None:
        return {}
    if isinstance(x, Mapping):
        return {k: np.asarray(v, dtype=float) for k, v in x.items()}
    return {label: np.asarray(x, dtype=float)}


def plot_latent_tube(gpdm: Any, delta: float, path: str | Path,
                     paths: Mapping[str, np.ndarray] | np.ndarray | None = None,
                     control_points: Mapping[str, np.ndarray] | np.ndarray | None = None,
                     title: str | None = None) -> Path:
    """Training latent points, optional paths and control points, and the tube at delta (Fig. 1, 3).

    3-D latent spaces show the tube surface from :func:`tube_mesh`; 2-D ones
    the filled region sigma^2 <= delta on a grid.
    """
    fig = _figure("latent_tube")
    d = gpdm.latent_dim
    curves = _as_dict(paths, "path")
    ctrl = _as_dict(control_points, "control points")
    styles = ["-", "--", ":", "-."]
    colour = {name: f"C{i}" for i, name in enumerate(curves)}
    for j, name in enumerate(ctrl):  # control points take the colour of their path
        colour[name] = next((colour[c] for c in curves if name.startswith(c)), f"C{len(curves) + j}")
    if d == 3:
        ax = fig.add_subplot(projection="3d")
        ax.computed_zorder = False  # draw paths and points over the translucent tube
        shown = [gpdm.X] + list(curves.values()) + list(ctrl.values())
        for T in gpdm.latent_trajectories():
            P, ok = tube_mesh(gpdm, delta, centre=T)
            shown.append(P[ok])
            P = np.concatenate([P, P[:, :1]], axis=1)  # close the tube around
            ax.plot_surface(P[..., 0], P[..., 1], P[..., 2], color="gold", alpha=0.35,
                            linewidth=0, shade=True, zorder=1)
        X = gpdm.X
        ax.scatter(X[:, 0], X[:, 1], X[:, 2], s=1.5, c="k", label="training latent points", zorder=2)
        for i, (name, c) in enumerate(curves.items()):
            ax.plot(c[:, 0], c[:, 1], c[:, 2], styles[i % 4], color=colour[name], lw=2, label=name,
                    zorder=3)
        for name, c in ctrl.items():
            ax.scatter(c[:, 0], c[:, 1], c[:, 2], s=40, color=colour[name], edgecolors="k",
                       depthshade=False, label=name, zorder=4)
        ax.set_xlabel("$x_1$"), ax.set_ylabel("$x_2$"), ax.set_zlabel("$x_3$")
        allp = np.vstack(shown)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        ext = np.maximum(hi - lo, 1e-9)
        ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
        ax.set_box_aspect(np.maximum(ext, 0.3 * ext.max()))  # near-equal scales
    elif d == 2:
        ax = fig.add_subplot()
        pts = [gpdm.X] + list(curves.values()) + list(ctrl.values())
        allp = np.vstack(pts)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        pad = 0.3 * (hi - lo) + 1e-9
        g1, g2 = np.meshgrid(np.linspace(lo[0] - pad[0], hi[0] + pad[0], 200),
                             np.linspace(lo[1] - pad[1], hi[1] + pad[1], 200))
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
    else:
        raise ValueError(f"latent_dim must be 2 or 3, got {d}")
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(title or f"variance tube $\\sigma^2(x) \\leq \\delta = {delta:.3g}$")
    return _save(fig, path)


def _grid(fig: Figure, n: int, ncols: int = 4) -> list:
    ncols = min(ncols, max(n, 1))
    nrows = int(np.ceil(n / ncols))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    return list(axes.ravel()[:n])


def _curves(name: str, t: np.ndarray, y: Mapping[str, np.ndarray] | np.ndarray,
            names: Sequence[str], path: str | Path, ylabel: str, scale: float = 1.0,
            limits: tuple[np.ndarray, np.ndarray] | None = None) -> Path:
    fig = _figure(name)
    series = _as_dict(y, "")
    t = np.asarray(t, dtype=float)
    for k, Y in series.items():
        if Y.shape != (len(t), len(names)):
            raise ValueError(f"{k or 'values'}: expected shape {(len(t), len(names))}, got {Y.shape}")
    axes = _grid(fig, len(names))
    for j, ax in enumerate(axes):
        for i, (label, Y) in enumerate(series.items()):
            ax.plot(t, scale * Y[:, j], ["-", "--", ":", "-."][i % 4], lw=1.5, label=label or None)
        if limits is not None:
            for lim in limits:
                ax.axhline(scale * float(np.asarray(lim)[j]), color="r", ls=":", lw=1)
        ax.set_title(names[j], fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in axes[-min(4, len(axes)):]:
        ax.set_xlabel("t [s]", fontsize=8)
    fig.supylabel(ylabel)
    if len(series) > 1 and axes:
        axes[0].legend(fontsize=7)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.07, top=0.95, wspace=0.3, hspace=0.35)
    return _save(fig, path)


def plot_joint_curves(t: np.ndarray, q: Mapping[str, np.ndarray] | np.ndarray,
                      names: Sequence[str], path: str | Path) -> Path:
    """Joint angles in degrees, one panel per joint; ``q`` (n, len(names)) or {label: q}."""
    return _curves("joint_curves", t, q, names, path, "joint angle [deg]", np.degrees(1.0))


def plot_torques(t: np.ndarray, tau: Mapping[str, np.ndarray] | np.ndarray,
                 names: Sequence[str], path: str | Path,
                 limits: tuple[np.ndarray, np.ndarray] | None = None) -> Path:
    """Joint torques [N m], one panel per joint, with optional (tau_min, tau_max) lines."""
    return _curves("torques", t, tau, names, path, "torque [N m]", 1.0, limits)


def plot_contact_forces(t: np.ndarray, forces: np.ndarray, names: Sequence[str],
                        path: str | Path) -> Path:
    """Contact forces (n, n_contacts, 3 or 6) in the world frame: normal and tangential parts."""
    F = np.asarray(forces, dtype=float)
    if F.ndim == 2:
        F = F.reshape(len(F), len(names), -1)
    if F.shape[:2] != (len(t), len(names)) or F.shape[2] < 3:
        raise ValueError(f"forces: expected shape ({len(t)}, {len(names)}, 3 or 6), got {F.shape}")
    fig = _figure("contact_forces")
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for k, name in enumerate(names):
        ax1.plot(t, F[:, k, 2], label=name)
        ax2.plot(t, np.linalg.norm(F[:, k, :2], axis=1), label=name)
    ax1.plot(t, F[:, :, 2].sum(axis=1), "k--", lw=1, label="total")
    ax1.set_ylabel("normal force $f_z$ [N]")
    ax2.set_ylabel("tangential $|f_{xy}|$ [N]")
    ax2.set_xlabel("t [s]")
    ax1.legend(fontsize=7, ncol=2)
    fig.subplots_adjust(left=0.1, right=0.97, bottom=0.09, top=0.97, hspace=0.12)
    return _save(fig, path)


def plot_zmp_com(zmp: np.ndarray, com: np.ndarray, polygon: np.ndarray, path: str | Path,
                 t: np.ndarray | None = None) -> Path:
    """ZMP and ground-projected COM against the support polygon (k, 2) (Eq. 35-36).

    Left: top view (x, y).  Right: x against time with the polygon's x extent
    shaded (the sagittal picture of a jump); without ``t``, against sample index.
    """
    zmp, com = np.atleast_2d(zmp)[:, :2], np.atleast_2d(com)[:, :2]
    poly = np.asarray(polygon, dtype=float)[:, :2]
    fig = _figure("zmp_com")
    ax, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1.3]})
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
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.11, top=0.93, wspace=0.22)
    return _save(fig, path)


def _log_x(ax: Any, x: np.ndarray) -> None:
    """Log x axis; minor tick labels only when the data span less than a decade."""
    ax.set_xscale("log")
    if np.max(x) >= 10.0 * np.min(x):
        ax.xaxis.set_minor_formatter(NullFormatter())


def plot_gain_vs_tube(results: Sequence[Result], path: str | Path,
                      reference: Sequence[tuple[float, float]] | None = None,
                      title: str | None = None) -> Path:
    """Performance gain [%] against tube size delta, log-x (Tables 2, 4, 6).

    ``results`` are :class:`~latentoc.results.Result` (a sweep's); those of the full-space
    baseline (``method`` "joint-range") go to a second panel, gain against joint range (Table 2,
    right). Unsuccessful solves are drawn as open markers. ``reference`` (delta, gain) pairs,
    e.g. the paper's, are drawn for comparison.
    """
    lat = sorted((r for r in results if r.tube is not None), key=lambda r: r.tube.delta)  # type: ignore[union-attr]
    base = sorted((r for r in results if r.method == "joint-range"), key=lambda r: r.details["joint_range_deg"])
    if not lat and not base:
        raise ValueError("results has no result with a tube or a joint range")
    fig = _figure("gain_vs_tube")
    axes = fig.subplots(1, 2 if base and lat else 1, squeeze=False)[0]

    def draw(ax: Any, rows: Sequence[Result], x: np.ndarray, xlabel: str, label: str) -> None:
        y = np.array([r.gain_pct for r in rows])
        ok = np.array([r.success for r in rows])
        ax.plot(x, y, "-", color="C0", lw=1)
        ax.plot(x[ok], y[ok], "o", color="C0", label=label)
        if not ok.all():
            ax.plot(x[~ok], y[~ok], "o", mfc="none", color="C0", label="not converged")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("performance gain [%]")
        ax.grid(True, alpha=0.3)

    if lat:
        ax = axes[0]
        x = np.array([r.tube.delta for r in lat])  # type: ignore[union-attr]
        draw(ax, lat, x, r"tube size $\delta$", "latent (GPDM)")
        if reference is not None:
            ref = np.asarray(reference, dtype=float)
            ax.plot(ref[:, 0], ref[:, 1], "s--", color="C1", label="Kang & Park 2015")
        if np.all(x > 0):
            _log_x(ax, x)
        ax.legend(fontsize=8)
    if base:
        ax = axes[-1]
        draw(ax, base, np.array([float(r.details["joint_range_deg"]) for r in base]),
             "joint range [$\\pm$deg]", "full configuration space")
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    fig.subplots_adjust(left=0.08, right=0.98, bottom=0.13, top=0.9 if title else 0.95, wspace=0.25)
    return _save(fig, path)


def plot_start_poses(rows: Sequence[Mapping[str, Any]], path: str | Path,
                     model: pin.Model | None = None, plane: str = "yz") -> Path:
    """New start poses against tube size (Fig. 4, 5).

    ``rows`` are :func:`latentoc.start_poses.start_pose_distances` rows (``tube``,
    ``translational_distance`` (Eq. 31), ``pose_distance`` (Eq. 32) and ``q``).
    Left: the distances against delta (Fig. 5).  Right, with ``model``: the
    reconstructed start poses overlaid, lighter for larger tubes (Fig. 4).
    """
    rows = sorted(rows, key=lambda r: float(r["tube"]))
    d = np.array([float(r["tube"]) for r in rows])
    fig = _figure("start_poses")
    ax, ax2 = fig.subplots(1, 2)
    ax.plot(d, [r["translational_distance"] for r in rows], "o-", color="C0",
            label="translational distance [m] (Eq. 31)")
    ax.plot(d, [r["pose_distance"] for r in rows], "s-", color="C3", label="pose distance (Eq. 32)")
    if np.all(d > 0):
        _log_x(ax, d)
    ax.set_xlabel(r"tube size $\delta$")
    ax.set_ylabel("distance from the start pose")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if model is None or not rows or "q" not in rows[0]:
        ax2.set_visible(False)
    else:
        i0, i1 = PLANES[plane]
        for k, r in enumerate(rows):
            grey = 0.75 * k / max(len(rows) - 1, 1)
            S = skeleton_segments(model, np.asarray(r["q"], dtype=float))
            for j, (a, b) in enumerate(S):
                ax2.plot([a[i0], b[i0]], [a[i1], b[i1]], "-", lw=2, color=(grey, grey, 1.0 - 0.5 * grey),
                         label=f"$\\delta$ = {r['tube']:.3g}" if j == 0 else None)
        ax2.set_aspect("equal", "datalim")
        ax2.set_xlabel(f"{plane[0]} [m]"), ax2.set_ylabel(f"{plane[1]} [m]")
        ax2.legend(fontsize=7)
        ax2.set_title("reconstructed start poses", fontsize=9)
    fig.subplots_adjust(left=0.07, right=0.98, bottom=0.11, top=0.93, wspace=0.25)
    return _save(fig, path)


def frame_indices(n: int, frames: int) -> np.ndarray:
    """``frames`` evenly spaced sample indices of a length-n motion, first and last included."""
    return np.unique(np.round(np.linspace(0, n - 1, min(int(frames), n))).astype(int))


SIDE_COLOURS = {"left": "C0", "right": "C3", "centre": "0.2"}


def plot_stick_frames(model: pin.Model, Q: np.ndarray | Mapping[str, np.ndarray],
                      path: str | Path, frames: int = 8, plane: str = "xz",
                      layout: str = "panels") -> Path:
    """Stick figures at ``frames`` evenly spaced samples, numbered 1..frames (Fig. 3, 7).

    ``Q`` is (n, nq) or {label: Q}, one row of frames per motion; the PNG is
    ``pixel_size("stick_frames", rows)``.  ``plane`` picks the projection
    (``"xz"`` side, ``"yz"`` front, ``"xy"`` top).  ``layout="panels"`` draws
    the frames side by side at one scale (a moving base is re-centred in each
    panel, its horizontal position printed); ``"overlay"`` draws them in one
    axes at their true positions.  Left bones are blue, right ones red.
    """
    motions = _as_dict(Q, "")
    i0, i1 = PLANES[plane]
    idx = {k: frame_indices(len(M), frames) for k, M in motions.items()}
    segs = {k: [skeleton_segments(model, M[i], return_names=True) for i in idx[k]]
            for k, M in motions.items()}
    colours: dict[str, str] = {}
    for v in segs.values():
        for _, names in v:
            for n in names:
                colours.setdefault(n, SIDE_COLOURS[_side(model, n)])
    floating = model.njoints > 1 and model.joints[1].nq == 7
    if layout not in ("panels", "overlay"):
        raise ValueError(f"layout must be 'panels' or 'overlay', got {layout!r}")
    recentre = layout == "panels" and floating and plane != "xy"
    shifts = {k: [float(np.mean(S[:, :, i0])) if recentre else 0.0 for S, _ in v]
              for k, v in segs.items()}
    horiz = np.concatenate([(S[:, :, i0] - c).ravel() for k, v in segs.items()
                            for (S, _), c in zip(v, shifts[k])])
    vert = np.concatenate([S[:, :, i1].ravel() for v in segs.values() for S, _ in v])
    if floating and plane != "xy":
        vert = np.append(vert, 0.0)
    pad = 0.05 * max(np.ptp(horiz), np.ptp(vert)) + 1e-6
    xlim = (horiz.min() - pad, horiz.max() + pad)
    ylim = (vert.min() - pad, vert.max() + pad)
    rows = len(motions)
    fig = Figure(figsize=(FIGSIZES["stick_frames"][0], FIGSIZES["stick_frames"][1] * rows), dpi=DPI)
    ncols = max(len(v) for v in idx.values()) if layout == "panels" else 1
    axes = fig.subplots(rows, ncols, squeeze=False)
    for r, (label, frames_) in enumerate(segs.items()):
        for c, (S, names) in enumerate(frames_):
            ax = axes[r, c if layout == "panels" else 0]
            for (a, b), n in zip(S, names):
                ax.plot([a[i0] - shifts[label][c], b[i0] - shifts[label][c]], [a[i1], b[i1]],
                        "-", color=colours[n], lw=2 if layout == "panels" else 1.2,
                        solid_capstyle="round")
            if not floating and len(S):  # the fixed base, e.g. the shoulder
                ax.plot([S[0, 0, i0]], [S[0, 0, i1]], "ko", ms=4)
            if layout == "panels":
                title = f"{label} {c + 1}".strip()
                if recentre:
                    title += f"\n{plane[0]} = {shifts[label][c]:.2f} m"
                ax.set_title(title, fontsize=9)
        for ax in axes[r]:
            if floating and plane != "xy":
                ax.axhline(0.0, color="k", lw=0.8)  # the ground
            if layout == "panels":
                ax.set_axis_off()
                ax.set_xlim(*xlim)
            else:
                ax.set_xlabel(f"{plane[0]} [m]", fontsize=8)
                ax.set_ylabel(f"{plane[1]} [m]", fontsize=8)
                ax.set_title(label or None, fontsize=9)
            ax.set_ylim(*ylim)
            ax.set_aspect("equal", adjustable="datalim" if layout == "overlay" else "box")
    fig.subplots_adjust(left=0.01 if layout == "panels" else 0.06, right=0.99, bottom=0.03 if layout == "panels" else 0.12,
                        top=0.88 if rows == 1 else 0.93, wspace=0.05, hspace=0.3)
    return _save(fig, path)


# ------------------------------------------------------------------ solution
def _actuated(model: pin.Model, max_joints: int, Q: np.ndarray) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, q indices and v indices of the 1-DOF joints; if more than ``max_joints``, the
    ones moving most in Q."""
    js = [j for j in range(1, model.njoints) if model.joints[j].nq == 1]
    if len(js) > max_joints:
        ranges = np.ptp(Q[:, [model.joints[j].idx_q for j in js]], axis=0)
        js = sorted(js[k] for k in np.argsort(-ranges)[:max_joints])
    return ([model.names[j] for j in js], np.array([model.joints[j].idx_q for j in js]),
            np.array([model.joints[j].idx_v for j in js]))


def _inverse_dynamics(model: pin.Model, t: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Torques of a sampled motion with finite-difference v and a (vector-space q only)."""
    V = np.gradient(Q, t, axis=0)
    A = np.gradient(V, t, axis=0)
    data = model.createData()
    return np.array([pin.rnea(model, data, q, v, a) for q, v, a in zip(Q, V, A)])


def _landing_balance(model: pin.Model, traj: Mapping[str, np.ndarray]) -> tuple[np.ndarray, ...]:
    """ZMP and COM on the landing samples (t >= touchdown, in contact) and the support
    polygon of both feet (heel and toe tip, mirrored) at the last sample, for a
    ``broad-jump`` trajectory (see :mod:`latentoc.jump.verify`)."""
    from .jump.training import FOOT, TOE
    from .jump.zmp import zmp as zmp_point
    t, Q, V, A = (np.asarray(traj[k]) for k in ("t", "q", "v", "a"))
    land = (t >= float(traj["touchdown"]) - 1e-9) & np.asarray(traj["contact"]).astype(bool)
    data = model.createData()
    mass = sum(i.mass for i in model.inertias)
    zmp, com = [], []
    for q, v, a in zip(Q[land], V[land], A[land]):
        c = pin.centerOfMass(model, data, q)
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, q, v, a).vector
        zmp.append(zmp_point(c, dh, mass))
        com.append(c)
    pin.framesForwardKinematics(model, data, Q[-1])
    M = data.oMf[model.getFrameId(FOOT)]
    heel = M.translation + M.rotation @ np.asarray(traj["heel_offset"])
    toe = data.oMf[model.getFrameId(TOE)].translation
    poly = np.array([[heel[0], -heel[1]], [toe[0], -toe[1]], [toe[0], toe[1]], [heel[0], heel[1]]])
    return np.array(zmp).reshape(-1, 2), np.array(com).reshape(-1, 3), poly, t[land]


def plot_solution(result: Result | str | Path, max_joints: int = 12, plane: str | None = None,
                  gif: bool = False, out_dir: str | Path | None = None) -> list[Path]:
    """Write the figures of a :class:`~latentoc.results.Result` (or of the result folder a path
    names) into ``out_dir`` (default: the folder's ``plots/``) and return their paths.

    Only the result schema is read (:data:`latentoc.results.TRAJECTORY_KEYS`): always joint
    angles, torques (with ``tau_min``/``tau_max`` when recorded) and stick frames (with the
    training fit ``q_initial`` when recorded); for a latent solution the tube with the paths
    (``x``, ``x_initial``) and control points (``P``, ``P_initial``) in the result's GPDM; for the
    broad jump (``wrench``, ``contact``, ``touchdown``, ``heel_offset``) the foot forces and the
    landing's ZMP and COM in the support polygon. With ``gif`` also an animation ``motion.gif``
    of the optimised motion (:func:`latentoc.animation.animate`).
    """
    from .results import load_result

    if not isinstance(result, Result):
        folder = Path(result)
        result = load_result(folder)
        out_dir = folder / "plots" if out_dir is None else out_dir
    if out_dir is None:
        raise ValueError("plot_solution needs out_dir for a Result that was not read from a folder")
    plot_dir = Path(out_dir)
    traj = result.trajectory
    model = pin.Model()
    model.loadFromString(str(traj["model"]))
    t, q, tau = traj["t"], traj["q"], traj["tau"]
    q0 = traj.get("q_initial")
    q0_grid = q0 if q0 is not None and len(q0) == len(t) else None  # an initial motion may have its own rate
    tau0 = _inverse_dynamics(model, t, q0_grid) if q0_grid is not None and model.nq == model.nv and len(t) > 2 \
        else None
    names, iq, iv = _actuated(model, max_joints, q)
    floating = model.njoints > 1 and model.joints[1].nq == 7
    plane = plane or ("xz" if floating else "yz")
    title = result.problem
    written: list[Path] = []

    qs = {"optimised": q[:, iq]}
    if q0_grid is not None:
        qs = {"initial": q0_grid[:, iq], **qs}
    written.append(plot_joint_curves(t, qs, names, plot_dir / "joint_angles.png"))
    jv = iv - (model.nv - tau.shape[1])  # tau may hold the actuated joints only
    taus = {"optimised": tau[:, jv]}
    if tau0 is not None:
        taus = {"initial": tau0[:, jv], **taus}
    limits = (traj["tau_min"][jv], traj["tau_max"][jv]) if "tau_min" in traj else None
    written.append(plot_torques(t, taus, names, plot_dir / "torques.png", limits=limits))
    motions = {"optimised": q} if q0 is None else {"initial": q0, "optimised": q}
    written.append(plot_stick_frames(model, motions, plot_dir / "stick_frames.png", plane=plane))

    if "wrench" in traj:  # the broad jump: one toe-tip wrench per (symmetric) foot
        forces = (traj["wrench"][:, :3] * traj["contact"][:, None])[:, None, :]
        written.append(plot_contact_forces(t, forces, ["each foot"], plot_dir / "contact_forces.png"))
        zmp, com, poly, t_zmp = _landing_balance(model, traj)
        written.append(plot_zmp_com(zmp, com, poly, plot_dir / "zmp_com.png", t=t_zmp))

    if "x" in traj and result.gpdm is not None and result.tube is not None and result.gpdm.latent_dim in (2, 3):
        paths = {"optimised": traj["x"]}
        if "x_initial" in traj:
            paths = {"initial": traj["x_initial"], **paths}
        ctrl = {"optimised control points": traj["P"]}
        if "P_initial" in traj:
            ctrl = {"initial control points": traj["P_initial"], **ctrl}
        delta = result.tube.delta
        written.append(plot_latent_tube(result.gpdm, delta, plot_dir / "latent_tube.png", paths=paths,
                                        control_points=ctrl, title=f"{title}: delta = {delta:.3g}"))
    if gif:
        from .animation import animate
        written.append(animate(model, t, q, plot_dir / "motion.gif", fps=15, plane=plane, title=title))
    return written
