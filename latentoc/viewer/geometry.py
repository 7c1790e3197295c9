"""What the 3-D view draws of a robot: its own visual meshes where its URDF has them, else capsules
along the stick figure's bones (the CMU skeleton models).

A :class:`Part` is one rigid shape: a triangle mesh (vertices in its own frame), a box, sphere,
cylinder or capsule, attached to a frame of the result's model by name with a fixed placement.
:func:`part_poses` places every part at each configuration (numeric forward kinematics). Meshes
are read by Pinocchio (coal/assimp) from the URDF's ``package://`` or relative paths; a reduced
model (joints locked by a demonstration) keeps the URDF's frame names, so parts find their frame.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.plots.kinematics import bones, side

__all__ = ["Part", "robot_parts", "mesh_parts", "capsule_parts", "part_poses", "urdf_of_setting"]

SIDE_RGB = {"left": (0.25, 0.45, 0.9), "right": (0.9, 0.3, 0.25), "centre": (0.62, 0.62, 0.66)}
MESH_RGB = (0.82, 0.84, 0.88)  # a URDF's default grey (0.9) is too bright under the lights


@dataclass
class Part:
    """One rigid shape: ``kind`` "mesh" (``vertices`` (k, 3), ``triangles`` (m, 3)), "box" (``size``:
    3 edge lengths), "sphere" (radius), "cylinder" or "capsule" (radius, length along local z);
    attached to frame ``frame`` (or joint, ``on_joint``) of the model at ``placement``."""

    name: str
    kind: str
    frame: str
    placement: pin.SE3
    colour: tuple[float, float, float]
    size: tuple[float, ...] = ()
    vertices: np.ndarray | None = None
    triangles: np.ndarray | None = None
    on_joint: bool = False
    segment: tuple[str, int, str, int] | None = None  # a bone: placed between two points each pose


def urdf_of_setting(robot: Any, source: str | None) -> tuple[Path, list[Path]] | None:
    """The URDF and package folders of a problem's ``robot`` setting (a name or a ``{urdf = ...}``
    table relative to the problem file ``source``); None for a model without a URDF."""
    from latentoc.robots import example_robot_data_dir, robot_urdf

    if isinstance(robot, str):
        try:
            urdf = robot_urdf(robot)
        except LookupError:
            return None
        return None if urdf is None else (urdf, [example_robot_data_dir().parents[1]])
    if isinstance(robot, dict) and "urdf" in robot:
        base = Path(source).parent if source else Path(".")
        dirs = [base / d for d in robot.get("package_dirs", [])]
        text = str(robot["urdf"])
        if text.startswith("package://"):
            rest = text[len("package://"):]
            found = [d / rest for d in dirs if (d / rest).is_file()]
            return (found[0], dirs) if found else None
        urdf = base / text
        return (urdf, dirs + [urdf.parent]) if urdf.is_file() else None
    return None


def _shape(geometry: Any) -> tuple[str, tuple[float, ...], np.ndarray | None, np.ndarray | None] | None:
    """(kind, size, vertices, triangles) of a coal geometry; None for a shape the view cannot draw."""
    name = type(geometry).__name__
    if name.startswith("BVHModel"):
        V = np.array(geometry.vertices(), dtype=float).reshape(-1, 3)
        T = np.array([[t[0], t[1], t[2]] for t in (geometry.tri_indices(i) for i in range(geometry.num_tris))],
                     dtype=np.int64).reshape(-1, 3)
        return "mesh", (), V, T
    if name == "Box":
        return "box", tuple(2.0 * np.asarray(geometry.halfSide, dtype=float)), None, None
    if name == "Sphere":
        return "sphere", (float(geometry.radius),), None, None
    if name in ("Cylinder", "Capsule"):
        return name.lower(), (float(geometry.radius), 2.0 * float(geometry.halfLength)), None, None
    return None


def mesh_parts(model: pin.Model, urdf: Path, package_dirs: list[Path]) -> list[Part]:
    """The URDF's visual shapes, each on its body frame by name (a frame of ``model``)."""
    full = pin.buildModelFromUrdf(str(urdf))
    geom = pin.buildGeomFromUrdf(full, str(urdf), pin.GeometryType.VISUAL, package_dirs=[str(d) for d in package_dirs])
    parts = []
    for go in geom.geometryObjects:
        frame = full.frames[go.parentFrame]
        shape = _shape(go.geometry)
        if shape is None or not model.existFrame(frame.name):
            continue
        kind, size, V, T = shape
        rgba = np.asarray(go.meshColor, dtype=float)
        colour = MESH_RGB if np.allclose(rgba[:3], 0.9) else tuple(float(c) for c in rgba[:3])
        # the shape's placement relative to its body frame (both given relative to the parent joint)
        parts.append(Part(go.name, kind, frame.name, frame.placement.inverse() * go.placement, colour,  # type: ignore[arg-type]
                          size, V, T))
    return parts


def capsule_parts(model: pin.Model, radius: float = 0.025) -> list[Part]:
    """A capsule along every stick-figure bone (:func:`latentoc.plots.bones`), coloured by side."""
    data = model.createData()
    pin.forwardKinematics(model, data, pin.neutral(model))
    pin.updateFramePlacements(model, data)
    parts = []
    for _, a, kind, b, name in bones(model):
        end = data.oMi[b] if kind == "joint" else data.oMf[b]
        length = float(np.linalg.norm(end.translation - data.oMi[a].translation))
        if length < 1e-9:
            continue
        parts.append(Part(f"bone_{name}", "capsule", model.names[a], pin.SE3.Identity(), SIDE_RGB[side(model, name)],
                          (radius, length), segment=("joint", a, kind, b)))
    return parts


def robot_parts(model: pin.Model, robot: Any = None, source: str | None = None) -> tuple[list[Part], str]:
    """The parts of ``model`` and what they are ("meshes" of the URDF, or "capsules"); a URDF whose
    meshes cannot be read falls back to capsules with a warning."""
    found = urdf_of_setting(robot, source)
    if found is not None:
        try:
            parts = mesh_parts(model, *found)
            if parts:
                return parts, "meshes"
        except (ValueError, RuntimeError) as exc:
            warnings.warn(f"{found[0]}: its meshes could not be read ({exc}); drawing capsules", stacklevel=2)
    return capsule_parts(model), "capsules"


def _segment_pose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Position and quaternion (x, y, z, w) of a capsule from a to b (local z along the bone)."""
    d = b - a
    n = float(np.linalg.norm(d))
    z = d / n if n > 1e-12 else np.array([0.0, 0.0, 1.0])
    quat = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), z)  # the shortest rotation taking z to d
    return np.concatenate([0.5 * (a + b), quat.coeffs()])


def part_poses(model: pin.Model, parts: list[Part], Q: np.ndarray) -> np.ndarray:
    """World pose (position, quaternion x y z w) of every part at every configuration: (n, parts, 7)."""
    data = model.createData()
    frame_ids = [model.getFrameId(p.frame) if p.segment is None else -1 for p in parts]
    out = np.zeros((len(Q), len(parts), 7))
    for i, q in enumerate(np.asarray(Q, dtype=float)):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        for k, (p, f) in enumerate(zip(parts, frame_ids)):
            if p.segment is not None:
                _, a, kind, b = p.segment
                end = data.oMi[b] if kind == "joint" else data.oMf[b]
                out[i, k] = _segment_pose(data.oMi[a].translation, end.translation)
            else:
                M = data.oMf[f] * p.placement
                out[i, k] = np.concatenate([M.translation, pin.Quaternion(M.rotation).coeffs()])
    return out
