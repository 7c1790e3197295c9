"""The training motion of a problem: a registered name or the user's recorded motion file.

A problem file's ``training`` is a name of :data:`TRAINING_MOTIONS` or a table naming a file
(:data:`TRAINING`; paths relative to the problem file)::

    training = { file = "reach.csv" }
    training = { file = "reach.npz", rate = 100.0, fixed_pose = { panda_finger_joint1 = 0.02 },
                 locked = ["panda_finger_joint2"] }
    training = { file = "01_01.amc", asf = "01.asf", start = 120, stop = 468, fps = 120.0 }

:func:`demonstration_from_file` turns a file (:mod:`.readers`) into a
:class:`Demonstration`: the samples in the robot's joint order, time from 0 on a uniform grid
(non-uniform time stamps, or a given ``rate``, resampled by a cubic spline through the samples),
inside the robot's joint limits (or clipped to them with ``clip_to_limits``), and the robot
reduced to the joints the file moves. Every other joint must be declared: held at its
``fixed_pose`` value or, listed in ``locked``, at the model's neutral value; a joint the file does
not move and nothing declares is an error (a missing column is a mistake more often than a choice).
A continuous joint (a URDF's ``continuous``) takes one angle, in rad, with no limits
(:func:`latentoc.robots.urdf.continuous_as_revolute`).
Every problem is a :class:`~.readers.MotionFileError` naming the file.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.robots.human_arm import arm_trial
from latentoc.robots.human_models import broad_jump_training_motion
from latentoc.robots.urdf import continuous_as_revolute
from latentoc.problem.schema import Check
from latentoc.motions.readers import FORMATS, MotionFileError, RawMotion, read_raw_motion

__all__ = ["Demonstration", "TRAINING", "TRAINING_MOTIONS", "demonstration_from_file", "load_demonstration",
           "one_dof_joints", "check_frames", "MotionFileError"]

#: the longest demonstration and the fastest sampling read; beyond them the times are not in seconds
MAX_DURATION_S, MAX_RATE_HZ = 600.0, 100_000.0
UNIFORM_RTOL = 1e-6  # time steps within this fraction of the median step count as uniform
MAX_SAMPLES = 1_000_000  # a resampled motion may have at most this many samples


#: Named training motions: name -> () -> (t [N], Q [N x nq]).
TRAINING_MOTIONS: dict[str, Callable[[], tuple[np.ndarray, np.ndarray]]] = {
    "human-arm-trial": arm_trial,
    "cmu-broad-jump": broad_jump_training_motion,
}

_TABLE_KEYS = {"file": str, "format": str, "asf": str, "fps": float, "start": int, "stop": int, "rate": float,
               "fixed_pose": dict, "locked": list, "clip_to_limits": bool}


def _training_table(value: Any) -> str | dict[str, Any]:
    """The ``training`` setting normalised: a registered name, or a file table (module doc)."""
    if isinstance(value, str):
        if value not in TRAINING_MOTIONS:
            raise ValueError
        return value
    if not isinstance(value, dict) or "file" not in value or set(value) - set(_TABLE_KEYS):
        raise ValueError
    out: dict[str, Any] = {"file": None, "format": None, "asf": None, "fps": 120.0, "start": None, "stop": None,
                           "rate": None, "fixed_pose": {}, "locked": [], "clip_to_limits": False}
    for key, v in value.items():
        if v is None and key != "file":  # a normalised table (Problem.from_dict) holds None for "not given"
            continue
        kind = _TABLE_KEYS[key]
        if kind is float and isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        if not isinstance(v, kind) or isinstance(v, bool) and kind is not bool:
            raise ValueError
        out[key] = v
    positive = [out[k] for k in ("fps", "rate") if out[k] is not None]
    if not out["file"] or any(not np.isfinite(v) or v <= 0 for v in positive) \
            or out["format"] not in (None, *FORMATS) \
            or any(out[k] is not None and out[k] < 0 for k in ("start", "stop")) \
            or not all(isinstance(k, str) and isinstance(v, (int, float)) and not isinstance(v, bool)
                       and np.isfinite(v) for k, v in out["fixed_pose"].items()) \
            or not all(isinstance(k, str) for k in out["locked"]):
        raise ValueError
    out["fixed_pose"] = {k: float(v) for k, v in out["fixed_pose"].items()}
    return out


#: the check of a problem file's ``training``: a registered name or a table naming a file
TRAINING = Check(_training_table, f"one of {', '.join(map(repr, TRAINING_MOTIONS))}, or a table "
                                  '{ file = "path.csv|npz|amc", rate, fixed_pose = { joint = value }, '
                                  'locked = ["joint"], clip_to_limits, start, stop, asf, fps, format }')


@dataclass
class Demonstration:
    """A recorded motion ready to learn from: ``Q`` (N x D) of the ``joint_names`` at times ``t``
    (from 0, uniform), and ``model``, the robot with every other joint locked (``locked``)."""

    t: np.ndarray
    Q: np.ndarray
    joint_names: list[str]
    model: pin.Model
    source: str
    locked: dict[str, list[float]] = field(default_factory=dict)
    rate_hz: float = 0.0
    resampled: bool = False
    clipped: dict[str, float] = field(default_factory=dict)  # joint -> largest clipped amount (rad or m)

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def info(self) -> dict[str, Any]:
        """JSON-ready facts for a result: source, frames, rate, joints, locked, resampled, clipped."""
        return {"source": self.source, "frames": int(len(self.t)), "rate_hz": self.rate_hz,
                "duration_s": self.duration, "joints": list(self.joint_names), "locked_joints": self.locked,
                "resampled": self.resampled, "clipped": self.clipped}


def one_dof_joints(model: pin.Model) -> dict[str, int]:
    """The model's joints with one coordinate (revolute, prismatic): name -> index in q."""
    return {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints) if model.joints[j].nq == 1}


def _column_order(raw: RawMotion, model: pin.Model) -> tuple[list[str], np.ndarray]:
    """The file's joints in the model's q order and the values in that order."""
    joints = one_dof_joints(model)
    if raw.names is None:  # an NPZ q of the full configuration
        if raw.values.shape[1] != model.nq:
            raise MotionFileError(f"{raw.path}: q has {raw.values.shape[1]} columns, the robot {model.name!r} has "
                                  f"nq = {model.nq}; give joint_names for a subset")
        if len(joints) != model.njoints - 1:
            multi = [model.names[j] for j in range(1, model.njoints) if model.joints[j].nq != 1]
            raise MotionFileError(f"{raw.path}: the robot has joints of several coordinates ({', '.join(multi)}); "
                                  "give joint_names for its 1-DOF joints")
        names = [model.names[j] for j in range(1, model.njoints)]
        return names, raw.values
    given = raw.names
    unknown = [n for n in given if n not in joints]
    if unknown:
        raise MotionFileError(f"{raw.path}: unknown joint name{'s' if len(unknown) > 1 else ''} "
                              f"{', '.join(map(repr, unknown))}; the robot {model.name!r} has the joints "
                              f"{', '.join(joints)}")
    order = sorted(range(len(given)), key=lambda i: joints[given[i]])
    return [given[i] for i in order], raw.values[:, order]


def _limits(model: pin.Model, names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits of the joints ``names`` (infinite where the URDF gives none: lo >= hi)."""
    idx = [model.joints[model.getJointId(n)].idx_q for n in names]
    lo = np.asarray(model.lowerPositionLimit, float)[idx]
    hi = np.asarray(model.upperPositionLimit, float)[idx]
    none = ~(lo < hi)
    return np.where(none, -np.inf, lo), np.where(none, np.inf, hi)


def _check_limits(raw: RawMotion, names: list[str], Q: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                  model_name: str) -> None:
    """A MotionFileError saying which joints leave their limits, by how much and where."""
    below, above = lo - Q, Q - hi
    out = np.maximum(below, above)
    bad = np.nonzero((out > 0).any(axis=0))[0]
    if not len(bad):
        return
    lines = []
    for j in sorted(bad, key=lambda j: -out[:, j].max())[:5]:
        i = int(np.argmax(out[:, j]))
        side = f"below its lower limit {lo[j]:.6g}" if below[i, j] > 0 else f"above its upper limit {hi[j]:.6g}"
        lines.append(f"{names[j]!r} by {out[i, j]:.4g} {side} at t = {raw.t[i]:.4g} s ({raw.where[i]})")
    more = f" and {len(bad) - 5} more joints" if len(bad) > 5 else ""
    raise MotionFileError(f"{raw.path}: the motion leaves the joint limits of {model_name!r}: " + "; ".join(lines)
                          + more + ". Set clip_to_limits = true in the training table (CLI: --clip) to clip it")


def _uniform_time(raw: RawMotion, rate: float | None) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """(t from 0, values, rate, resampled): the samples as they are if their steps are uniform (and
    ``rate`` is not another), else a cubic spline through them on an even grid over the same span
    at ``rate`` or the median rate."""
    t = raw.t
    dt = np.diff(t)
    if len(dt) and (dt <= 0).any():
        i = int(np.argmax(dt <= 0)) + 1
        raise MotionFileError(f"{raw.path}, {raw.where[i]}: time t = {t[i]:.6g} s does not increase "
                              f"(previous sample t = {t[i - 1]:.6g} s); t must be strictly increasing")
    step = float(np.median(dt))
    span = float(t[-1] - t[0])
    if 1.0 / step > MAX_RATE_HZ or span > MAX_DURATION_S:
        unit = "milliseconds" if 1.0 / step <= MAX_RATE_HZ and span / 1000.0 <= MAX_DURATION_S else "another unit than seconds"
        raise MotionFileError(f"{raw.path}: {span:.6g} s at {1.0 / step:.6g} Hz (median step); a demonstration lasts at "
                              f"most {MAX_DURATION_S:g} s at up to {MAX_RATE_HZ / 1000:g} kHz, so the times look like "
                              f"{unit}: give t in seconds")
    uniform = bool(np.all(np.abs(dt - step) <= UNIFORM_RTOL * step))
    if uniform and (rate is None or abs(rate * step - 1.0) <= UNIFORM_RTOL):
        return t - t[0], raw.values, 1.0 / step, False
    target = 1.0 / step if rate is None else float(rate)
    if not span * target <= MAX_SAMPLES:
        raise MotionFileError(f"{raw.path}: resampling {span:.6g} s at {target:.6g} Hz would give more than "
                              f"{MAX_SAMPLES} samples; give a lower rate")
    n = max(2, int(round(span * target)) + 1)
    grid = np.linspace(0.0, span, n)
    from scipy.interpolate import CubicSpline  # here: only resampling needs it, and its import is slow

    try:
        with np.errstate(all="ignore"):
            values = CubicSpline(t - t[0], raw.values, axis=0)(grid)
    except ValueError:  # scipy refuses slopes that overflow
        values = np.full(1, np.nan)
    if not np.isfinite(values).all():
        raise MotionFileError(f"{raw.path}: the samples cannot be resampled on an even grid (time stamps from "
                              f"{t[0]:.6g} to {t[-1]:.6g} s give values that are not finite)")
    return grid, values, (n - 1) / span, True


def _reduced(model: pin.Model, names: list[str], fixed_pose: dict[str, float], held: list[str], path: Path
             ) -> tuple[pin.Model, dict[str, list[float]]]:
    """The model with every joint not in ``names`` locked: at ``fixed_pose`` or, listed in ``held``,
    at its neutral value; a joint in none of them is an error."""
    joints = {model.names[j]: j for j in range(1, model.njoints)}
    declared = [*fixed_pose, *held]
    unknown = [n for n in declared if n not in joints]
    if unknown:
        raise MotionFileError(f"{path}: fixed_pose/locked name unknown joint{'s' if len(unknown) > 1 else ''} "
                              f"{', '.join(map(repr, unknown))}; the robot {model.name!r} has {', '.join(joints)}")
    moved = [n for n in declared if n in names]
    if moved:
        raise MotionFileError(f"{path}: fixed_pose/locked give {', '.join(map(repr, moved))}, which the file moves")
    twice = sorted(set(fixed_pose) & set(held))
    if twice:
        raise MotionFileError(f"{path}: {', '.join(map(repr, twice))} in both fixed_pose and locked; give each once")
    undeclared = [n for n in joints if n not in names and n not in declared
                  and model.joints[joints[n]].shortname() != "JointModelFreeFlyer"]
    if undeclared:
        many = len(undeclared) > 1
        raise MotionFileError(
            f"{path}: no column for the robot's joint{'s' if many else ''} {', '.join(map(repr, undeclared))} "
            f"(the file moves {', '.join(names)}); if {'they are' if many else 'it is'} meant to be held still, say "
            f"so: in the problem file's training table, fixed_pose = {{ {undeclared[0]} = value }} or locked = "
            f"[{', '.join(map(repr, undeclared))}] (at the model's neutral value); for `learn`, "
            f"--hold {undeclared[0]}[=value]")
    q_ref = pin.neutral(model)
    locked: dict[str, list[float]] = {}
    for name, j in joints.items():
        if name in names:
            continue
        jm = model.joints[j]
        if jm.shortname() == "JointModelFreeFlyer":  # locking it would fix a floating base in the world
            raise MotionFileError(f"{path}: the robot's free-flyer root {name!r} cannot be locked at a pose; use a "
                                  "fixed-base robot (free_flyer = false)")
        if name in fixed_pose:
            if jm.nq != 1:
                raise MotionFileError(f"{path}: fixed_pose: joint {name!r} has {jm.nq} coordinates, one value given")
            q_ref[jm.idx_q] = fixed_pose[name]
        lo, hi = _limits(model, [name]) if jm.nq == 1 else (np.array([-np.inf]), np.array([np.inf]))
        if jm.nq == 1 and not lo[0] <= q_ref[jm.idx_q] <= hi[0]:
            given = "fixed_pose value" if name in fixed_pose else "neutral value"
            raise MotionFileError(f"{path}: joint {name!r} is not in the file and its {given} {q_ref[jm.idx_q]:.6g} "
                                  f"is outside its limits [{lo[0]:.6g}, {hi[0]:.6g}]; give it in fixed_pose")
        locked[name] = [float(v) for v in q_ref[jm.idx_q:jm.idx_q + jm.nq]]
    if not locked:
        return model, locked
    reduced = pin.buildReducedModel(model, [joints[n] for n in locked], q_ref)
    reduced.name = model.name
    return reduced, locked


def demonstration_from_file(path: str | Path, model: pin.Model, *, fmt: str | None = None, asf: str | Path | None = None,
                            fps: float = 120.0, start: int | None = None, stop: int | None = None,
                            rate: float | None = None, fixed_pose: dict[str, float] | None = None,
                            locked: list[str] | None = None, clip_to_limits: bool = False) -> Demonstration:
    """The motion in the file ``path`` on the robot ``model`` (module doc); ``start``, ``stop``:
    the samples start .. stop - 1 (0-based, in file order); ``fixed_pose`` and ``locked`` declare the
    joints the file does not move (held at the given values, or at the model's neutral)."""
    path = Path(path)
    model = continuous_as_revolute(model)  # one angle per continuous joint, unbounded
    raw = read_raw_motion(path, model, fmt, None if asf is None else Path(asf), fps)
    n = len(raw.t)
    a, b = (0 if start is None else start), (n if stop is None else stop)
    if not 0 <= a < b <= n:
        raise MotionFileError(f"{path}: frame range start = {start}, stop = {stop} is empty or outside the "
                              f"file's {n} samples (0 .. {n - 1})")
    raw = RawMotion(raw.path, raw.t[a:b], raw.values[a:b], raw.names, raw.where[a:b])
    if len(raw.t) < 2:
        raise MotionFileError(f"{path}: {len(raw.t)} sample in the frame range; a motion needs at least 2")
    names, Q = _column_order(raw, model)
    lo, hi = _limits(model, names)
    clipped: dict[str, float] = {}
    if clip_to_limits:
        clipped = {n: float(v) for n, v in zip(names, np.max(np.maximum(lo - Q, Q - hi), axis=0)) if v > 0}
        Q = np.clip(Q, lo, hi)
    else:
        _check_limits(raw, names, Q, lo, hi, model.name)
    raw = RawMotion(raw.path, raw.t, Q, names, raw.where)
    t, Q, rate_hz, resampled = _uniform_time(raw, rate)
    if resampled:  # a cubic through samples at a limit may overshoot it between them: clipped
        over = np.max(np.maximum(lo - Q, Q - hi), axis=0)
        clipped.update({n: max(clipped.get(n, 0.0), float(v)) for n, v in zip(names, over) if v > 0})
        Q = np.clip(Q, lo, hi)
    reduced, held = _reduced(model, names, fixed_pose or {}, list(locked or []), path)
    return Demonstration(t=t, Q=Q, joint_names=names, model=reduced, source=str(path), locked=held,
                         rate_hz=float(rate_hz), resampled=resampled, clipped=clipped)


def load_demonstration(setting: str | dict[str, Any], model: pin.Model, base_dir: str | Path = ".") -> Demonstration:
    """The demonstration a ``training`` setting (:data:`TRAINING`) names, on ``model``; a file's
    paths are relative to ``base_dir``."""
    if isinstance(setting, str):
        t, Q = (np.asarray(a, dtype=float) for a in TRAINING_MOTIONS[setting]())
        names = [model.names[j] for j in range(1, model.njoints)]
        return Demonstration(t=t, Q=Q, joint_names=names, model=model, source=setting,
                             rate_hz=float((len(t) - 1) / (t[-1] - t[0])))
    base = Path(base_dir)
    return demonstration_from_file(base / setting["file"], model, fmt=setting["format"],
                                   asf=None if setting["asf"] is None else base / setting["asf"], fps=setting["fps"],
                                   start=setting["start"], stop=setting["stop"], rate=setting["rate"],
                                   fixed_pose=setting["fixed_pose"], locked=setting["locked"],
                                   clip_to_limits=setting["clip_to_limits"])


def check_frames(demo: Demonstration, latent_dim: int, stride: int = 1) -> None:
    """A MotionFileError if the frames (every ``stride``-th) are too few for a GPDM of ``latent_dim``
    (N >= d + 2, :func:`latentoc.gpdm.learning.prepare_data`) or d is not below the joints' count."""
    n = len(range(0, len(demo.t), stride)) + (1 if (len(demo.t) - 1) % stride else 0)
    D = len(demo.joint_names)
    if latent_dim >= D:
        raise MotionFileError(f"{demo.source}: latent dimension {latent_dim} must be below the motion's {D} joints")
    if n < latent_dim + 2:
        every = f" (every {stride}th of {len(demo.t)})" if stride > 1 else ""
        raise MotionFileError(f"{demo.source}: {n} frames{every} are too few for a GPDM of latent dimension "
                              f"{latent_dim}: it needs at least d + 2 = {latent_dim + 2}")
