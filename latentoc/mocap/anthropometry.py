"""Segment masses, centres of mass and inertias for the CMU skeleton.

Source: P. de Leva, "Adjustments to Zatsiorsky-Seluyanov's segment inertia
parameters", J. Biomechanics 29(9):1223-1230, 1996, Table 4 (male values): mass in % of
body mass, COM position in % of segment length from the listed origin, radii of
gyration (sagittal, transverse, longitudinal) in % of segment length, and the mean
segment lengths of the reference sample (stature 1741 mm).  Masses are scaled to the
total mass, lengths used for the radii of gyration to the stature (Kang & Park 2015,
Table 5: 63.86 kg, 1.75 m).

Mapping onto the CMU bones (documented lumping/splitting; fractions of the de Leva
segment):

============== ======================= =========================================
de Leva        CMU bones               split
============== ======================= =========================================
head (+neck)   lowerneck, upperneck,   0.10, 0.10, 0.80 (head carries the skull)
               head
upper trunk    thorax, l/rclavicle     0.70, 0.15, 0.15 (shoulder girdle)
middle trunk   upperback, lowerback    0.50, 0.50
lower trunk    root, l/rhipjoint       0.50, 0.25, 0.25 (pelvis spread to hips)
upper arm      l/rhumerus              1.0 each side
forearm        l/rradius, l/rwrist     2/3, 1/3 (CMU splits the forearm ~2:1)
hand           l/rhand, fingers, thumb 0.50, 0.30, 0.20
thigh          l/rfemur                1.0
shank          l/rtibia                1.0
foot           l/rfoot, l/rtoes        0.75, 0.25
============== ======================= =========================================

The COM of a piece lies on its bone at the de Leva fraction measured from the
bone's start (spine and head bones point upwards, so the cranial-origin de Leva
fractions are flipped); minor pieces (share < 0.5) have it at mid-bone; the root's
COM is at the root.  A piece's inertia about its
COM is ``share * m_seg * diag((r_sag L)^2, (r_trans L)^2, (r_long L)^2)`` with the
long axis along the bone (vertical for the root), so it is positive definite.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from latentoc.mocap.asf import Skeleton
from latentoc.mocap.skeleton_model import P_ASF_TO_WORLD, euler_matrix

DE_LEVA_STATURE = 1.741  # m, male reference sample

# name: (mass %, COM % from de Leva origin, r_sag %, r_trans %, r_long %, length mm, origin)
DE_LEVA_MALE: dict[str, tuple[float, float, float, float, float, float, str]] = {
    "head": (6.94, 59.76, 36.2, 37.6, 31.2, 242.9, "VERT"),
    "upper_trunk": (15.96, 50.66, 50.5, 32.0, 46.5, 242.1, "CERV"),
    "middle_trunk": (16.33, 45.02, 48.2, 38.3, 46.8, 215.5, "XYPH"),
    "lower_trunk": (11.17, 61.15, 61.5, 55.1, 58.7, 145.7, "OMPH"),
    "upper_arm": (2.71, 57.72, 28.5, 26.9, 15.8, 281.7, "SJC"),
    "forearm": (1.62, 45.74, 27.6, 26.5, 12.1, 268.9, "EJC"),
    "hand": (0.61, 79.00, 62.8, 51.3, 40.1, 86.2, "WJC"),
    "thigh": (14.16, 40.95, 32.9, 32.9, 14.9, 422.2, "HJC"),
    "shank": (4.33, 44.59, 25.5, 24.9, 10.3, 434.0, "KJC"),
    "foot": (1.37, 44.15, 25.7, 24.5, 12.4, 258.1, "HEEL"),
}
BILATERAL = ("upper_arm", "forearm", "hand", "thigh", "shank", "foot")

# bone -> (de Leva segment, share, COM fraction from bone start or None for midpoint)
_CRANIAL = {"head", "upper_trunk", "middle_trunk", "lower_trunk"}
BONE_MAP: dict[str, tuple[str, float]] = {
    "lowerneck": ("head", 0.10), "upperneck": ("head", 0.10), "head": ("head", 0.80),
    "thorax": ("upper_trunk", 0.70), "lclavicle": ("upper_trunk", 0.15),
    "rclavicle": ("upper_trunk", 0.15),
    "upperback": ("middle_trunk", 0.50), "lowerback": ("middle_trunk", 0.50),
    "root": ("lower_trunk", 0.50), "lhipjoint": ("lower_trunk", 0.25),
    "rhipjoint": ("lower_trunk", 0.25),
}
for _s in ("l", "r"):
    BONE_MAP.update({
        f"{_s}humerus": ("upper_arm", 1.0), f"{_s}radius": ("forearm", 2 / 3),
        f"{_s}wrist": ("forearm", 1 / 3), f"{_s}hand": ("hand", 0.50),
        f"{_s}fingers": ("hand", 0.30), f"{_s}thumb": ("hand", 0.20),
        f"{_s}femur": ("thigh", 1.0), f"{_s}tibia": ("shank", 1.0),
        f"{_s}foot": ("foot", 0.75), f"{_s}toes": ("foot", 0.25),
    })


@dataclass
class Segment:
    """One de Leva segment scaled to a subject."""

    mass: float
    length: float
    com_fraction: float
    radii: np.ndarray  # sagittal, transverse, longitudinal, in metres


def de_leva_segments(mass: float = 63.86, height: float = 1.75) -> dict[str, Segment]:
    """De Leva (1996) male segments scaled to ``mass`` (kg) and ``height`` (m).

    Masses of one side; the percentages (both sides counted) sum to 100 %.
    """
    out = {}
    for k, (pm, pc, rs, rt, rl, lmm, _o) in DE_LEVA_MALE.items():
        L = lmm / 1000.0 * height / DE_LEVA_STATURE
        out[k] = Segment(mass * pm / 100.0, L, pc / 100.0, np.array([rs, rt, rl]) / 100.0 * L)
    return out


def _frame_with_long_axis(d: np.ndarray) -> np.ndarray:
    """Rotation whose third column is ``d`` (unit)."""
    d = d / np.linalg.norm(d)
    a = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(a, d)
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(d, e1), d])


def piece_inertia(mass: float, radii: np.ndarray, com: np.ndarray, long_axis: np.ndarray) -> pin.Inertia:
    """Spatial inertia of a piece with radii of gyration about its COM, long axis given."""
    R = _frame_with_long_axis(long_axis)
    I = R @ np.diag(mass * radii**2) @ R.T
    return pin.Inertia(mass, com, 0.5 * (I + I.T))


def cmu_inertias(skeleton: Skeleton, mass: float = 63.86, height: float = 1.75,
                 bones: list[str] | None = None, total: float | None = None,
                 ) -> tuple[pin.Inertia, dict[str, pin.Inertia]]:
    """Root inertia and per-bone inertias (in each bone's body frame) for the CMU skeleton.

    With ``bones`` only those bones get mass; with ``total`` the masses of the selected
    pieces are rescaled so that they sum to ``total`` exactly (inertias scale along).
    Without both, root + 30 bones sum to ``mass`` exactly.
    """
    seg = de_leva_segments(mass, height)
    u = skeleton.unit_to_m
    names = list(bones) if bones is not None else ["root", *skeleton.bones]
    pieces: dict[str, tuple[float, np.ndarray, np.ndarray, np.ndarray]] = {}
    for bn in names:
        sname, share = BONE_MAP[bn]
        s = seg[sname]
        m = s.mass * share
        if bn == "root":
            pieces[bn] = (m, s.radii, np.zeros(3), np.array([0.0, 0.0, 1.0]))
            continue
        b = skeleton.bones[bn]
        C = euler_matrix(b.axis, b.axis_order)
        vec = C.T @ (b.direction * b.length * u)  # bone vector in its body frame
        frac = 1.0 - s.com_fraction if sname in _CRANIAL else s.com_fraction
        if share < 0.5:  # minor piece of a split segment: COM at mid-bone
            frac = 0.5
        pieces[bn] = (m, s.radii, frac * vec, vec)
    scale = 1.0
    if total is not None:
        scale = total / sum(p[0] for p in pieces.values())
    elif bones is None:
        scale = mass / sum(p[0] for p in pieces.values())  # = 1 up to rounding
    out = {bn: piece_inertia(m * scale, r, c, ax) for bn, (m, r, c, ax) in pieces.items()}
    root = out.pop("root", pin.Inertia.Zero())
    return root, out


def root_long_axis_world() -> np.ndarray:
    """The root body frame is world aligned at rest: vertical is +z (ASF +y)."""
    return P_ASF_TO_WORLD @ np.array([0.0, 1.0, 0.0])
