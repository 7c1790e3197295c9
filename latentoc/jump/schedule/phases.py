"""Phase timing of the jump, its contact schedule, the path's knots at its events and the NLP's
nodes and samples on the phases (Sect. 4.2).

Takeoff and touchdown come from the training motion's contact timing, refined to the toe
tip, on the body the stance and the landing plant (:mod:`..closure.planted_legs`):
:func:`latentoc.mocap.jumps.detect_jumps` finds the flight by the feet's height (1.5 cm
above their floor); the toe tip, however, leaves the ground earlier and lands later. Takeoff is
the toe-off, the frame at which the toe tip is lowest in the 0.1 s before the detected takeoff
(after it the tip rises fast, so a toe pinned until the detected takeoff could not take the
captured takeoff velocity); touchdown is the first frame after the detected one at which the toe
tip is back at its standing height. docs/broad-jump.md, "The training jump", prints the times.
The landing is "settled" (Eq. 36's COM-in-polygon constraint applies) from the first
training frame after touchdown at which the projected COM is inside the feet's polygon.
Contact schedule: the heel and the ball carry force only while they are on the ground in the
training motion (within ``CONTACT_HEIGHT`` of their standing height): the heel until
``heel_off`` and again from ``heel_strike``, the ball until ``ball_off`` and from ``ball_strike``;
the toe tip carries force in every contact node. A fixed contact sequence keeps the NLP free of
complementarity rows, whose degenerate multipliers stalled Ipopt (docs/broad-jump-history.md). The latent path has a double
knot at each event that changes the contact model (:meth:`Phases.latent_spline`).
The NLP's times on the phases, in the counts and spacing of :class:`~..settings.JumpSettings`: the
contact and flight nodes (:func:`node_grid`) and the packaged contact and flight samples
(:func:`contact_sample_grid`, :func:`flight_sample_grid`) that phase 2 starts with.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from latentoc.errors import ProblemError
from latentoc.mocap.jumps import detect_jumps
from latentoc.latent.spline import BSpline
from latentoc.jump.robot.feet import POINTS, FootGeometry, foot_points, point_joint
from latentoc.jump.demonstration.training import JumpTraining
from latentoc.jump.settings import JumpSettings

CONTACT_HEIGHT = 0.01  # m above the standing height: a heel or ball higher than this is off the ground


@dataclass(frozen=True)
class Phases:
    """Times in seconds."""

    takeoff: float
    touchdown: float
    settle: float
    duration: float
    heel_off: float | None = None  # contact schedule (module doc); None: no schedule
    ball_off: float | None = None
    ball_strike: float | None = None
    heel_strike: float | None = None
    pad_with_ball: bool = False  # the pad on the ball's body (a rigid sole): loaded with the ball, not alone

    def standing(self, t: np.ndarray | float) -> np.ndarray:
        """Whether times ``t`` are in the stance, the takeoff included."""
        return np.asarray(t, float) <= self.takeoff + 1e-9

    def landed(self, t: np.ndarray | float) -> np.ndarray:
        """Whether times ``t`` are in the landing, the touchdown included."""
        return np.asarray(t, float) >= self.touchdown - 1e-9

    def settled(self, t: np.ndarray | float) -> np.ndarray:
        """Whether times ``t`` are at or after the landing's settle (the COM inside the feet)."""
        return np.asarray(t, float) >= self.settle - 1e-9

    def on_ground(self, t: np.ndarray | float) -> np.ndarray:
        """Whether times ``t`` are in a contact phase (:meth:`standing` or :meth:`landed`)."""
        return self.standing(t) | self.landed(t)

    def flat(self, t: np.ndarray) -> np.ndarray:
        """Whether the foot lies flat (the heel loaded) at contact times ``t``."""
        t = np.asarray(t, float)
        if self.heel_off is None or self.heel_strike is None:
            return np.zeros(t.shape, bool)
        return (t <= self.heel_off + 1e-9) | (t >= self.heel_strike - 1e-9)

    def loaded(self, point: str, t: np.ndarray) -> np.ndarray:
        """Whether ``point`` ("heel", "ball", "toe" or "pad": the toes', or a rigid sole's with the
        ball) may carry force at contact times ``t``."""
        t = np.asarray(t, float)
        if point == "pad" and self.pad_with_ball:  # a rigid sole pivots on its toe tip alone
            point = "ball"
        if point in ("toe", "pad") or self.heel_off is None:
            return np.ones(t.shape, bool)
        off, strike = {"heel": (self.heel_off, self.heel_strike), "ball": (self.ball_off, self.ball_strike)}[point]
        assert off is not None and strike is not None  # the schedule is whole or absent
        return (t <= off + 1e-9) | (t >= strike - 1e-9)

    def held(self, t: np.ndarray) -> np.ndarray:
        """Whether the heel body's hinge holds its standing angle (the foot flat in contact) at times t
        (:mod:`..closure.planted_legs`)."""
        return self.flat(t) & self.on_ground(t)

    def closing(self, t: np.ndarray) -> np.ndarray:
        """Whether contact times ``t`` end the phase before an event (the takeoff, the heel's lift-off):
        the path's derivatives there are the left limits (:meth:`latent_spline`'s double knots)."""
        t = np.asarray(t, float)
        ends = [self.takeoff] + ([self.heel_off] if self.heel_off is not None and self.heel_off in self.events else [])
        return np.isclose(t[..., None], ends, rtol=0.0, atol=1e-12).any(axis=-1)

    @property
    def events(self) -> list[float]:
        """The times at which the contact model changes: the heel's lift-off and strike inside the
        contact phases, the takeoff and the touchdown."""
        ev = [self.takeoff, self.touchdown]
        if self.heel_off is not None and 0.0 < self.heel_off < self.takeoff - 1e-9:
            ev.append(self.heel_off)
        if self.heel_strike is not None and self.touchdown + 1e-9 < self.heel_strike < self.duration:
            ev.append(self.heel_strike)
        return sorted(ev)

    def latent_spline(self, n_control: int) -> BSpline:
        """The path's cubic B-spline with ``n_control`` control points: a double knot at each of the
        :attr:`events` (C1: the accelerations jump as the contact forces switch) and the rest of the
        polynomial pieces spread over the phases by their durations, one at least."""
        ev = self.events
        bounds = np.array([0.0, *ev, self.duration])
        n_pieces = n_control - 3 - len(ev)
        if n_pieces < len(ev) + 1:
            raise ProblemError(f"key 'latent.control_points': {n_control} control points cannot span the jump's "
                               f"{len(ev) + 1} contact phases; it needs at least {2 * len(ev) + 4}")
        share = np.diff(bounds) / self.duration * (n_pieces - len(ev) - 1)
        pieces = 1 + np.floor(share).astype(int)
        for k in np.argsort(share - np.floor(share))[::-1][:n_pieces - int(pieces.sum())]:
            pieces[k] += 1
        return BSpline.phased(self.duration, ev, pieces.tolist(), [2] * len(ev))

    def switch_samples(self, eps: float = 5e-4) -> np.ndarray:
        """Times just inside each unloaded interval of the contact schedule: ``eps`` after the heel
        and ball leave the ground and before they strike it (empty without a schedule)."""
        if self.heel_off is None or self.ball_off is None or self.ball_strike is None or self.heel_strike is None:
            return np.zeros(0)
        t = np.array([self.heel_off + eps, self.ball_off + eps, self.ball_strike - eps, self.heel_strike - eps])
        inside = ((t > 0) & (t < self.takeoff)) | ((t > self.touchdown) & (t < self.duration))
        return t[inside]


# ------------------------------------------------------------------ the NLP's nodes and samples on the phases
def node_grid(settings: JumpSettings, phases: Phases) -> dict[str, np.ndarray]:
    """Contact and flight node times: stance, flight, landing."""
    s, ph = settings, phases
    return {"stance": np.linspace(0.0, ph.takeoff, s.n_stance), "flight": np.linspace(ph.takeoff, ph.touchdown, s.n_flight),
            "land": np.linspace(ph.touchdown, ph.duration, s.n_land)}


def contact_sample_grid(settings: JumpSettings, phases: Phases, rate_hz: float = 1000.0) -> np.ndarray:
    """Contact sample times on the export's 1 kHz grid: every ``sample_spacing``, at the splines'
    breakpoints (their accelerations kink there) and just inside each unloaded interval of the
    contact schedule, in the stance and the landing, none within 1 ms of a contact node."""
    s, ph = settings, phases
    T = ph.duration
    if s.sample_spacing <= 0:
        return np.zeros(0)
    knots = ph.latent_spline(s.n_control).breakpoints
    sw = ph.switch_samples(eps=1.0 / rate_hz)
    t = np.concatenate([np.arange(0.0, T, s.sample_spacing), knots, sw])
    t = np.unique(np.round(t * rate_hz) / rate_hz)
    grid = node_grid(s, ph)
    nodes = np.concatenate([grid["stance"], grid["land"]])
    inside = ((t > 0) & (t < ph.takeoff)) | ((t > ph.touchdown) & (t < T))
    far = np.min(np.abs(t[:, None] - nodes[None, :]), axis=1) > 1.0 / rate_hz - 1e-9
    return t[inside & far]


def flight_sample_grid(settings: JumpSettings, phases: Phases, rate_hz: float = 1000.0) -> np.ndarray:
    """Flight sample times on the export's 1 kHz grid, about every ``sample_spacing`` inside the flight."""
    ph, h = phases, settings.sample_spacing
    if h <= 0:
        return np.zeros(0)
    t = np.unique(np.round(np.arange(ph.takeoff + h / 2, ph.touchdown, h) * rate_hz) / rate_hz)
    return t[(t > ph.takeoff) & (t < ph.touchdown)]


def toe_path(model: pin.Model, Q: np.ndarray, geom: FootGeometry) -> np.ndarray:
    """The left toe tip (x, y, z) in every configuration (n x 3)."""
    d = model.createData()
    out = np.zeros((len(Q), 3))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, d, q)
        out[i] = foot_points(model, d, geom)[:, 2]
    return out


def toe_heights(model: pin.Model, Q: np.ndarray, geom: FootGeometry) -> np.ndarray:
    """Height of the left toe tip in every configuration."""
    return toe_path(model, Q, geom)[:, 2]


def contact_schedule(model: pin.Model, tr: JumpTraining, geom: FootGeometry, takeoff: float,
                     touchdown: float) -> dict[str, float]:
    """Heel and ball contact times of the training motion (module doc): the last stance frame
    before the point first rises ``CONTACT_HEIGHT`` above its standing height, and the first
    landing frame from which it stays below that height for 50 ms."""
    d = model.createData()
    H = np.zeros((len(tr.Q), 3))
    for i, q in enumerate(tr.Q):
        pin.framesForwardKinematics(model, d, q)
        H[i] = foot_points(model, d, geom)[2, :3]
    up = H - H[0] > CONTACT_HEIGHT
    n_hold = max(1, int(round(0.05 / (tr.t[1] - tr.t[0]))))
    out = {}
    for k, name in ((0, "heel"), (1, "ball")):
        first_up = int(np.argmax(up[:, k] & (tr.t <= takeoff + 1e-9)))
        out[f"{name}_off"] = float(min(tr.t[max(first_up - 1, 0)], takeoff)) if up[first_up, k] else takeoff
        strike = touchdown
        for i in np.where(tr.t >= touchdown - 1e-9)[0]:
            if not up[i:i + n_hold, k].any():
                strike = float(tr.t[i])
                break
        out[f"{name}_strike"] = strike
    return out


#: the contact schedule's times in the order they must come (a problem's ``[schedule]`` keys)
SCHEDULE_ORDER = ("heel_off", "ball_off", "takeoff", "touchdown", "ball_strike", "heel_strike")


def training_phases(model: pin.Model, tr: JumpTraining, geom: FootGeometry, schedule: bool = True,
                    declared: Mapping[str, float] | None = None) -> Phases:
    """Phases of a symmetric training jump: toe-off, toe touchdown, settle and, with ``schedule``,
    the heel and ball contact schedule (see module doc); the times in ``declared`` (a problem's
    ``[schedule]``) replace the detected ones, checked in :data:`SCHEDULE_ORDER`."""
    declared = dict(declared or {})
    fps = round(1.0 / float(np.median(np.diff(tr.t))), 6)  # frames per second (the CMU's 120)
    low = [POINTS.index("toe"), POINTS.index("ball")]  # each foot's low points, toe tip first
    feet = tuple(tuple((c.frame, c.offset) for c in (side[k] for k in low)) for side in (geom.points, geom.right_points))
    jumps = detect_jumps(model, tr.Q, fps, feet=feet, ankles=((geom.points[low[1]].frame, None),
                                                              (geom.right_points[low[1]].frame, None)))
    if not jumps:
        raise ProblemError("the training motion has no jump: its feet never leave the ground together "
                           "(8 cm up for 80 ms); key 'robot.motion'")
    j = jumps[0]
    z = toe_heights(model, tr.Q, geom)
    lo = max(0, j.takeoff - int(round(0.1 * fps)))
    i_off = lo + int(np.argmin(z[lo:j.takeoff + 1]))
    down = np.where(z[j.touchdown:] <= z[0])[0]
    i_td = j.touchdown + int(down[0]) if len(down) else j.touchdown
    takeoff = float(declared.get("takeoff", tr.t[i_off]))
    touchdown = float(declared.get("touchdown", tr.t[i_td]))
    i_td = int(np.searchsorted(tr.t, touchdown - 1e-9))
    d = model.createData()
    settle = None
    for i in range(i_td, len(tr.Q)):
        pin.framesForwardKinematics(model, d, tr.Q[i])
        c = pin.centerOfMass(model, d, tr.Q[i])
        heel, _, toe, _ = foot_points(model, d, geom)[0]
        if heel <= c[0] <= toe:
            settle = tr.t[i]
            break
    if settle is None:
        settle = tr.t[-1]
    sched = contact_schedule(model, tr, geom, takeoff, touchdown) if schedule else {}
    sched.update({k: float(v) for k, v in declared.items() if k in sched})
    rigid = point_joint(model, geom, "pad") == point_joint(model, geom, "ball")
    ph = Phases(takeoff, touchdown, float(max(settle, touchdown)), tr.duration, **sched, pad_with_ball=rigid)
    _check_order(ph, declared)
    return ph


def _check_order(ph: Phases, declared: Mapping[str, float]) -> None:
    """A ProblemError naming the first declared time out of :data:`SCHEDULE_ORDER` or outside the motion."""
    times = [(k, getattr(ph, k)) for k in SCHEDULE_ORDER if getattr(ph, k) is not None]
    for (a, ta), (b, tb) in zip(times, times[1:]):
        if ta > tb + 1e-12 or (a, b) == ("takeoff", "touchdown") and ta >= tb:
            key = b if b in declared else a
            raise ProblemError(f"key 'schedule.{key}': the contact schedule must run {' <= '.join(SCHEDULE_ORDER)} "
                               f"(takeoff < touchdown); {a} is {ta:.4f} s and {b} {tb:.4f} s")
    for k, v in declared.items():
        if not 0.0 < v < ph.duration:
            raise ProblemError(f"key 'schedule.{k}': {v} s is outside the training motion (0 to {ph.duration:.4f} s)")
