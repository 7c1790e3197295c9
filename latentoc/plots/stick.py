"""Stick figures of motions at evenly spaced times (Fig. 3, 7), each frame labelled with its time.

One row of frames per motion; ``layout="panels"`` draws them side by side at one scale (a moving
base re-centred in each panel, its position in the label) with a scale bar, ``"overlay"`` in one
axes at their true positions. Left bones are blue, right ones red.
"""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.figure import Figure

from latentoc.plots.figure import new_figure, panel_axes
from latentoc.plots.kinematics import PLANES, SIDE_COLOURS, floating_base, frame_indices, side, skeleton_segments

__all__ = ["plot_stick_frames", "scale_bar_length"]


def scale_bar_length(extent: float) -> float:
    """A round length (1, 2 or 5 x 10^k m) of about a quarter of ``extent``."""
    target = max(float(extent), 1e-9) / 4.0
    k = np.floor(np.log10(target))
    return float(max(m * 10.0 ** k for m in (1.0, 2.0, 5.0) if m * 10.0 ** k <= target))


def _motions(Q: np.ndarray | Mapping[str, np.ndarray], t: np.ndarray | Mapping[str, np.ndarray] | None
             ) -> dict[str, tuple[np.ndarray, np.ndarray | None]]:
    """{label: (Q, t or None)}."""
    qs = {k: np.asarray(v, dtype=float) for k, v in Q.items()} if isinstance(Q, Mapping) else \
        {"": np.asarray(Q, dtype=float)}
    out: dict[str, tuple[np.ndarray, np.ndarray | None]] = {}
    for k, M in qs.items():
        tk = t.get(k) if isinstance(t, Mapping) else t
        if tk is not None and len(tk) != len(M):
            raise ValueError(f"{k or 'motion'}: {len(M)} poses but {len(tk)} times")
        out[k] = (M, None if tk is None else np.asarray(tk, dtype=float))
    return out


def plot_stick_frames(model: pin.Model, Q: np.ndarray | Mapping[str, np.ndarray],
                      t: np.ndarray | Mapping[str, np.ndarray] | None = None, frames: int = 8,
                      plane: str = "xz", layout: str = "panels", axes: Any = None) -> Figure:
    """Stick figures at ``frames`` evenly spaced samples of each motion ``Q`` ((n, nq) or
    {label: (n, nq)}), one row per motion, each frame titled with its time from ``t`` (one array,
    or {label: t}; without it the frame's number). ``plane``: ``"xz"`` side, ``"yz"`` front,
    ``"xy"`` top. ``axes``: rows x frames axes for "panels", one axes for "overlay"."""
    if layout not in ("panels", "overlay"):
        raise ValueError(f"layout must be 'panels' or 'overlay', got {layout!r}")
    motions = _motions(Q, t)
    i0, i1 = PLANES[plane]
    idx = {k: frame_indices(len(M), frames) for k, (M, _) in motions.items()}
    segs = {k: [skeleton_segments(model, M[i], return_names=True) for i in idx[k]] for k, (M, _) in motions.items()}
    colours: dict[str, str] = {}
    for v in segs.values():
        for _, names in v:
            for n in names:
                colours.setdefault(n, SIDE_COLOURS[side(model, n)])
    floating = floating_base(model)
    recentre = layout == "panels" and floating and plane != "xy"
    shifts = {k: [float(np.mean(S[:, :, i0])) if recentre else 0.0 for S, _ in v] for k, v in segs.items()}
    horiz = np.concatenate([(S[:, :, i0] - c).ravel() for k, v in segs.items() for (S, _), c in zip(v, shifts[k])])
    vert = np.concatenate([S[:, :, i1].ravel() for v in segs.values() for S, _ in v])
    if floating and plane != "xy":
        vert = np.append(vert, 0.0)
    extent = max(float(np.ptp(horiz)), float(np.ptp(vert)))
    pad = 0.05 * extent + 1e-6
    xlim, ylim = (horiz.min() - pad, horiz.max() + pad), (vert.min() - pad, vert.max() + pad)
    if layout == "panels":  # room for the scale bar below the figures
        ylim = (ylim[0] - 0.12 * extent, ylim[1])
    rows = len(motions)
    ncols = max(len(v) for v in idx.values()) if layout == "panels" else 1
    if axes is None:
        fig = new_figure("stick_frames", rows)
        grid = fig.subplots(rows, ncols, squeeze=False)
    else:
        fig, given = panel_axes(axes, "stick_frames", rows * ncols)
        grid = np.array(given, dtype=object).reshape(rows, ncols)
    bar = scale_bar_length(extent)
    for r, (label, frames_) in enumerate(segs.items()):
        times = motions[label][1]
        for c, (S, names) in enumerate(frames_):
            ax = grid[r, c if layout == "panels" else 0]
            dx = shifts[label][c]
            for (a, b), n in zip(S, names):
                ax.plot([a[i0] - dx, b[i0] - dx], [a[i1], b[i1]], "-", color=colours[n],
                        lw=2 if layout == "panels" else 1.2, solid_capstyle="round")
            if not floating and len(S):  # the fixed base, e.g. the shoulder
                ax.plot([S[0, 0, i0]], [S[0, 0, i1]], "ko", ms=4)
            if layout == "panels":
                when = f"t = {times[idx[label][c]] - times[0]:.2f} s" if times is not None else f"{c + 1}"
                title = f"{label}  {when}".strip() if c == 0 else when
                if recentre:
                    title += f"\n{plane[0]} = {dx:.2f} m"
                ax.set_title(title, fontsize=9)
        for c, ax in enumerate(grid[r]):
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
        if layout == "panels":  # the scale bar, bottom left of the row's first frame
            ax = grid[r, 0]
            x0, y0 = xlim[0] + 0.02 * extent, ylim[0] + 0.03 * extent
            ax.plot([x0, x0 + bar], [y0, y0], "k-", lw=2.5, solid_capstyle="butt")
            ax.text(x0 + 0.5 * bar, y0 + 0.02 * extent, f"{bar:g} m", ha="center", va="bottom", fontsize=7)
    if axes is None:
        fig.subplots_adjust(left=0.01 if layout == "panels" else 0.06, right=0.99,
                            bottom=0.03 if layout == "panels" else 0.12, top=0.86 if rows == 1 else 0.92,
                            wspace=0.05, hspace=0.35)
    return fig
