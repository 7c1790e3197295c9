"""Learn a GPDM from the user's motion file (``python -m latentoc learn FILE --robot NAME_OR_URDF``).

Reads the motion on the robot (:mod:`latentoc.motions`), learns a GPDM (Eq. 16) from its frames,
and writes into one folder, only after everything has been computed (a bad input writes nothing):

* ``gpdm.npz``: the model (:meth:`latentoc.gpdm.GPDM.save`), the input of a problem's solve;
* ``learn.json``: the demonstration (source, frames, rate, joints, locked joints, resampling,
  clipping), the GPDM's settings and learning report, its reconstruction error (RMS of the GP
  mean at the training latent points minus the motion, Eq. 18; overall and per joint) and the
  training tube tube_training (Eq. 30), the largest sigma^2 (Eq. 19) along the training path;
* with ``plots``: ``latent_tube.png`` (the training path in the tube at tube_training),
  ``reconstruction.png`` (the motion and the GP mean) and ``variance.png`` (sigma^2 along the
  training path against time, with tube_training).

:func:`cmd_learn` is the command itself; :func:`load_gpdm_file` reads the model back (``solve --gpdm``).
"""
from __future__ import annotations

import argparse
import io
import json
import tempfile
import time
from dataclasses import asdict, dataclass, is_dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError
from latentoc.runtime.files import NPZ_ERRORS, check_out_dir, dumps_json
from latentoc.runtime.interrupts import finish
from latentoc.gpdm import GPDM, GPDMInputError, GPDMSettings, learn_gpdm
from latentoc.motions import Demonstration, check_frames, demonstration_from_file
from latentoc.results import GPDM_NAME, write_files
from latentoc.robots import load_robot, load_urdf

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure

__all__ = ["LearnedMotion", "learn_motion", "learn_file", "figures", "robot_from_argument", "load_gpdm_file",
           "LEARN_NAME", "cmd_learn"]

LEARN_NAME = "learn.json"


def robot_from_argument(text: str) -> pin.Model:
    """The robot of ``--robot``: a registered name, or the path of a URDF file (fixed base)."""
    if text.lower().endswith(".urdf") or "/" in text or Path(text).is_file():
        return load_urdf(Path(text))
    return load_robot(text)


@dataclass
class LearnedMotion:
    """A GPDM learned from a demonstration, with its reconstruction error and training tube."""

    demonstration: Demonstration
    gpdm: GPDM
    frames: np.ndarray  # the indices of the demonstration's frames it learned from
    time_s: float

    @property
    def reconstruction_rmse(self) -> np.ndarray:
        """Per joint: RMS of mean(X) - Y over the training frames (rad or m), Eq. 18."""
        return np.sqrt(np.mean((self.gpdm.mean(self.gpdm.X) - self.gpdm.Y) ** 2, axis=0))

    def summary(self) -> dict[str, Any]:
        """``learn.json``'s content (module doc)."""
        g = self.gpdm
        per_joint = self.reconstruction_rmse
        report = getattr(g, "learning", None)  # how learning ended, where the GPDM records it
        return {"demonstration": self.demonstration.info(), "learned_frames": int(len(self.frames)),
                "latent_dim": g.latent_dim, "settings": json.loads(g.settings.to_json()),
                "learning": asdict(report) if is_dataclass(report) and not isinstance(report, type) else None,
                "learning_time_s": self.time_s, "objective_value": float(g.objective_value),
                "reconstruction_rmse": float(np.sqrt(np.mean(per_joint ** 2))),
                "reconstruction_rmse_per_joint": dict(zip(self.demonstration.joint_names, map(float, per_joint))),
                "tube_training": g.tube_size(), "noise_variance": g.noise_variance,
                "alpha": g.alpha.tolist(), "beta": g.beta.tolist()}


def learn_motion(demo: Demonstration, latent_dim: int = 3, stride: int = 1,
                 settings: GPDMSettings | None = None) -> LearnedMotion:
    """A GPDM of every ``stride``-th frame of ``demo`` (the last frame always kept)."""
    check_frames(demo, latent_dim, stride)
    frames = np.arange(0, len(demo.t), stride)
    if frames[-1] != len(demo.t) - 1:
        frames = np.append(frames, len(demo.t) - 1)
    settings = GPDMSettings(latent_dim=latent_dim) if settings is None else settings
    t0 = time.perf_counter()
    gp = learn_gpdm(demo.Q[frames], settings)
    return LearnedMotion(demo, gp, frames, time.perf_counter() - t0)


def _png(fig: "Figure") -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    return buffer.getvalue()


def _variance_png(learned: LearnedMotion) -> bytes:
    """sigma^2 along the training latent path (linear between its points) against time."""
    g, t = learned.gpdm, learned.demonstration.t[learned.frames]
    X = g.latent_trajectories()[0]
    s = np.linspace(0.0, 1.0, 11)[:-1]
    pts = np.vstack([(X[:-1, None, :] * (1 - s)[None, :, None] + X[1:, None, :] * s[None, :, None]).reshape(-1, X.shape[1]),
                     X[-1:]])
    tt = np.append((t[:-1, None] * (1 - s) + t[1:, None] * s).ravel(), t[-1])
    from matplotlib.figure import Figure  # only with --plots: matplotlib takes 0.3 s to import

    fig = Figure(figsize=(8.0, 3.5), dpi=100)
    ax = fig.add_subplot()
    ax.plot(tt, g.variance(pts), lw=1.5, label="$\\sigma^2$ along the training path (Eq. 19)")
    ax.axhline(g.tube_size(), color="goldenrod", ls="--", label="tube_training (Eq. 30)")
    ax.axhline(g.noise_variance, color="grey", ls=":", label="noise variance $1/\\beta_3$")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("$\\sigma^2$")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _png(fig)


def figures(learned: LearnedMotion, title: str) -> dict[str, bytes]:
    """The PNG figures by file name (module doc)."""
    from latentoc.plots import plot_joint_curves, plot_latent_tube, save

    g, demo = learned.gpdm, learned.demonstration
    out = {"variance.png": _variance_png(learned)}
    figs = {"reconstruction.png": plot_joint_curves(demo.t[learned.frames], {"demonstration": g.Y,
                                                                             "GPDM mean (Eq. 18)": g.mean(g.X)},
                                                    demo.joint_names)}
    if g.latent_dim in (2, 3):
        figs["latent_tube.png"] = plot_latent_tube(g, g.tube_size(), paths={"training path": g.latent_trajectories()[0]},
                                                   title=f"{title}: tube at tube_training = {g.tube_size():.3g}")
    with tempfile.TemporaryDirectory() as tmp:
        out.update({name: save(fig, Path(tmp) / name).read_bytes() for name, fig in figs.items()})
    return out


def learn_file(path: str | Path, robot: str, out: str | Path, *, latent_dim: int = 3, stride: int = 1,
               plots: bool = False, clip_to_limits: bool = False, rate: float | None = None,
               asf: str | Path | None = None, start: int | None = None, stop: int | None = None,
               fps: float = 120.0, fixed_pose: dict[str, float] | None = None,
               locked: list[str] | None = None) -> tuple[LearnedMotion, list[Path]]:
    """The ``learn`` command: read, learn, then write the folder ``out`` (module doc); ``fixed_pose``
    and ``locked``: the joints the file does not move (:func:`~latentoc.motions.demonstration_from_file`)."""
    demo = demonstration_from_file(path, robot_from_argument(robot), asf=asf, fps=fps, start=start, stop=stop,
                                   rate=rate, fixed_pose=fixed_pose, locked=locked, clip_to_limits=clip_to_limits)
    learned = learn_motion(demo, latent_dim, stride)
    with tempfile.TemporaryDirectory() as tmp:  # GPDM.save writes to a path
        learned.gpdm.save(Path(tmp) / GPDM_NAME)
        files = {GPDM_NAME: (Path(tmp) / GPDM_NAME).read_bytes()}
    if plots:
        files.update(figures(learned, Path(path).stem))
    summary = {"robot": robot, **learned.summary()}
    files[LEARN_NAME] = dumps_json(summary).encode()
    finish()  # on the command line: the folder is written whole, or (Ctrl-C before this line) not at all
    return learned, write_files(files, out, marker=LEARN_NAME)


def load_gpdm_file(path: str | Path) -> GPDM:
    """The GPDM in ``path`` (a ``gpdm.npz`` of ``learn`` or of a result folder); a GPDMInputError
    naming the file if it is missing or not one."""
    path = Path(path)
    if not path.is_file():
        raise GPDMInputError(f"GPDM file {path} does not exist")
    try:
        return GPDM.load(path)
    except NPZ_ERRORS as exc:
        raise GPDMInputError(f"{path} is not a GPDM written by latentoc ({type(exc).__name__}: {exc})") from None


def cmd_learn(args: argparse.Namespace) -> int:
    """``python -m latentoc learn``: :func:`learn_file` with the command line's arguments, and what it learned."""
    if args.stride < 1 or args.latent_dim < 1:
        raise LatentocError(f"--stride and --latent-dim must be positive, got {args.stride} and {args.latent_dim}")
    check_out_dir(args.out)
    _, paths = learn_file(args.file, args.robot, args.out, latent_dim=args.latent_dim, stride=args.stride,
                          plots=args.plots, clip_to_limits=args.clip, rate=args.rate, asf=args.asf,
                          start=args.start, stop=args.stop, fps=args.fps,
                          fixed_pose={n: v for n, v in args.hold if v is not None},
                          locked=[n for n, v in args.hold if v is None])
    s = json.loads(next(p for p in paths if p.name == "learn.json").read_text())  # learned.summary(), as written
    demo = s["demonstration"]
    print(f"{args.file}: {demo['frames']} frames at {demo['rate_hz']:.4g} Hz ({demo['duration_s']:.3g} s) of "
          f"{len(demo['joints'])} joints" + (f", {len(demo['locked_joints'])} locked" if demo["locked_joints"] else "")
          + (", resampled" if demo["resampled"] else "") + (f", clipped {demo['clipped']}" if demo["clipped"] else ""))
    report = s["learning"]
    ended = "" if report is None else " (converged)" if report["converged"] else f" (not converged: {report['message']})"
    print(f"  GPDM d = {s['latent_dim']} on {s['learned_frames']} frames in {s['learning_time_s']:.2f} s{ended}")
    print(f"  reconstruction RMS error {s['reconstruction_rmse']:.3g} (rad or m), "
          f"tube_training (Eq. 30) {s['tube_training']:.4g}, noise variance {s['noise_variance']:.3g}")
    print("  per joint: " + ", ".join(f"{name} {e:.3g}" for name, e in s["reconstruction_rmse_per_joint"].items()))
    print("  wrote " + ", ".join(str(p) for p in paths))
    return 0
