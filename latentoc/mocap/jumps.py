"""Phase detection of standing broad jumps in a captured take (Kang & Park 2015, Sect. 4.2).

Nothing is hard-coded about the take: phases come from the heights of the feet
(the lowest of each foot's low points: the CMU humanoid's ``<side>toes_end`` and
``<side>foot_end`` frames, or a robot's declared sole points) and from the root speed,
computed by forward kinematics of the model.

* The local ground level of each foot is a running 10th percentile of its height
  (window 2 s), which follows slow drift of the capture volume.
* A flight is a run of frames in which *both* feet are more than ``core_height`` above
  their ground level; it is widened to the frames in which both feet are more than
  ``contact_height`` up: ``takeoff`` is the first airborne frame, ``touchdown`` the
  first frame with a foot back on the ground.
* ``start_still``/``end_still`` are the nearest frames before takeoff / after
  touchdown (but not beyond the neighbouring flights) at which the lightly smoothed
  root speed is below ``still_speed`` (0.25 m/s; the subject sways a little between
  jumps), or the slowest frame there if it never is.
* ``distance`` is the horizontal displacement of the mid-point of the two ankles
  between ``start_still`` and ``end_still``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy.ndimage import percentile_filter, uniform_filter1d


@dataclass(frozen=True)
class Jump:
    """Frame indices (0-based) of one jump and its horizontal distance in metres."""

    start_still: int
    takeoff: int
    touchdown: int
    end_still: int
    distance: float
    fps: float = 120.0

    @property
    def flight_time(self) -> float:
        """Seconds between takeoff and touchdown."""
        return (self.touchdown - self.takeoff) / self.fps


#: a point fixed in a frame: (frame, offset in it; None: the frame's origin)
FramePoint = tuple[str, "np.ndarray | None"]
#: the CMU humanoid's feet: each foot's low points (toes end, foot end) and the ankles (tibia ends)
CMU_FEET: tuple[tuple[FramePoint, ...], tuple[FramePoint, ...]] = (
    (("ltoes_end", None), ("lfoot_end", None)), (("rtoes_end", None), ("rfoot_end", None)))
CMU_ANKLES: tuple[FramePoint, FramePoint] = (("ltibia_end", None), ("rtibia_end", None))


def feature_tracks(model: pin.Model, Q: np.ndarray, feet=CMU_FEET, ankles=CMU_ANKLES) -> dict[str, np.ndarray]:
    """Foot low-point heights (the lowest of each foot's ``feet`` points), ankle positions and root
    positions along ``Q``."""
    d = model.createData()
    points = [*feet[0], *feet[1], *ankles]
    ids = [model.getFrameId(f) for f, _ in points]
    P = np.zeros((len(Q), len(ids), 3))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, d, q)
        for k, (f, (_, offset)) in enumerate(zip(ids, points)):
            M = d.oMf[f]
            P[i, k] = M.translation if offset is None else M.translation + M.rotation @ offset
    n_l, n_r = len(feet[0]), len(feet[1])
    return {"left": P[:, :n_l, 2].min(axis=1),
            "right": P[:, n_l:n_l + n_r, 2].min(axis=1),
            "ankles": 0.5 * (P[:, -2] + P[:, -1]),
            "root": np.array(Q[:, :3])}


def detect_jumps(model: pin.Model, Q: np.ndarray, fps: float = 120.0,
                 core_height: float = 0.08, contact_height: float = 0.015,
                 still_speed: float = 0.25, min_flight: float = 0.08, feet=CMU_FEET, ankles=CMU_ANKLES) -> list[Jump]:
    """All two-footed jumps in the configurations ``Q`` (n, nq) of a free-flyer model whose feet's
    low points and ankles are ``feet`` and ``ankles`` (:func:`feature_tracks`)."""
    tr = feature_tracks(model, Q, feet, ankles)
    win = int(2 * fps) | 1
    elev = np.minimum(tr["left"] - percentile_filter(tr["left"], 10, size=win, mode="nearest"),
                      tr["right"] - percentile_filter(tr["right"], 10, size=win, mode="nearest"))
    core = np.concatenate([[False], elev > core_height, [False]])
    d = np.diff(core.astype(int))
    starts, ends = np.where(d == 1)[0], np.where(d == -1)[0]
    speed = np.linalg.norm(np.gradient(tr["root"], axis=0), axis=1) * fps
    speed = uniform_filter1d(speed, max(1, int(round(0.04 * fps))), mode="nearest")
    n = len(Q)
    flights: list[tuple[int, int]] = []
    for s, e in zip(starts, ends):
        if (e - s) < min_flight * fps:
            continue
        a = s
        while a > 0 and elev[a - 1] > contact_height:
            a -= 1
        b = e
        while b < n - 1 and elev[b] > contact_height:
            b += 1
        if flights and a <= flights[-1][1]:
            continue
        flights.append((a, b))
    jumps: list[Jump] = []
    for k, (a, b) in enumerate(flights):
        lo = flights[k - 1][1] if k > 0 else 0
        hi = flights[k + 1][0] if k + 1 < len(flights) else n - 1
        # still frames: nearest slow frame, searched only between neighbouring flights
        before = np.where(speed[lo:a + 1] < still_speed)[0]
        s0 = lo + int(before[-1]) if len(before) else lo + int(np.argmin(speed[lo:a + 1]))
        after = np.where(speed[b:hi + 1] < still_speed)[0]
        e0 = b + int(after[0]) if len(after) else b + int(np.argmin(speed[b:hi + 1]))
        dist = float(np.linalg.norm(tr["ankles"][e0, :2] - tr["ankles"][s0, :2]))
        jumps.append(Jump(int(s0), int(a), int(b), int(e0), dist, fps))
    return jumps


def jump_window(jump: Jump, before: float = 0.35, duration: float = 1.3) -> tuple[int, int]:
    """Frame slice [a, b) of ``duration`` seconds starting ``before`` s ahead of takeoff."""
    a = max(0, jump.takeoff - int(round(before * jump.fps)))
    return a, a + int(round(duration * jump.fps)) + 1
