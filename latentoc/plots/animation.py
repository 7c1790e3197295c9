"""Motion animations (GIF) and the live 3-D view (meshcat or viser).

:func:`animate` draws the stick figure of :func:`latentoc.plots.skeleton_segments` at ``fps``
frames per second of motion time, each frame shown for its exact share of the motion (GIF delays
are whole centiseconds: they are rounded so that frame k starts at k/fps to 10 ms), with the
initial motion as a grey ghost and the trace of its end point; :func:`view` opens Pinocchio's
meshcat or viser visualizer on capsules along the same bones when that optional package is
installed. A self-contained HTML page of a result is :mod:`latentoc.viewer`.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from latentoc.plots.figure import DPI
from latentoc.plots.kinematics import PLANES, SIDE_COLOURS, bones, floating_base, side, skeleton_segments

__all__ = ["ANIMATION_SIZE", "GHOST_COLOUR", "frame_times", "frame_delays_cs", "animate", "stick_geometry", "view",
           "VisualizerNotInstalledError"]

ANIMATION_SIZE = (6.0, 6.0)  # inches; times DPI gives the GIF's pixel size
GHOST_COLOUR = "#b3b3b3"  # the initial motion


def frame_times(t: np.ndarray, fps: float) -> np.ndarray:
    """Sample indices of ``t`` nearest to the frame times t0, t0 + 1/fps, ..., <= t[-1]."""
    t = np.asarray(t, dtype=float)
    n = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    times = t[0] + np.arange(n) / float(fps)
    return np.abs(t[None, :] - times[:, None]).argmin(axis=1)


def frame_delays_cs(n: int, fps: float) -> list[int]:
    """GIF delays (centiseconds) of n frames at ``fps``: frame k starts at round(100 k / fps) cs."""
    starts = np.round(100.0 * np.arange(n + 1) / float(fps)).astype(int)
    return [int(d) for d in np.diff(starts)]


def _tip(S: np.ndarray) -> np.ndarray:
    """The traced point of a stick figure: the end of its last bone (a hand, a toe)."""
    return S[-1, 1] if len(S) else np.zeros(3)


def animate(model: pin.Model, t: np.ndarray, Q: np.ndarray, path: str | Path, fps: float = 25,
            plane: str = "xz", title: str | None = None, initial: np.ndarray | None = None,
            t_initial: np.ndarray | None = None) -> Path:
    """Write a GIF of the stick figure of motion (t, Q) seen in ``plane``; returns the path.

    One frame per 1/fps of motion time (:func:`frame_times`), each shown for 1/fps (to the GIF's
    10 ms: :func:`frame_delays_cs`). ``initial`` (m, nq; its times ``t_initial``, default: t when
    m = n, else spread over the same duration) is drawn as a grey ghost with the trace of its
    end point; the optimised end point's trace is drawn too.
    """
    Q = np.asarray(Q, dtype=float)
    t = np.asarray(t, dtype=float)
    if len(t) != len(Q):
        raise ValueError(f"t has {len(t)} samples but Q has {len(Q)}")
    i0, i1 = PLANES[plane]
    idx = frame_times(t, fps)
    frames = [skeleton_segments(model, Q[i], return_names=True) for i in idx]
    ghosts: list[np.ndarray] = []
    if initial is not None:
        Q0 = np.asarray(initial, dtype=float)
        t0 = np.asarray(t_initial, dtype=float) if t_initial is not None else \
            (t if len(Q0) == len(t) else np.linspace(t[0], t[-1], len(Q0)))
        near = np.abs(t0[None, :] - t[idx][:, None]).argmin(axis=1)
        ghosts = [skeleton_segments(model, Q0[j]) for j in near]  # type: ignore[misc]
    pts = np.concatenate([S.reshape(-1, 3) for S, _ in frames] + [G.reshape(-1, 3) for G in ghosts])
    floating = floating_base(model)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if floating and plane != "xy":
        lo[2] = min(lo[2], 0.0)
    half = 0.55 * float(np.max(hi[[i0, i1]] - lo[[i0, i1]])) + 1e-6
    mid = 0.5 * (lo + hi)
    fig = Figure(figsize=ANIMATION_SIZE, dpi=DPI)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_xlim(mid[i0] - half, mid[i0] + half)
    ax.set_ylim(mid[i1] - half, mid[i1] + half)
    ax.set_aspect("equal")
    ax.set_xlabel(f"{plane[0]} [m]"), ax.set_ylabel(f"{plane[1]} [m]")
    if floating and plane != "xy":
        ax.axhline(0.0, color="k", lw=0.8)
    ghost_lines = [ax.plot([], [], "-", lw=2.5, color=GHOST_COLOUR, solid_capstyle="round", zorder=1)[0]
                   for _ in range(len(ghosts[0]) if ghosts else 0)]
    if ghosts:
        ghost_lines[0].set_label("initial")
        tip0 = np.array([_tip(G) for G in ghosts])
        ax.plot(tip0[:, i0], tip0[:, i1], "--", color=GHOST_COLOUR, lw=1.2, zorder=1)
    tip = np.array([_tip(S) for S, _ in frames])
    ax.plot(tip[:, i0], tip[:, i1], "-", color="C1", lw=1.0, alpha=0.6, zorder=1)
    names0 = frames[0][1]
    lines = {n: ax.plot([], [], "-", lw=2.5, solid_capstyle="round", color=SIDE_COLOURS[side(model, n)],
                        zorder=2)[0] for n in names0}
    if ghosts:
        next(iter(lines.values())).set_label("optimised")
        ax.legend(loc="upper right", fontsize=8)
    label = ax.set_title("")
    images = []
    for k, (i, (S, names)) in enumerate(zip(idx, frames)):
        seen = dict(zip(names, S))
        for n, line in lines.items():
            a, b = seen.get(n, (np.full(3, np.nan), np.full(3, np.nan)))
            line.set_data([a[i0], b[i0]], [a[i1], b[i1]])
        if ghosts:
            for line, (a, b) in zip(ghost_lines, ghosts[k]):
                line.set_data([a[i0], b[i0]], [a[i1], b[i1]])
        label.set_text(f"{title + '  ' if title else ''}t = {t[i] - t[0]:.2f} s")
        canvas.draw()
        images.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3]).quantize(colors=64))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], loop=0,
                   duration=[10 * d for d in frame_delays_cs(len(images), fps)], disposal=1)
    return path


def stick_geometry(model: pin.Model, radius: float = 0.02) -> pin.GeometryModel:
    """Capsules along the stick-figure bones (the models have no meshes), for a visualizer."""
    import coal

    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    pin.updateFramePlacements(model, data)
    geom = pin.GeometryModel()
    for _, a, kind, b, name in bones(model):
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
        rgb = {"left": (0.2, 0.4, 0.9), "right": (0.9, 0.25, 0.2)}.get(side(model, name),
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
