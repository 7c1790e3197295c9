"""What every figure shares: sizes, file formats, drawing on the caller's axes or a new Figure, saving.

Every ``plot_*`` function of :mod:`latentoc.plots` returns a :class:`matplotlib.figure.Figure`
(no pyplot state) and takes ``axes=``: the caller's axes to draw on (one, or a sequence when the
figure has panels), else a Figure of ``FIGSIZES[name]`` inches is made. :func:`save` writes a
Figure as PNG (``FIGSIZES[name]`` x ``DPI`` pixels), PDF or SVG.
"""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.figure import Figure

__all__ = ["DPI", "FIGSIZES", "FORMATS", "pixel_size", "new_figure", "panel_axes", "save", "LIMIT_STYLE"]

DPI = 100
FORMATS = ("png", "pdf", "svg")
FIGSIZES: dict[str, tuple[float, float]] = {
    "latent_tube": (8.0, 7.0),
    "joint_curves": (12.0, 8.0),
    "velocities": (12.0, 8.0),
    "torques": (12.0, 8.0),
    "contact_forces": (10.0, 6.0),
    "contact_margins": (10.0, 9.0),
    "zmp_com": (12.0, 5.0),
    "gain_vs_tube": (10.0, 4.5),
    "start_poses": (12.0, 5.0),
    "stick_frames": (14.0, 3.5),  # per row of frames
    "convergence": (10.0, 8.0),
}
#: how an enforced limit is drawn (the tests find limit lines by this colour)
LIMIT_STYLE: dict[str, Any] = {"color": "red", "ls": ":", "lw": 1.2}


def pixel_size(name: str, rows: int = 1) -> tuple[int, int]:
    """(width, height) in pixels of figure ``name`` saved as PNG; ``rows`` (motions drawn) only
    matters for ``stick_frames``, whose height is per row."""
    w, h = FIGSIZES[name]
    if name == "stick_frames":
        h *= rows
    return int(round(w * DPI)), int(round(h * DPI))


def new_figure(name: str, rows: int = 1) -> Figure:
    """An empty Figure of ``name``'s size (:func:`pixel_size`)."""
    w, h = FIGSIZES[name]
    return Figure(figsize=(w, h * rows if name == "stick_frames" else h), dpi=DPI)


def panel_axes(axes: Axes | Sequence[Axes] | np.ndarray | None, name: str, n: int, ncols: int = 4,
               sharex: bool = True, **subplot_kw: Any) -> tuple[Figure, list[Axes]]:
    """The figure and ``n`` axes to draw on: the caller's (at least n of them) or a new figure of
    ``name``'s size with n panels in rows of ``ncols`` (the unused ones hidden)."""
    if axes is not None:
        given = list(np.ravel(np.asarray(axes, dtype=object)))
        if len(given) < n:
            raise ValueError(f"this figure draws {n} panels; axes= gave {len(given)}")
        fig: Any = given[0].get_figure()
        if fig is None:
            raise ValueError("axes= must belong to a figure")
        return fig, given[:n]
    fig = new_figure(name)
    ncols = min(ncols, max(n, 1))
    nrows = int(np.ceil(n / ncols))
    grid = fig.subplots(nrows, ncols, squeeze=False, sharex=sharex, subplot_kw=subplot_kw or None)
    for ax in grid.ravel()[n:]:
        ax.set_visible(False)
    return fig, list(grid.ravel()[:n])


def save(fig: Figure, path: str | Path, format: str | None = None) -> Path:
    """Write ``fig`` to ``path`` (folders made) as ``format`` (default: the suffix, else PNG);
    PNGs at :data:`DPI`, so their pixel size is :func:`pixel_size`. Returns the path."""
    path = Path(path)
    fmt = (format or path.suffix.lstrip(".") or "png").lower()
    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    # no creation date in PDF/SVG, so the same figure gives the same file
    metadata = {"Software": None} if fmt == "png" else {"CreationDate": None} if fmt == "pdf" else {"Date": None}
    with rc_context({"svg.hashsalt": "latentoc"}):  # SVG element ids from a fixed salt, not at random
        fig.savefig(path, dpi=DPI, format=fmt, metadata=metadata)
    return path
