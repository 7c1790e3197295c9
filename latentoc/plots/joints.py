"""Joint angles, velocities and torques over time, one panel per joint, with the enforced limits.

A limit is a dotted red line (:data:`~latentoc.plots.figure.LIMIT_STYLE`) at its value; an
infinite one (no limit) is not drawn. Several motions ({label: array}) share each panel.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from latentoc.plots.figure import LIMIT_STYLE, panel_axes

__all__ = ["plot_joint_curves", "plot_velocities", "plot_torques", "Bounds"]

#: (lower, upper) per joint; None: no limits drawn
Bounds = tuple[np.ndarray, np.ndarray] | None


def _series(y: Mapping[str, np.ndarray] | np.ndarray) -> dict[str, np.ndarray]:
    if isinstance(y, Mapping):
        return {k: np.asarray(v, dtype=float) for k, v in y.items()}
    return {"": np.asarray(y, dtype=float)}


def _curves(name: str, t: np.ndarray, y: Mapping[str, np.ndarray] | np.ndarray, names: Sequence[str], ylabel: str,
            scale: float, limits: Bounds, axes: Any) -> Figure:
    series = _series(y)
    t = np.asarray(t, dtype=float)
    for k, Y in series.items():
        if Y.shape != (len(t), len(names)):
            raise ValueError(f"{k or 'values'}: expected shape {(len(t), len(names))}, got {Y.shape}")
    own = axes is None
    fig, panels = panel_axes(axes, name, len(names))
    for j, ax in enumerate(panels):
        for i, (label, Y) in enumerate(series.items()):
            ax.plot(t, scale * Y[:, j], ["-", "--", ":", "-."][i % 4], lw=1.5, label=label or None)
        if limits is not None:
            for side, lim in enumerate(limits):
                value = float(np.asarray(lim)[j])
                if np.isfinite(value):
                    ax.axhline(scale * value, label="limit" if side == 0 else None, **LIMIT_STYLE)
        ax.set_title(names[j], fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in panels[-min(4, len(panels)):]:
        ax.set_xlabel("t [s]", fontsize=8)
    if panels:
        handles = panels[0].get_legend_handles_labels()[0]
        if len(handles) > 1:
            panels[0].legend(fontsize=7)
    if own:
        fig.supylabel(ylabel)
        fig.subplots_adjust(left=0.08, right=0.98, bottom=0.07, top=0.95, wspace=0.3, hspace=0.35)
    return fig


def plot_joint_curves(t: np.ndarray, q: Mapping[str, np.ndarray] | np.ndarray, names: Sequence[str],
                      limits: Bounds = None, axes: Any = None) -> Figure:
    """Joint angles [deg], one panel per joint; ``q`` (n, len(names)) or {label: q}; ``limits``
    (q_min, q_max) in rad."""
    return _curves("joint_curves", t, q, names, "joint angle [deg]", float(np.degrees(1.0)), limits, axes)


def plot_velocities(t: np.ndarray, v: Mapping[str, np.ndarray] | np.ndarray, names: Sequence[str],
                    v_max: np.ndarray | None = None, axes: Any = None) -> Figure:
    """Joint velocities [deg/s], one panel per joint, with the limits +-``v_max`` (rad/s)."""
    limits = None if v_max is None else (-np.asarray(v_max, dtype=float), np.asarray(v_max, dtype=float))
    return _curves("velocities", t, v, names, "joint velocity [deg/s]", float(np.degrees(1.0)), limits, axes)


def plot_torques(t: np.ndarray, tau: Mapping[str, np.ndarray] | np.ndarray, names: Sequence[str],
                 limits: Bounds = None, axes: Any = None) -> Figure:
    """Joint torques [N m], one panel per joint, with the limits (tau_min, tau_max)."""
    return _curves("torques", t, tau, names, "torque [N m]", 1.0, limits, axes)
