"""A contact node or sample of the stance or the landing (Eq. 3, 34-36).

Inputs r: the base (b, bd, bdd) of the contact phase's own (x, z, pitch) spline, the toe tip's
ground point x_pin, and the friction-pyramid edge weights lam (heel, ball, toe, pad; body weights).
Rows: the sagittal base rows of RNEA minus sum J^T f (body weights), the joint torques, where
the foot is (:func:`_placement_at`: the toe tip on its ground point, the heel, ball and pad heights,
the loaded points' sideways offsets), the centre of pressure on
the ground within the loaded support, the ZMP in the support polygon (both homogeneous in the
normal force, smooth as fz -> 0) and the projected COM in it.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ...nlp.blocks import RobotBlock
from ..contact import EDGES, point_forces, point_generalized_force, toe_wrench
from ..robot import SAGITTAL_ROWS, JumpRobot, galilean
from ..selection import POLYGON_EDGES
from ..wiring import Rows, Wiring
from ...support_polygon import symbolic_rows
from . import inputs

INPUTS = {"b": 3, "bd": 3, "bdd": 3, "x_pin": 1, "lam": EDGES}


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
    b0, bd0 = galilean(u["b"], u["bd"])
    q, v, a = robot.configuration(b0, bd0, u["bdd"], y, yd, ydd)
    tau = robot.sym.rnea(q, v, a)
    lam = u["lam"]
    gen = point_generalized_force(robot.sym, robot.geom, q, point_forces(lam * W, robot.mu))
    P = robot.points(q, u["b"][:2])
    w = toe_wrench(lam, P, robot.mu)  # body weights, moment about the toe tip
    fx, fz = w[0], w[2]
    my = w[4] + P[2, 2] * fx  # about the ground point below the toe tip: CoP x = toe_x - my / fz
    heel, toe = P[:2, 0], P[:2, 2]
    fp = robot.geom.footprint
    assert fp is not None, "the contact rows need the standing footprint (FootGeometry.from_standing)"
    parts = {
        "dynamics": (tau - gen)[SAGITTAL_ROWS] / W,
        "torque": robot.torque_rows((tau - gen)[6:]),
        # heights above each point's standing height (the toe tip stands ~1 mm above the others)
        "ball_height": P[2, 1] - float(fp[2, 1]),
        "toe_position": ca.vertcat(P[0, 2] - u["x_pin"], P[2, 2] - float(fp[2, 2])),
        "heel_height": P[2, 0] - float(fp[2, 0]),
        "pad_height": P[2, 3] - float(fp[2, 3]),
        "point_y": ca.vertcat(*[P[1, k] - float(fp[1, k]) for k in range(4)]),  # heel, ball, toe, pad sideways
        # the centre of pressure on the ground between the rearmost loaded point and the toe tip
        # (homogeneous in fz, >= 0): cop_front, and cop_heel / cop_ball / cop_pad by the schedule
        "cop_front": my,
        "cop_heel": (toe[0] - heel[0]) * fz - my,
        "cop_ball": (toe[0] - P[0, 1]) * fz - my,
        "cop_pad": robot.geom.pad_setback * fz - my,
        # ZMP x = toe_x - my / fz (y = 0), as fz * rows(ZMP)
        "zmp_polygon": homogeneous_polygon_rows(heel, toe, ca.vertcat(toe[0] * fz - my, 0), fz),
        "com_polygon": symbolic_rows(heel, toe)(robot.sym.com(q)[:2] + ca.vertcat(u["b"][0], 0)),
    }
    return RobotBlock.from_parts("jump_contact", (y, yd, ydd, r), parts, d)


def _rows_at(rows: Rows, w: Wiring, k: int, t: float, torque: np.ndarray, polygon: np.ndarray) -> None:
    """A contact node's or sample's rows: base rows and centre of pressure always; the chosen torque
    rows; the chosen ZMP edges in the landing and COM edges once it has settled."""
    robot, ph, s = w.robot, w.phases, w.settings
    kept = robot.unmirrored
    at = np.array([t])
    rows.add(k, "dynamics")
    rows.add(k, "cop_front")
    rows.add(k, "cop_heel" if ph.loaded("heel", at)[0] else "cop_ball" if ph.loaded("ball", at)[0] else "cop_pad")
    if s.torque_limits and torque.any():
        rows.add(k, "torque", 1.0 / robot.torque_scale[kept[torque]], kept[torque])
    if s.polygon and t >= ph.touchdown - 1e-9:
        zmp, com = polygon[:POLYGON_EDGES], polygon[POLYGON_EDGES:]
        if zmp.any():
            rows.add(k, "zmp_polygon", subset=np.flatnonzero(zmp))
        if com.any() and t >= ph.settle - 1e-9:
            rows.add(k, "com_polygon", subset=np.flatnonzero(com))


def _placement_at(rows: Rows, w: Wiring, k: int, t: float) -> None:
    """Where the foot is: the toe tip on its ground point (x, z), the heel and ball heights (bounds
    by the schedule). With ``sticking`` one row more per degree of freedom the loaded points hold
    (none redundant): while the ball is off the ground the pad's height (the toes lie flat on tip
    and pad); the toe tip's and the rearmost loaded point's sideways offsets (the foot's or the toes'
    yaw)."""
    on = {p: bool(w.phases.loaded(p, np.array([t]))[0]) for p in ("heel", "ball", "pad")}
    for part in ("ball_height", "toe_position", "heel_height"):
        rows.add(k, part)
    if not w.settings.sticking:
        return
    if not on["ball"]:
        rows.add(k, "pad_height")
    rear = next((i for i, p in ((0, "heel"), (1, "ball"), (3, "pad")) if on[p]), None)
    rows.add(k, "point_y", subset=np.array([2] + ([rear] if rear is not None else [])))


def wire_nodes(w: Wiring) -> None:
    """The contact nodes: their own edge weights, the toe tip's ground point (the stance's at 0, the
    landing's the jump distance x_L), the feet's placement and the chosen rows."""
    ts, tl = w.grid["stance"], w.grid["land"]
    tc, var, sel = np.concatenate([ts, tl]), w.variables, w.selection
    ni = w.inputs(len(tc))
    w.latent(ni, tc)
    w.base(ni, tc)
    ni.variables(np.concatenate([-np.ones(len(ts), np.int64), np.full(len(tl), var.index("x_L")[0])])[:, None])
    ni.variables(var.index("lam"))
    rows = Rows(w.blocks["contact"])
    for k, t in enumerate(tc):
        _rows_at(rows, w, k, t, sel.node_torque[k], sel.node_polygon[k])
        _placement_at(rows, w, k, t)
    w.add("contact", ni, rows, tc)


def wire_samples(w: Wiring) -> None:
    """The contact samples: the same block with their own edge weights; with ``sticking`` the nodes'
    foot placement (the feet held between the nodes)."""
    sel = w.selection
    if not len(sel.contact):
        return
    ni = w.inputs(len(sel.contact))
    w.latent(ni, sel.contact)
    w.base(ni, sel.contact)
    land = sel.contact >= w.phases.touchdown - 1e-9  # the toe tip's ground point: 0, or x_L in the landing
    ni.variables(np.where(land, w.variables.index("x_L")[0], -1).astype(np.int64)[:, None])
    ni.variables(w.variables.index("lam_sample"))
    rows = Rows(w.blocks["contact"])
    for k, t in enumerate(sel.contact):
        _rows_at(rows, w, k, t, sel.contact_torque[k], sel.contact_polygon[k])
        if w.settings.sticking:  # the feet held between the nodes too
            _placement_at(rows, w, k, t)
    w.add("contact_sample", ni, rows, sel.contact)
