"""The CMU subject 01 humanoid and its captured take 01_01 (Kang & Park 2015, Sect. 4.2).

* :func:`build_cmu_humanoid` - the CMU subject 01 skeleton (31 links, 62 DOF = 6 base
  + 56 revolute) as a Pinocchio model with de Leva (1996) masses (Table 5: 63.86 kg,
  1.75 m).
* :func:`skeleton_chain` - a fixed-base chain of an ASF skeleton's bones (a problem's own
  ``robot = { asf = ... }``);
* :func:`broad_jump_training_motion`, :func:`broad_jump_sequences` - standing broad
  jumps cut from CMU take 01_01 (Sect. 4.2, Table 5: 1.3 s).

The data files live in ``robots/cmu`` of the repository (or ``_data/robots/cmu``
inside an installed wheel), see :func:`cmu_file`. The 7-DOF arm of Sect. 4.1 is
:mod:`.human_arm`.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from latentoc.mocap.amc import Motion, read_amc
from latentoc.mocap.anthropometry import BONE_MAP, cmu_inertias
from latentoc.mocap.asf import Skeleton, read_asf
from latentoc.mocap.configurations import motion_to_q
from latentoc.mocap.jumps import detect_jumps, jump_window
from latentoc.mocap.skeleton_model import build_model
from latentoc.runtime.paths import data_dir
from latentoc.robots.robot_checks import check_model
from latentoc.robots.urdf import RobotFileError

__all__ = ["cmu_file", "cmu_skeleton", "cmu_motion", "build_cmu_humanoid", "cmu_configurations", "skeleton_chain",
           "broad_jump_sequences", "broad_jump_training_motion"]

ASF_NAME = "01.asf"
AMC_NAME = "01_01.amc"


def cmu_file(name: str) -> Path:
    """A file of ``robots/cmu`` (:func:`latentoc.runtime.paths.data_dir`: the checkout's, or the wheel's copy)."""
    return data_dir("robots") / "cmu" / name


@lru_cache(maxsize=1)
def cmu_skeleton() -> Skeleton:
    """The parsed CMU subject 01 skeleton."""
    return read_asf(cmu_file(ASF_NAME))


@lru_cache(maxsize=1)
def cmu_motion() -> Motion:
    """The parsed take 01_01 (2751 frames at 120 fps)."""
    return read_amc(cmu_file(AMC_NAME), cmu_skeleton())


def build_cmu_humanoid(mass: float = 63.86, height: float = 1.75) -> pin.Model:
    """CMU humanoid: free-flyer root + 30 bones, Z up, de Leva masses summing to ``mass``.

    Geometry is the ASF's (not rescaled, so AMC angles reproduce the capture exactly);
    ``height`` scales the de Leva segment lengths used for the radii of gyration.
    """
    skel = cmu_skeleton()
    root, inert = cmu_inertias(skel, mass, height)
    return build_model(skel, inertias=inert, root_inertia=root, name="cmu_humanoid")


def cmu_configurations(model: pin.Model | None = None, frames=None) -> np.ndarray:
    """All (or selected) frames of take 01_01 as humanoid configurations (n, 63)."""
    model = model if model is not None else build_cmu_humanoid()
    return motion_to_q(model, cmu_skeleton(), cmu_motion(), frames)


def skeleton_chain(asf: str | Path, bones: list[str], mass: float = 63.86, height: float = 1.75) -> pin.Model:
    """A fixed-base chain of ``bones`` of the ASF skeleton at ``asf`` (the first bone's parent is the
    world), de Leva masses of a subject of ``mass`` kg and ``height`` m, joints ``<bone>_<dof>`` as
    in the CMU humanoid; a :class:`~latentoc.robots.RobotFileError` if the file or a bone is wrong."""
    path = Path(asf)
    if not path.is_file():
        raise RobotFileError(f"skeleton {path} does not exist")
    skeleton = read_asf(path)
    unknown = [b for b in bones if b not in skeleton.bones]
    if unknown:
        raise RobotFileError(f"skeleton {path}: no bone {', '.join(map(repr, unknown))}; it has "
                             f"{', '.join(skeleton.bones)}")
    no_mass = [b for b in bones if b not in BONE_MAP]
    if no_mass:
        raise RobotFileError(f"skeleton {path}: bone {', '.join(map(repr, no_mass))} has no de Leva segment "
                             f"(CMU bone names: {', '.join(sorted(b for b in BONE_MAP if b != 'root'))})")
    _, inertias = cmu_inertias(skeleton, mass, height, bones=list(bones))
    model = build_model(skeleton, inertias=inertias, bones=list(bones), fixed_base=True, name=path.stem)
    if model.nv == 0:
        raise RobotFileError(f"skeleton {path}: the bones {', '.join(bones)} have no degrees of freedom")
    try:
        check_model(model, f"skeleton {path}")
    except ValueError as exc:
        raise RobotFileError(str(exc)) from None
    return model


def broad_jump_sequences() -> list[tuple[np.ndarray, np.ndarray]]:
    """Every standing broad jump of take 01_01 as (t, Q) with t starting at 0."""
    model = build_cmu_humanoid()
    Q = cmu_configurations(model)
    out = []
    for j in detect_jumps(model, Q):
        a, b = jump_window(j)
        if b > len(Q):  # keep the full length at the end of the take
            a, b = a - (b - len(Q)), len(Q)
        out.append((np.arange(b - a) / 120.0, Q[a:b].copy()))
    return out


def broad_jump_training_motion() -> tuple[np.ndarray, np.ndarray]:
    """The training broad jump: the first jump of the take, 157 frames = 1.3 s at 120 fps.

    The window starts 0.35 s before takeoff (crouch and arm swing), covers the ~0.34 s
    flight and ends after the landing has settled (Table 5: motion duration 1.3 s).
    """
    return broad_jump_sequences()[0]
