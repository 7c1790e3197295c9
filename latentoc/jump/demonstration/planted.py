"""The training jump with its feet planted, before the GPDM learns it.

The captured toes move by about a centimetre in stance (and 3 cm sideways), and the toe tip sinks
1.4 cm into the floor at the push-off, so a model that learns the capture learns feet that slide.
The contact model of the NLP (:mod:`..robot.feet`, :class:`..schedule.phases.Phases`) holds the toes flat on
their ground points, and the foot flat while the heel is loaded; :func:`planted_training` makes
the demonstration obey the same: the left toes body sits at its standing placement through the
stance (at the standing orientation over the captured landing point through the landing), so the
foot rises about the toe joint while the toes stay flat, as a foot's toes do at push-off, and
while the heel is loaded the toe joint holds its standing angle, approached smoothly over
``TOE_RAMP``. (Toes rolling on their tip alone, as captured, leave a point contact that holds no
moment: docs/broad-jump.md.) Only the left leg's seven joints change (the right is their mirror) and,
where the leg cannot reach, the sagittal base; each frame changes them least (:func:`latentoc.motions.planting.plant`);
the correction fades out over ``TAPER`` into the flight.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from latentoc.mocap.symmetry import SymmetryMap
from latentoc.motions.planting import Plant, plant, taper
from latentoc.jump.robot.sagittal_base import base_to_freeflyer, freeflyer_to_base
from latentoc.jump.robot.feet import POINTS, FootGeometry, point_joint
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.demonstration.training import JumpTraining

__all__ = ["PlantedTraining", "foot_bodies", "leg_joints", "learned_leg", "planted_training", "plantable"]

TAPER = 0.05  # s over which the correction fades into the flight
TOE_RAMP = 0.05  # s over which the toe joint is brought to its standing angle before the heel loads
SAGITTAL_BASE_V = (0, 2, 4)  # the base's x, z and pitch velocity coordinates
BASE_WEIGHTS = np.array([10.0, 10.0, 3.0])  # a base change of 1 cm weighs as 0.1 rad of a joint, 1 deg of pitch as 3


@dataclass
class PlantedTraining:
    """The planted training jump and what planting changed."""

    training: JumpTraining
    change_deg: dict[str, float]  # largest |change| per leg joint, degrees
    rms_change_deg: dict[str, float]  # root mean square over the frames, degrees
    landing_shift: np.ndarray  # the landing's planted toes frame less the standing one (x, y, z), m
    base_change: np.ndarray  # largest |change| of the base's x, z (m) and pitch (rad)


def leg_joints(model: pin.Model, anchor: str) -> tuple[str, ...]:
    """The 1-DOF joints between the base and the body frame ``anchor`` (the leg that carries it),
    base to foot: for the CMU humanoid's toes the hip's three, the knee, the ankle's two and the toe."""
    j = model.frames[model.getFrameId(anchor)].parentJoint
    return tuple(model.names[k] for k in model.supports[j] if k > 0 and model.joints[k].nq == 1)


def anchor_point(model: pin.Model, anchor_id: int, frame: str, offset: np.ndarray) -> np.ndarray:
    """The point ``offset`` of frame ``frame`` in the coordinates of the frame ``anchor_id`` on the same body."""
    a, f = model.frames[anchor_id].placement, model.frames[model.getFrameId(frame)].placement
    return a.actInv(f.act(offset))


def _ramped(theta: np.ndarray, target: float, held: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The toe angle brought smoothly to ``target`` where it is ``held`` (cosine ramp before and after)."""
    delta = np.where(held, target - theta, 0.0)
    return theta + taper(delta[:, None], held, t, TOE_RAMP)[:, 0]


def plantable(phases: Phases) -> bool:
    """Whether a captured jump's contact schedule is whole: the heel leaves the ground after the start,
    the ball after it and no later than the takeoff, and both strike back after the touchdown (a
    capture cut in mid-motion has none of that, and its feet cannot be planted)."""
    ph = phases
    if ph.heel_off is None or ph.ball_off is None or ph.ball_strike is None or ph.heel_strike is None:
        return False
    return 0.0 < ph.heel_off <= ph.ball_off <= ph.takeoff < ph.touchdown <= ph.ball_strike <= ph.heel_strike < ph.duration


def foot_bodies(model: pin.Model, geom: FootGeometry) -> tuple[str, str | None]:
    """The body the planting holds (the toe tip's: the CMU's toes, a rigid sole's foot) and the hinge
    between it and the heel's body (the CMU's toe joint; None for a rigid sole)."""
    jt = point_joint(model, geom, "toe")
    anchor = next(f.name for f in model.frames if f.parentJoint == jt and f.type == pin.FrameType.BODY)
    return anchor, (model.names[jt] if point_joint(model, geom, "heel") != jt else None)


def learned_leg(model: pin.Model, smap: SymmetryMap, geom: FootGeometry) -> list[int]:
    """Positions in the learned coordinates of the left leg's joints (:func:`leg_joints` of the planted body)."""
    return [smap.learned_names.index(n) for n in leg_joints(model, foot_bodies(model, geom)[0])]


def planted_training(model: pin.Model, smap: SymmetryMap, tr: JumpTraining, phases: Phases,
                     geom: FootGeometry) -> PlantedTraining:
    """The training jump ``tr`` with its feet planted (module doc); ``geom``: the feet's points."""
    t, Q = tr.t, tr.Q
    stance, landing = phases.standing(t), phases.landed(t)
    anchor, hinge = foot_bodies(model, geom)
    d = model.createData()
    fid = model.getFrameId(anchor)
    pin.framesForwardKinematics(model, d, Q[0])
    standing = d.oMf[fid].copy()
    landed = np.zeros((int(landing.sum()), 3))
    for k, i in enumerate(np.flatnonzero(landing)):
        pin.framesForwardKinematics(model, d, Q[i])
        landed[k] = d.oMf[fid].translation
    point = np.median(landed[:, :2], axis=0)
    # over the captured landing point, at the standing width and heading (the NLP's feet keep them)
    on_ground = pin.SE3(standing.rotation, np.array([point[0], standing.translation[1], standing.translation[2]]))
    leg = leg_joints(model, anchor)
    legs_v = [model.joints[model.getJointId(n)].idx_v for n in leg]
    free_v = np.array(list(SAGITTAL_BASE_V) + legs_v)
    weights = np.concatenate([BASE_WEIGHTS, np.ones(len(legs_v))])
    flat = phases.flat(t) & (stance | landing)
    contact = stance | landing
    if hinge is None:  # a rigid sole: flat while the heel is loaded, then pivoting on its toe tip
        toe = geom.points[POINTS.index("toe")]
        tip = np.zeros(3) if toe.offset is None else np.asarray(toe.offset, float)
        on_tip = anchor_point(model, fid, toe.frame, tip)
        plants = [Plant(anchor, standing, stance & flat), Plant(anchor, on_ground, landing & flat),
                  Plant(anchor, pin.SE3(np.eye(3), standing.act(on_tip)), stance & ~flat, point=on_tip),
                  Plant(anchor, pin.SE3(np.eye(3), on_ground.act(on_tip)), landing & ~flat, point=on_tip)]
        Qp = plant(model, Q, free_v, plants, None, weights)
    else:
        jid = model.getJointId(hinge)
        iq, iv = model.joints[jid].idx_q, model.joints[jid].idx_v
        theta = _ramped(Q[:, iq], float(Q[0, iq]), flat, t)
        held = contact & (np.abs(t[:, None] - t[flat][None, :]).min(axis=1) < TOE_RAMP)
        plants = [Plant(anchor, standing, stance), Plant(anchor, on_ground, landing)]
        Qp = plant(model, Q, free_v, plants, {iv: (theta, held)}, weights)
    Y0, legs = tr.Y, [smap.learned_names.index(n) for n in leg]
    dY = np.zeros_like(Y0)
    dY[:, legs] = smap.to_learned(Qp)[:, legs] - Y0[:, legs]
    dY = taper(dY, contact, t, TAPER)
    db = taper(np.where(contact[:, None], freeflyer_to_base(Qp[:, :7]) - tr.base, 0.0), contact, t, TAPER)
    Y, base = Y0 + dY, tr.base + db
    Qs = smap.to_full(Y, base_to_freeflyer(base)[0])
    change = {n: float(np.degrees(np.max(np.abs(dY[:, k])))) for n, k in zip(leg, legs)}
    rms = {n: float(np.degrees(np.sqrt(np.mean(dY[:, k] ** 2)))) for n, k in zip(leg, legs)}
    base_change = np.max(np.abs(db), axis=0)
    return PlantedTraining(JumpTraining(t, Y, base, Qs), change, rms, on_ground.translation - standing.translation,
                           base_change)
