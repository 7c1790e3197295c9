"""Figures of several solves: gain against tube size (Tables 2, 4, 6) and new start poses (Fig. 4, 5)."""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from latentoc.results import Result
from latentoc.plots.figure import new_figure, panel_axes
from latentoc.plots.kinematics import PLANES, skeleton_segments

__all__ = ["plot_gain_vs_tube", "plot_start_poses"]


def _log_x(ax: Any, x: np.ndarray) -> None:
    """Log x axis; minor tick labels only when the data span less than a decade."""
    ax.set_xscale("log")
    if np.max(x) >= 10.0 * np.min(x):
        ax.xaxis.set_minor_formatter(NullFormatter())


def plot_gain_vs_tube(results: Sequence[Result], reference: Sequence[tuple[float, float]] | None = None,
                      title: str | None = None, axes: Any = None) -> Figure:
    """Performance gain [%] against tube size delta, log-x (Tables 2, 4, 6).

    ``results`` are a sweep's :class:`~latentoc.results.Result`; those of the full-space baseline
    (``method`` "joint-range") go to a second panel, gain against joint range. Unsuccessful solves
    are open markers. ``reference`` (delta, gain) pairs, e.g. the paper's, are drawn beside.
    """
    lat = sorted((r for r in results if r.tube is not None), key=lambda r: r.tube.delta)  # type: ignore[union-attr]
    base = sorted((r for r in results if r.method == "joint-range"), key=lambda r: r.details["joint_range_deg"])
    if not lat and not base:
        raise ValueError("results has no result with a tube or a joint range")
    fig, panels = panel_axes(axes, "gain_vs_tube", 2 if base and lat else 1, ncols=2, sharex=False)

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
        ax = panels[0]
        x = np.array([r.tube.delta for r in lat])  # type: ignore[union-attr]
        draw(ax, lat, x, r"tube size $\delta$", "latent (GPDM)")
        if reference is not None:
            ref = np.asarray(reference, dtype=float)
            ax.plot(ref[:, 0], ref[:, 1], "s--", color="C1", label="Kang & Park 2015")
        if np.all(x > 0):
            _log_x(ax, x)
        ax.legend(fontsize=8)
    if base:
        ax = panels[-1]
        draw(ax, base, np.array([float(r.details["joint_range_deg"]) for r in base]),
             "joint range [$\\pm$deg]", "full configuration space")
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    if axes is None:
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.13, top=0.9 if title else 0.95, wspace=0.25)
    return fig


def plot_start_poses(rows: Sequence[Mapping[str, Any]], model: pin.Model | None = None, plane: str = "yz",
                     axes: Any = None) -> Figure:
    """New start poses against tube size (Fig. 4, 5).

    ``rows`` are :func:`latentoc.min_torque.start_poses.start_pose_distances` rows (``tube``,
    ``translational_distance`` (Eq. 31), ``pose_distance`` (Eq. 32) and ``q``). Left: the
    distances against delta (Fig. 5). Right, with ``model``: the start poses overlaid, lighter for
    larger tubes (Fig. 4), at equal scale.
    """
    rows = sorted(rows, key=lambda r: float(r["tube"]))
    d = np.array([float(r["tube"]) for r in rows])
    if axes is None:
        fig = new_figure("start_poses")
        ax, ax2 = fig.subplots(1, 2)
    else:
        fig, (ax, ax2) = panel_axes(axes, "start_poses", 2)
    ax.plot(d, [r["translational_distance"] for r in rows], "o-", color="C0", label="translational distance [m] (Eq. 31)")
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
    if axes is None:
        fig.subplots_adjust(left=0.07, right=0.98, bottom=0.11, top=0.93, wspace=0.25)
    return fig
