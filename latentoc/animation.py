"""Motion animations (GIF via matplotlib) and interactive 3-D views (meshcat or viser).

:func:`animate` draws the stick figure of :func:`latentoc.plots.skeleton_segments`
at ``fps`` frames per second of motion time; :func:`view` opens Pinocchio's
meshcat or viser visualizer on capsules along the same bones when that optional
package is installed.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.animation import PillowWriter
from matplotlib.figure import Figure

from .plots import DPI, PLANES, SIDE_COLOURS, _bones, _side, skeleton_segments

__all__ = ["ANIMATION_SIZE", "frame_times", "animate", "stick_geometry", "view",
           "VisualizerNotInstalledError"]

ANIMATION_SIZE = (6.0, 6.0)  # inches; times DPI gives the GIF's pixel size


def frame_times(t: np.ndarray, fps: float) -> np.ndarray:
    """Sample indices of ``t`` nearest to the frame times t0, t0 + 1/fps, ..., <= t[-1]."""
    t = np.asarray(t, dtype=float)
    n = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    times = t[0] + np.arange(n) / float(fps)
    return np.abs(t[None, :] - times[:, None]).argmin(axis=1)


def animate(model: pin.Model, t: np.ndarray, Q: np.ndarray, path: str | Path, fps: float = 30,
            plane: str = "xz", title: str | None = None) -> Path:
    """Write a GIF of the stick figure of motion (t, Q) seen in ``plane``; returns the path.

    One frame per 1/fps of motion time (see :func:`frame_times`), played at fps.
    """
    Q = np.asarray(Q, dtype=float)
    if len(t) != len(Q):
        raise ValueError(f"t has {len(t)} samples but Q has {len(Q)}")
    i0, i1 = PLANES[plane]
    idx = frame_times(t, fps)
    frames = [skeleton_segments(model, Q[i], return_names=True) for i in idx]
    pts = np.concatenate([S.reshape(-1, 3) for S, _ in frames])
    floating = model.njoints > 1 and model.joints[1].nq == 7
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if floating and plane != "xy":
        lo[2] = min(lo[2], 0.0)
    half = 0.55 * float(np.max(hi[[i0, i1]] - lo[[i0, i1]])) + 1e-6
    mid = 0.5 * (lo + hi)
    fig = Figure(figsize=ANIMATION_SIZE, dpi=DPI)
    ax = fig.add_subplot()
    ax.set_xlim(mid[i0] - half, mid[i0] + half)
    ax.set_ylim(mid[i1] - half, mid[i1] + half)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{plane[0]} [m]"), ax.set_ylabel(f"{plane[1]} [m]")
    if floating and plane != "xy":
        ax.axhline(0.0, color="k", lw=0.8)
    names0 = frames[0][1]
    lines = {n: ax.plot([], [], "-", lw=2.5, solid_capstyle="round",
                        color=SIDE_COLOURS[_side(model, n)])[0] for n in names0}
    label = ax.set_title("")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = PillowWriter(fps=fps)
    with writer.saving(fig, str(path), dpi=DPI):
        for i, (S, names) in zip(idx, frames):
            seen = dict(zip(names, S))
            for n, line in lines.items():
                a, b = seen.get(n, (np.full(3, np.nan), np.full(3, np.nan)))
                line.set_data([a[i0], b[i0]], [a[i1], b[i1]])
            label.set_text(f"{title + '  ' if title else ''}t = {t[i] - t[0]:.2f} s")
            writer.grab_frame()
    return path


def stick_geometry(model: pin.Model, radius: float = 0.02) -> pin.GeometryModel:
    """Capsules along the stick-figure bones (the models have no meshes), for a visualizer."""
    import coal

    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    pin.updateFramePlacements(model, data)
    geom = pin.GeometryModel()
    for _, a, kind, b, name in _bones(model):
        # bone end in the parent joint's frame (neutral pose: fixed along the bone)
        end = data.oMi[b] if kind == "joint" else data.oMf[b]
        p = (data.oMi[a].inverse() * end).translation
        length = float(np.linalg.norm(p))
        if length < 1e-9:
            continue
        z = p / length
        x = np.cross(z, [1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.cross(z, [0.0, 1.0, 0.0])
        x /= np.linalg.norm(x)
        R = np.column_stack([x, np.cross(z, x), z])
        obj = pin.GeometryObject(f"bone_{name}", a, pin.SE3(R, 0.5 * p),
                                 coal.Capsule(radius, length))
        rgb = {"left": (0.2, 0.4, 0.9), "right": (0.9, 0.25, 0.2)}.get(_side(model, name),
                                                                        (0.6, 0.6, 0.6))
        obj.meshColor = np.array([*rgb, 1.0])
        geom.addGeometryObject(obj)
    return geom


class VisualizerNotInstalledError(ImportError):
    """The optional 3-D viewer package (meshcat or viser) is missing."""


_VIEWERS = {"meshcat": "MeshcatVisualizer", "viser": "ViserVisualizer"}


def view(model: pin.Model, Q: np.ndarray, t: np.ndarray | None = None,
         backend: str = "meshcat", radius: float = 0.02, **viewer_options: Any) -> Any:
    """Show the motion Q (n, nq) or a pose (nq,) in Pinocchio's meshcat or viser viewer.

    Returns the visualizer (open it in a browser at the address it prints).
    Raises :class:`VisualizerNotInstalledError` naming the package to install
    (``pip install meshcat`` or ``pip install viser``) when it is missing.
    """
    if backend not in _VIEWERS:
        raise ValueError(f"backend must be one of {sorted(_VIEWERS)}, got {backend!r}")
    if importlib.util.find_spec(backend) is None:
        raise VisualizerNotInstalledError(
            f"view(backend={backend!r}) needs the optional package {backend!r}: "
            f"pip install {backend}")
    import pinocchio.visualize as pv

    geom = stick_geometry(model, radius)
    viz = getattr(pv, _VIEWERS[backend])(model, geom, geom)
    viz.initViewer(**viewer_options)
    viz.loadViewerModel()
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    if len(Q) == 1:
        viz.display(Q[0])
    else:
        dt = float(np.mean(np.diff(t))) if t is not None and len(t) > 1 else 1.0 / 30.0
        viz.play(Q, dt)
    return viz
