"""``latentoc simulate RESULT``: replay a result's torques in MuJoCo, write ``simulation.json`` and
``simulation.npz`` (into the result folder, or ``--out``) and print a summary.

The contact points come from ``trajectory.npz`` (:func:`contact_points`): per foot the heel (foot
frame + ``heel_offset``), the ball (the foot's end), the toe (the toes' end + ``toe_offset``, zero
in results written before it) and the pad (the toes' end + ``pad_offset``); the right foot's offsets
are the left's with one component negated: the local axis along which the right frame is the left
one's mirror image in the first frame of q (:func:`mirror_axis`; x in the CMU skeleton, whose
frames run along the bones in y), then :func:`check_mirror` compares the right points with the
mirrored left ones (1 mm). The
landing distance is the forward travel of the left toe point. Both files are written atomically
(:func:`latentoc.runtime.files.atomic_write`), the arrays first. A fall is a finding, not an error: the
exit code is 0 and ``simulation.json`` says ``"fell": true``.
"""
from __future__ import annotations

import argparse
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from latentoc.errors import LatentocError, ResultFileError, SimulationError
from latentoc.runtime.files import atomic_write, check_out_dir, write_json
from latentoc.results import load_result
from latentoc.simulate.mjcf import SOLIMP, SOLREF

if TYPE_CHECKING:
    from latentoc.simulate.replay import Simulation

__all__ = ["cmd_simulate", "contact_points", "mirror_axis", "check_mirror", "summary_lines", "DEFAULT_KP",
           "SIM_JSON", "SIM_NPZ"]

DEFAULT_KP = 200.0  # N m/rad, every joint (kd: critical damping per joint, latentoc.simulate.replay)
SIM_JSON, SIM_NPZ = "simulation.json", "simulation.npz"
MIRROR_TOL = 1e-3  # m: right points vs the mirrored left ones
FRICTION = 0.4  # a result without "friction"
RADIUS, TIMESTEP, INTEGRATOR = 0.005, 0.0005, "implicitfast"  # sphere radius (m), MuJoCo step (s)
# contact point -> (its frame among a foot's three: foot, foot end, toes end; its offset key)
_POINTS = {"heel": (0, "heel_offset"), "ball": (1, "ball_offset"), "toe": (2, "toe_offset"), "pad": (2, "pad_offset")}
_MIRROR_WORLD = np.diag([1.0, -1.0, 1.0])  # the sagittal plane's mirror

Contact = tuple[str, np.ndarray]


def contact_points(trajectory: Mapping[str, Any], model: pin.Model, where: str
                   ) -> tuple[list[Contact], list[Contact], dict[str, str]]:
    """The contact spheres (frame, offset) of a broad jump's ``trajectory`` (module doc), left foot
    first, the landing-distance point (the left toe tip) and the local
    axis each right frame's offsets are mirrored along (:func:`mirror_axis`)."""
    missing = [k for k in ("contact_frames", "contact_points", "heel_offset", "pad_offset") if k not in trajectory]
    if missing:
        raise ResultFileError(f"{where}: trajectory.npz has no contact data ({', '.join(missing)} missing); "
                              "simulate replays results with foot contacts (the broad jump)")
    frames = [str(f) for f in np.asarray(trajectory["contact_frames"]).ravel()]
    names = [str(p) for p in np.asarray(trajectory["contact_points"]).ravel()]
    unknown = sorted(set(names) - set(_POINTS))
    if len(frames) != 6 or unknown:
        raise ResultFileError(f"{where}: contact_frames {frames} and contact_points {names} are not a left and a "
                              f"right foot's three frames and points among {list(_POINTS)}")
    absent = [f for f in frames if not model.existFrame(f)]
    if absent:
        raise ResultFileError(f"{where}: the model has no contact frame {absent[0]!r}")
    offsets = {k: np.asarray(trajectory.get(k, np.zeros(3)), dtype=float).reshape(3)
               for k in ("heel_offset", "ball_offset", "toe_offset", "pad_offset")}
    q0 = np.asarray(trajectory["q"][0], dtype=float)
    axes = {frames[3 + i]: mirror_axis(model, q0, frames[i], frames[3 + i]) for i in range(3)}
    left = [(frames[i], offsets[key]) for i, key in (_POINTS[p] for p in names)]
    right = []
    for p, (_, offset) in zip(names, left):
        frame = frames[3 + _POINTS[p][0]]
        right.append((frame, offset * np.where(np.arange(3) == "xyz".index(axes[frame]), -1.0, 1.0)))
    point = [(frames[2], offsets["toe_offset"])]  # the toe tip: where the jump distance is measured
    return left + right, point, axes


def mirror_axis(model: pin.Model, q: np.ndarray, left: str, right: str) -> str:
    """The local axis ("x", "y" or "z") along which frame ``right`` is the mirror image of frame
    ``left`` in the base's sagittal plane at configuration ``q`` (a point with offset o in ``left``
    mirrors to o with that component negated in ``right``); a SimulationError if it is none."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    L, R = data.oMf[model.getFrameId(left)], data.oMf[model.getFrameId(right)]
    N = R.rotation.T @ _MIRROR_WORLD @ L.rotation
    for k, axis in enumerate("xyz"):
        flip = np.diag(np.where(np.arange(3) == k, -1.0, 1.0))
        if np.abs(N - flip).max() < MIRROR_TOL:
            return axis
    raise SimulationError(f"frame {right!r} is not the mirror image of {left!r} in the first frame of q "
                          f"(R_right^T M R_left = {np.round(N, 3).tolist()}, not a flip of one axis)")


def check_mirror(model: pin.Model, q: np.ndarray, contacts: Sequence[Contact], tol: float = MIRROR_TOL) -> float:
    """The largest distance between a right contact point and its left twin mirrored in the base's
    sagittal plane (y = the base's y) at configuration ``q``: a SimulationError above ``tol``."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, np.asarray(q, dtype=float))
    world = [data.oMf[model.getFrameId(f)].act(o) for f, o in contacts]
    half = len(contacts) // 2
    worst, which = 0.0, ""
    for (name, _), pl, pr in zip(contacts[half:], world[:half], world[half:]):
        mirrored = np.array([pl[0], 2.0 * q[1] - pl[1], pl[2]])
        gap = float(np.linalg.norm(pr - mirrored))
        if gap > worst:
            worst, which = gap, name
    if worst > tol:
        raise SimulationError(f"the right contact point on {which!r} is {1e3 * worst:.1f} mm from the mirrored left "
                              f"one in the first frame of q (tolerance {1e3 * tol:g} mm): the right foot is not the "
                              "left one's mirror image")
    return worst


def _replay(model: pin.Model, trajectory: Mapping[str, Any], kp: float, kd: float | None,
            contacts: list[Contact], point: list[Contact] | None, friction: float, desc: str) -> Simulation:
    from latentoc.simulate.replay import replay  # imports mujoco

    return replay(model, trajectory, kp, kd, contacts, friction, radius=RADIUS, timestep=TIMESTEP,
                  distance_point=point, integrator=INTEGRATOR, desc=desc)


def cmd_simulate(args: argparse.Namespace) -> int:
    """Replay RESULT in MuJoCo at ``--kp`` (and each ``--sweep-gains`` kp); write and print."""
    folder = Path(args.result)
    for name, value in [("--kp", args.kp), *(("--sweep-gains", k) for k in args.sweep_gains or ())]:
        if not (np.isfinite(value) and value > 0):
            raise SimulationError(f"{name} must be a positive gain (N m/rad), got {value}")
    if args.kd is not None and not (np.isfinite(args.kd) and args.kd >= 0):
        raise SimulationError(f"--kd must be a gain >= 0 (N m s/rad), got {args.kd}")
    if not folder.is_dir():
        raise ResultFileError(f"{folder}: no such result folder")
    out = check_out_dir(folder if args.out is None else args.out)
    try:
        import mujoco
    except ImportError:
        raise LatentocError("simulate needs MuJoCo: pip install -e '.[sim]'") from None
    trajectory = load_result(folder).trajectory
    model = pin.Model()
    model.loadFromString(str(trajectory["model"]))
    contacts, point, axes = contact_points(trajectory, model, str(folder))
    gap = check_mirror(model, trajectory["q"][0], contacts)
    friction = float(trajectory["friction"]) if "friction" in trajectory else FRICTION
    sim = _replay(model, trajectory, args.kp, args.kd, contacts, point, friction, "simulate")
    sweep = []
    for kp in args.sweep_gains or ():
        s = _replay(model, trajectory, kp, args.kd, contacts, point, friction, f"kp {kp:g}").summary
        sweep.append({k: s.get(k) for k in ("landing_distance", "landing_distance_planned", "fell", "fall_time",
                                            "base_tracking_rms", "base_tracking_max", "max_contact_slip")} | {"kp": kp})
    report = {"result": str(folder), "mujoco": mujoco.__version__, "timestep": TIMESTEP, "integrator": INTEGRATOR,
              "contact": {"radius": RADIUS, "floor_z": -RADIUS, "friction": friction, "cone": "elliptic", "condim": 3,
                          "solref": list(SOLREF), "solimp": list(SOLIMP), "mirror_gap": gap, "mirror_axes": axes,
                          "points": [{"frame": f, "offset": o.tolist()} for f, o in contacts]},
              "summary": {k: v for k, v in sim.summary.items() if k != "gains"}, "gains": sim.summary["gains"],
              "sweep": sweep}
    out.mkdir(parents=True, exist_ok=True)
    atomic_write(out / SIM_NPZ, lambda f: np.savez(f, **sim.arrays()), binary=True)
    write_json(out / SIM_JSON, report)
    for line in summary_lines(report):
        print(line)
    print(f"wrote {out / SIM_JSON}, {out / SIM_NPZ}")
    return 0


def summary_lines(report: Mapping[str, Any]) -> list[str]:
    """The printed summary of a ``simulation.json`` report."""
    s, g = report["summary"], report["gains"]
    lines = [f"replayed {s['duration']:.3f} of {s['planned_duration']:.3f} s in MuJoCo {report['mujoco']} "
             f"({1e3 * report['timestep']:g} ms steps): kp {g['kp']:g} N m/rad, kd {g['kd_rule']} "
             f"{g['kd_min']:.3g}-{g['kd_max']:.3g} N m s/rad"]
    if "landing_distance" in s:
        lines.append(f"landing distance {s['landing_distance']:.3f} m (planned {s['landing_distance_planned']:.3f} m); "
                     f"base off the plan by {s['base_tracking_rms']:.3f} m rms, {s['base_tracking_max']:.3f} m at most")
    state = (("DIVERGED" if s["diverged"] else "FELL") + f" at {s['fall_time']:.3f} s") if s["fell"] else "stayed upright"
    excess = s.get("torque_excess")
    torques = ("" if excess is None else "; torques within their limits" if excess["max"] <= 1e-9 else
               f"; torques beyond the limits by up to {excess['max']:.1f} N m ({excess['joint']}, "
               f"{100 * excess['fraction']:.0f} % of samples)")
    if "clamped_fraction" in s and excess is not None:
        torques += f", clamped to them on {100 * s['clamped_fraction']:.1f} % of samples"
    lines.append(f"{state}; contact slip up to {1e3 * s['max_contact_slip']:.1f} mm{torques}")
    if "initial_contact_height_min" in s and max(-s["initial_contact_height_min"], s["initial_contact_height_max"]) > 1e-3:
        lines.append(f"note: the plan's contact points start {1e3 * s['initial_contact_height_min']:+.1f} to "
                     f"{1e3 * s['initial_contact_height_max']:+.1f} mm from the ground")
    for row in report.get("sweep", []):
        lines.append(f"  kp {row['kp']:g}: " + (f"fell at {row['fall_time']:.3f} s" if row["fell"] else "upright")
                     + f", landing {row['landing_distance']:.3f} m, base off by up to {row['base_tracking_max']:.3f} m")
    return lines
