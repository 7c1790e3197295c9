"""The legged robot of a contact problem, declared in its problem file (``[robot]``).

The contact kind knows a robot only through this declaration: its model, the left/right mirror of
its joints and frames, the left foot's four contact points (the rows' heel, ball, toe tip and
pad, :data:`.feet.POINTS`; the right foot is the mirror image) and where its torque limits come
from. The CMU humanoid is one such declaration (:data:`CMU_HUMANOID`, the defaults)::

    [robot]
    model = "cmu-humanoid"       # the symmetrised CMU skeleton, or a name from `list --robots`
    mirror = ["l", "r"]          # a right frame's name: the left's with the first "l" made "r"
    limits = "training"          # Eq. 34 torques from the training's inverse dynamics, or "urdf": the
                                 # model's effort, position and velocity limits
    motion = ""                  # the robot's demonstration (NPZ/CSV of t, q); "": take 01_01
    [robot.foot]                 # each point fixed in a frame of the left foot
    heel = { frame = "lfoot", ground = true }            # the frame's origin dropped to the ground
    ball = { frame = "lfoot_end" }                       # the frame's origin
    toe = { frame = "ltoes_end" }
    pad = { frame = "ltoes_end", ground = true, shift = [-0.01, 0.0] }  # 1 cm behind, on the ground

A point is ``offset`` (in the frame's coordinates) from the frame's origin, or, with ``ground``,
the origin moved by ``shift`` (world x, y) and dropped to the ground at the standing pose (the
lowest of the other points), both fixed in the frame from then on.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.errors import ProblemError
from latentoc.mocap.symmetry import MirrorError, SymmetryMap
from latentoc.robots.catalog import load_robot, robot_names
from latentoc.robots.cmu_humanoid import symmetric_model
from latentoc.problem.schema import Check, choice
from latentoc.jump.robot.feet import MIRROR, POINTS, ContactPoint, FootGeometry, foot_points

__all__ = ["PointDeclaration", "RobotDeclaration", "CMU_HUMANOID", "ROBOT_KEYS", "declaration", "robot_model"]

MIRROR_TOLERANCE = 1e-3  # m between a right frame and the mirror image of its left partner, standing
FLAT_TOLERANCE = 5e-3  # m a point may stand above the lowest (the CMU's toe tip: 1 mm)
LIMIT_SOURCES = ("training", "urdf")


@dataclass(frozen=True)
class PointDeclaration:
    """One contact point of the left foot (module doc)."""

    frame: str
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ground: bool = False
    shift: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class RobotDeclaration:
    """The ``[robot]`` table: model name, mirror strings, limit source, the left foot's points."""

    model: str
    mirror: tuple[str, str]
    limits: str
    foot: tuple[PointDeclaration, ...]  # in POINTS' order
    motion: str = ""  # the robot's demonstration, relative to the problem file ("": the CMU's take 01_01)

    def right_frame(self, frame: str) -> str:
        """The mirror partner's name of a left frame."""
        left, right = self.mirror
        return frame.replace(left, right, 1)

    def geometry(self, model: pin.Model, q_stand: np.ndarray, on_ground: bool = True) -> FootGeometry:
        """The foot's points fixed in their frames from the standing pose ``q_stand`` (module doc),
        each left frame's mirror partner checked against the model there and, with ``on_ground``,
        every point checked to stand on the ground."""
        d = model.createData()
        pin.framesForwardKinematics(model, d, q_stand)
        for key, p in zip(POINTS, self.foot):
            for name, what in ((p.frame, "frame"), (self.right_frame(p.frame), "mirror partner")):
                if not model.existFrame(name):
                    raise ProblemError(f"key 'robot.foot.{key}': the model has no {what} {name!r}")
            L, R = (d.oMf[model.getFrameId(n)].translation for n in (p.frame, self.right_frame(p.frame)))
            if np.linalg.norm(R - MIRROR @ L) > MIRROR_TOLERANCE:
                raise ProblemError(f"key 'robot.mirror': frame {self.right_frame(p.frame)!r} is not the mirror image "
                                   f"of {p.frame!r} standing ({R.round(4)} and {L.round(4)})")
        placed = {k: d.oMf[model.getFrameId(p.frame)] for k, p in zip(POINTS, self.foot)}
        fixed = [placed[k].translation + placed[k].rotation @ np.asarray(p.offset)
                 for k, p in zip(POINTS, self.foot) if not p.ground]
        if not fixed:
            raise ProblemError("key 'robot.foot': every point is on the ground by declaration; "
                               "at least one must be a fixed offset (the ground is the lowest of those)")
        ground = min(x[2] for x in fixed)
        points = []
        for k, p in zip(POINTS, self.foot):
            M = placed[k]
            if p.ground:
                at = M.translation + np.array([p.shift[0], p.shift[1], ground - M.translation[2]])
                points.append(ContactPoint(k, p.frame, M.rotation.T @ (at - M.translation)))
            else:
                points.append(ContactPoint(k, p.frame, None if not any(p.offset) else np.asarray(p.offset, float)))
        geom = FootGeometry(tuple(points), {p.frame: self.right_frame(p.frame) for p in self.foot})
        geom.footprint = foot_points(model, d, geom)
        geom.right_points = tuple(_mirrored(model, d, c, geom.right[c.frame], geom.footprint[:, k])
                                  for k, c in enumerate(geom.points))
        high = {k: z - ground for k, z in zip(POINTS, geom.footprint[2]) if z - ground > FLAT_TOLERANCE}
        if high and on_ground:  # the rows hold each point's height above its standing one: all must stand on the ground
            raise ProblemError("key 'robot.foot': standing (the motion's first frame) every point must be on the "
                               f"ground; {', '.join(f'{k} {1000 * h:.1f} mm' for k, h in high.items())} above it")
        x = dict(zip(POINTS, geom.footprint[0]))
        if not x["heel"] < x["ball"] < x["pad"] < x["toe"]:  # the centre of pressure rows' order
            raise ProblemError("key 'robot.foot': standing, the points must lie heel, ball, pad, toe from back to "
                               f"front along x; they are at {', '.join(f'{k} {v:.4f}' for k, v in x.items())} m")
        return geom


def _mirrored(model: pin.Model, d: pin.Data, c: ContactPoint, right: str, at: np.ndarray) -> ContactPoint:
    """The point of frame ``right`` at the mirror image of the left point ``at`` (frames placed)."""
    if c.offset is None:
        return ContactPoint(c.name, right, None)
    M = d.oMf[model.getFrameId(right)]
    return ContactPoint(c.name, right, M.rotation.T @ (MIRROR @ at - M.translation))


#: the CMU humanoid (the defaults of ``[robot]``)
CMU_HUMANOID = RobotDeclaration(
    "cmu-humanoid", ("l", "r"), "training",
    (PointDeclaration("lfoot", ground=True), PointDeclaration("lfoot_end"), PointDeclaration("ltoes_end"),
     PointDeclaration("ltoes_end", ground=True, shift=(-0.01, 0.0))))


def _as_table(p: PointDeclaration) -> dict[str, Any]:
    if p.ground:
        return {"frame": p.frame, "ground": True, "shift": list(p.shift)}
    return {"frame": p.frame, "offset": list(p.offset)}


def _numbers(v: Any, n: int) -> list[float]:
    if not isinstance(v, (list, tuple)) or len(v) != n or not all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in v):
        raise ValueError
    return [float(x) for x in v]


def _point(v: Any) -> dict[str, Any]:
    if not isinstance(v, Mapping) or set(v) - {"frame", "offset", "ground", "shift"}:
        raise ValueError
    frame, ground = v.get("frame"), v.get("ground", False)
    if not isinstance(frame, str) or not frame or not isinstance(ground, bool):
        raise ValueError
    if ground and "offset" in v or not ground and "shift" in v:
        raise ValueError
    if ground:
        return {"frame": frame, "ground": True, "shift": _numbers(v.get("shift", [0.0, 0.0]), 2)}
    return {"frame": frame, "offset": _numbers(v.get("offset", [0.0, 0.0, 0.0]), 3)}


def _foot(value: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(value, Mapping) or set(value) != set(POINTS):
        raise ValueError
    return {k: _point(value[k]) for k in POINTS}


def _mirror(value: Any) -> list[str]:
    if not isinstance(value, (list, tuple)) or len(value) != 2 or not all(isinstance(s, str) and s for s in value) \
            or value[0] == value[1]:
        raise ValueError
    return [value[0], value[1]]


def _motion(value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError
    return value


def _model_name(value: Any) -> str:
    if not isinstance(value, str) or value not in robot_names() or value == "human-arm":
        raise ValueError
    return value


#: the ``[robot]`` keys: (check, default (the CMU humanoid's), doc), the schema's settings (:mod:`..problem`)
ROBOT_KEYS: dict[str, tuple[Check, Any, str]] = {
    "model": (Check(_model_name, "a robot name from `latentoc list --robots` with a floating base"),
              CMU_HUMANOID.model, "the robot: cmu-humanoid (the symmetrised CMU skeleton) or a catalogue name"),
    "mirror": (Check(_mirror, '["left", "right"]: two different strings'), list(CMU_HUMANOID.mirror),
               "a right frame's name is its left partner's with the first string made the second"),
    "limits": (choice(*LIMIT_SOURCES), CMU_HUMANOID.limits,
               '"training" (Eq. 34 torque limits from the training inverse dynamics) or "urdf" (the model\'s effort, '
               'position and velocity limits, all hard)'),
    "motion": (Check(_motion, "a path (relative to the problem file) of an NPZ or CSV of t and q, or \"\""), "",
               "the robot's demonstration of the jump (`retarget` writes one); \"\": the CMU humanoid's take 01_01"),
    "foot": (Check(_foot, 'a table of the points heel, ball, toe and pad, each { frame = "name", offset = [x, y, z] }'
                          ' or { frame = "name", ground = true, shift = [dx, dy] }'),
             {k: _point(_as_table(p)) for k, p in zip(POINTS, CMU_HUMANOID.foot)},
             "the left foot's contact points (the right foot is their mirror image)"),
}


def declaration(values: Mapping[str, Any]) -> RobotDeclaration:
    """The declaration of a problem's checked ``[robot]`` values (``robot_<key>`` by name)."""
    foot = values["robot_foot"]
    points = tuple(PointDeclaration(foot[k]["frame"], tuple(foot[k].get("offset", (0.0, 0.0, 0.0))),
                                    foot[k].get("ground", False), tuple(foot[k].get("shift", (0.0, 0.0))))
                   for k in POINTS)
    return RobotDeclaration(values["robot_model"], tuple(values["robot_mirror"]),  # type: ignore[arg-type]
                            values["robot_limits"], points, values["robot_motion"])  # type: ignore[arg-type]


def robot_model(decl: RobotDeclaration) -> tuple[pin.Model, SymmetryMap]:
    """The model and its joints' mirror: the CMU humanoid's from its skeleton, a URDF robot's from
    its joint names (:meth:`SymmetryMap.from_joint_names`)."""
    if decl.model == "cmu-humanoid":
        return symmetric_model()
    model = load_robot(decl.model)
    if model.joints[1].shortname() != "JointModelFreeFlyer":
        raise ProblemError(f"key 'robot.model': {decl.model!r} has a fixed base; a contact problem needs a floating one")
    try:
        return model, SymmetryMap.from_joint_names(model, *decl.mirror)
    except MirrorError as exc:
        raise ProblemError(f"key 'robot.mirror' {list(decl.mirror)} does not mirror {decl.model!r}'s joints: {exc}") from None
