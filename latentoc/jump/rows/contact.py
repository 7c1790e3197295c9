"""A contact node or sample of the stance or the landing (Eq. 3, 34-36).

Inputs r: the planted body's shift along x from its standing pose (0 in the stance, the jump in
the landing), whether the heel body's hinge is held (:mod:`..closure.planted_legs`), and the friction-pyramid
edge weights lam (heel, ball, toe, pad; body weights). The legs are closed and the base follows from
the planted body (:meth:`~..robot.jump_robot.JumpRobot.planted`), so the loaded points stay on the ground by
construction. Rows: the sagittal base rows of RNEA minus sum J^T f (body weights), the joint
torques, the points' heights (an unloaded one above the ground), the centre of pressure on the
ground within the loaded support, the ZMP in the support polygon (both homogeneous in the normal
force, smooth as fz -> 0) and the projected COM in it.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from latentoc.nlp.blocks import RobotBlock
from latentoc.jump.robot.feet import EDGES, POINTS, point_forces, point_generalized_force, toe_wrench
from latentoc.jump.robot.jump_robot import SAGITTAL_ROWS, JumpRobot, galilean
from latentoc.jump.transcription.selection import POLYGON_EDGES
from latentoc.jump.transcription.wiring import Rows, Wiring
from latentoc.jump.robot.support_polygon import symbolic_rows
from latentoc.jump.rows import inputs

INPUTS = {"shift": 1, "held": 1, "lam": EDGES}


def homogeneous_polygon_rows(heel, toe, p_scaled, s):
    """s * rows(p_scaled / s) of the feet's support polygon, without the division."""
    V = [(heel[0], -heel[1]), (toe[0], -toe[1]), (toe[0], toe[1]), (heel[0], heel[1])]
    out = []
    for i in range(4):
        (x0, y0), (x1, y1) = V[i], V[(i + 1) % 4]
        ex, ey = x1 - x0, y1 - y0
        out.append(-(ex * (p_scaled[1] - y0 * s) - ey * (p_scaled[0] - x0 * s)) / ca.sqrt(ex * ex + ey * ey))
    return ca.vertcat(*out)


def block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, INPUTS)
    W = robot.weight
    (yc, ydc, yddc), (b, bd, bdd) = robot.planted(y, yd, ydd, u["held"], u["shift"])
    b0, bd0 = galilean(b, bd)
    q, v, a = robot.configuration(b0, bd0, bdd, yc, ydc, yddc)
    tau = robot.sym.rnea(q, v, a)
    lam = u["lam"]
    gen = point_generalized_force(robot.sym, robot.geom, q, point_forces(lam * W, robot.mu))
    P = robot.points(q, b[:2])
    w = toe_wrench(lam, P, robot.mu)  # body weights, moment about the toe tip
    fx, fz = w[0], w[2]
    my = w[4] + P[2, 2] * fx  # about the ground point below the toe tip: CoP x = toe_x - my / fz
    heel, toe = P[:2, 0], P[:2, 2]
    fp = robot.geom.footprint
    assert fp is not None, "the contact rows need the standing footprint (FootGeometry.from_standing)"
    parts = {
        "dynamics": (tau - gen)[SAGITTAL_ROWS] / W,
        "torque": robot.torque_rows((tau - gen)[6:]),
        # heel, ball, toe and pad above their standing heights (the toe tip stands ~1 mm above the others)
        "height": ca.vertcat(*[P[2, k] - float(fp[2, k]) for k in range(len(POINTS))]),
        # the centre of pressure on the ground between the rearmost loaded point and the toe tip
        # (homogeneous in fz, >= 0): cop_front, and cop_heel / cop_ball / cop_pad by the schedule
        "cop_front": my,
        "cop_heel": (toe[0] - heel[0]) * fz - my,
        "cop_ball": (toe[0] - P[0, 1]) * fz - my,
        "cop_pad": robot.geom.pad_setback * fz - my,
        # ZMP x = toe_x - my / fz (y = 0), as fz * rows(ZMP)
        "zmp_polygon": homogeneous_polygon_rows(heel, toe, ca.vertcat(toe[0] * fz - my, 0), fz),
        "com_polygon": symbolic_rows(heel, toe)(robot.sym.com(q)[:2] + ca.vertcat(b[0], 0)),
    }
    return RobotBlock.from_parts("jump_contact", (y, yd, ydd, r), parts, d)


def _rows_at(rows: Rows, w: Wiring, k: int, t: float, torque: np.ndarray, polygon: np.ndarray) -> None:
    """A contact node's or sample's rows: base rows and centre of pressure always; the chosen torque
    rows; the chosen ZMP edges in the landing and COM edges once it has settled."""
    robot, ph = w.robot, w.phases
    kept = robot.unmirrored
    at = np.array([t])
    rows.add(k, "dynamics")
    rows.add(k, "cop_front")
    rows.add(k, "cop_heel" if ph.loaded("heel", at)[0] else "cop_ball" if ph.loaded("ball", at)[0] else "cop_pad")
    if torque.any():
        rows.add(k, "torque", 1.0 / robot.torque_scale[kept[torque]], kept[torque])
    if ph.landed(t):
        zmp, com = polygon[:POLYGON_EDGES], polygon[POLYGON_EDGES:]
        if zmp.any():
            rows.add(k, "zmp_polygon", subset=np.flatnonzero(zmp))
        if com.any() and ph.settled(t):
            rows.add(k, "com_polygon", subset=np.flatnonzero(com))


def _clearance_at(rows: Rows, w: Wiring, k: int, t: float) -> None:
    """The unloaded points' heights (above the ground: :func:`latentoc.jump.transcription.nlp.build_nlp`'s bounds)."""
    at = np.array([t])
    unloaded = [i for i, p in enumerate(POINTS) if not w.phases.loaded(p, at)[0]]
    if unloaded:
        rows.add(k, "height", subset=np.array(unloaded))


def _planted_inputs(w: Wiring, ni, t: np.ndarray) -> None:
    """The planted body's shift (0 in the stance, the landing's x_L less the standing toe tip's x) and
    whether the hinge is held, at contact times t."""
    land = w.phases.landed(t)
    x0 = w.robot.geom.toe_x
    ni.variables(np.where(land, w.variables.index("x_L")[0], -1).astype(np.int64)[:, None], np.where(land, -x0, 0.0)[:, None])
    ni.constant(w.phases.held(t).astype(float)[:, None])


def wire_nodes(w: Wiring) -> None:
    """The contact nodes: their own edge weights, the planted body's ground pose (the stance's, or the
    landing's at the jump distance x_L), the unloaded points' heights and the chosen rows."""
    ts, tl = w.grid["stance"], w.grid["land"]
    tc, var, sel = np.concatenate([ts, tl]), w.variables, w.selection
    ni = w.inputs(len(tc))
    w.latent(ni, tc)
    _planted_inputs(w, ni, tc)
    ni.variables(var.index("lam"))
    rows = Rows(w.blocks["contact"])
    for k, t in enumerate(tc):
        _rows_at(rows, w, k, t, sel.node_torque[k], sel.node_polygon[k])
        _clearance_at(rows, w, k, t)
    w.add("contact", ni, rows, tc)


def wire_samples(w: Wiring) -> None:
    """The contact samples: the same block with their own edge weights and the unloaded points' heights."""
    sel = w.selection
    if not len(sel.contact):
        return
    ni = w.inputs(len(sel.contact))
    w.latent(ni, sel.contact)
    _planted_inputs(w, ni, sel.contact)
    ni.variables(w.variables.index("lam_sample"))
    rows = Rows(w.blocks["contact"])
    for k, t in enumerate(sel.contact):
        _rows_at(rows, w, k, t, sel.contact_torque[k], sel.contact_polygon[k])
        _clearance_at(rows, w, k, t)
    w.add("contact_sample", ni, rows, sel.contact)
