"""A contact node or sample of the stance or the landing (Eq. 3, 34-36).

Inputs r: the contact mode (flat foot, rolling toes: 1 or 0 each; neither: flat toes), the toe
point's ground point x_pin, the landing's sideways shift of the feet y_shift, the rolling toes'
base pitch with its rate and acceleration, and the friction-pyramid edge weights lam (heel, ball,
toe, pad; body weights). The two lateral hip joints close each leg sideways through its planted
foot (:attr:`~latentoc.jump.robot.JumpRobot.closure`), and the base is anchored on the flat foot
or the flat toes (:meth:`~latentoc.jump.robot.JumpRobot.anchored`) or pitched about the toe point
(:attr:`~latentoc.jump.robot.JumpRobot.rolling`), so the loaded points stick by construction.
Rows: the sagittal base rows of RNEA minus sum J^T f (body weights), the joint torques, the
unloaded points' heights (the heel's on the toes, the toe's and pad's on the flat foot), the
centre of pressure on the ground within the loaded support, the ZMP in the support polygon (both
homogeneous in the normal force, smooth as fz -> 0) and the projected COM in it.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ...nlp.blocks import RobotBlock
from ..contact import EDGES, TOE_PAD, point_forces, point_generalized_force, toe_wrench
from ..robot import SAGITTAL_ROWS, JumpRobot, galilean
from ..selection import POLYGON_EDGES
from ..wiring import Rows, Wiring
from ...support_polygon import symbolic_rows
from . import inputs

INPUTS = {"flat": 1, "rolling": 1, "x_pin": 1, "y_shift": 1, "roll": 3, "lam": EDGES}


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
    flat, rolling, x_pin = u["flat"], u["rolling"], u["x_pin"]
    yc, ydc, yddc = robot.closure(y, yd, ydd, flat, u["y_shift"])  # the legs closed sideways through the feet
    foot, toes = robot.anchored("foot")(yc, ydc, yddc, x_pin), robot.anchored("toes")(yc, ydc, yddc, x_pin)
    roll = robot.rolling(yc, ydc, yddc, x_pin, u["roll"][0], u["roll"][1], u["roll"][2])
    b, bd, bdd = (flat * f + rolling * r + (1 - flat - rolling) * t for f, r, t in zip(foot, roll, toes))
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
    parts = {
        "dynamics": (tau - gen)[SAGITTAL_ROWS] / W,
        "torque": robot.torque_rows((tau - gen)[6:]),
        "heel_height": P[2, 0],
        "toes_height": P[2, 2:4].T,
        # the centre of pressure on the ground between the rearmost loaded point and the toe tip
        # (homogeneous in fz, >= 0): behind the toe point (cop_front) or, on the flat foot, the ball
        # (cop_front_ball), and ahead of cop_heel / cop_ball / cop_pad by the schedule
        "cop_front": my,
        "cop_front_ball": my - (toe[0] - P[0, 1]) * fz,
        "cop_heel": (toe[0] - heel[0]) * fz - my,
        "cop_ball": (toe[0] - P[0, 1]) * fz - my,
        "cop_pad": TOE_PAD * fz - my,
        # ZMP x = toe_x - my / fz (y = 0), as fz * rows(ZMP)
        "zmp_polygon": homogeneous_polygon_rows(heel, toe, ca.vertcat(toe[0] * fz - my, 0), fz),
        "com_polygon": symbolic_rows(heel, toe)(robot.sym.com(q)[:2] + ca.vertcat(b[0], 0)),
    }
    return RobotBlock.from_parts("jump_contact", (y, yd, ydd, r), parts, d)


def _rows_at(rows: Rows, w: Wiring, k: int, t: float, torque: np.ndarray, polygon: np.ndarray) -> None:
    """A contact node's or sample's rows: base rows, the unloaded points above the ground and the
    centre of pressure (on the rolling toe point it is that point); the chosen torque rows; the
    chosen ZMP edges in the landing and COM edges once it has settled."""
    robot, ph, s = w.robot, w.phases, w.settings
    kept = robot.unmirrored
    at = np.array([t])
    rows.add(k, "dynamics")
    if ph.flat(at)[0]:
        rows.add(k, "toes_height")
    else:
        rows.add(k, "heel_height")
    if ph.pivot(at)[0]:
        rows.add(k, "toes_height", subset=np.array([1]))  # the pad
    else:
        rows.add(k, "cop_front_ball" if ph.flat(at)[0] else "cop_front")
        rows.add(k, "cop_heel" if ph.loaded("heel", at)[0] else "cop_ball" if ph.loaded("ball", at)[0] else "cop_pad")
    if s.torque_limits and torque.any():
        rows.add(k, "torque", 1.0 / robot.torque_scale[kept[torque]], kept[torque])
    if s.polygon and t >= ph.touchdown - 1e-9:
        zmp, com = polygon[:POLYGON_EDGES], polygon[POLYGON_EDGES:]
        if zmp.any():
            rows.add(k, "zmp_polygon", subset=np.flatnonzero(zmp))
        if com.any() and t >= ph.settle - 1e-9:
            rows.add(k, "com_polygon", subset=np.flatnonzero(com))


def _anchors(w: Wiring, t: np.ndarray, ni) -> None:
    """The contact mode at times t, the toe point's ground point (0 in the stance, the jump
    distance x_L in the landing) and the rolling toes' base pitch."""
    ni.constant(np.column_stack([w.phases.flat(t), w.phases.pivot(t)]).astype(float))
    land = t >= w.phases.touchdown - 1e-12
    ni.variables(np.where(land, w.variables.index("x_L")[0], -1)[:, None])
    ni.variables(np.where(land, w.variables.index("y_L")[0], -1)[:, None])
    w.roll(ni, t)


def wire_nodes(w: Wiring) -> None:
    """The contact nodes: their own edge weights, the anchored base and the chosen rows (none while
    the toes roll)."""
    ts, tl = w.grid["stance"], w.grid["land"]
    tc, var, sel = np.concatenate([ts, tl]), w.variables, w.selection
    ni = w.inputs(len(tc))
    w.latent(ni, tc)
    _anchors(w, tc, ni)
    ni.variables(var.index("lam"))
    rows = Rows(w.blocks["contact"])
    rolling = w.phases.pivot(tc)
    for k, t in enumerate(tc):
        if not rolling[k]:  # the rolling toes are held by the 1 kHz samples (:func:`.nlp.rolling_samples`)
            _rows_at(rows, w, k, t, sel.node_torque[k], sel.node_polygon[k])
    w.add("contact", ni, rows, tc)


def wire_samples(w: Wiring) -> None:
    """The contact samples: the same block with their own edge weights."""
    sel = w.selection
    if not len(sel.contact):
        return
    ni = w.inputs(len(sel.contact))
    w.latent(ni, sel.contact)
    _anchors(w, sel.contact, ni)
    ni.variables(w.variables.index("lam_sample"))
    rows = Rows(w.blocks["contact"])
    for k, t in enumerate(sel.contact):
        _rows_at(rows, w, k, t, sel.contact_torque[k], sel.contact_polygon[k])
    w.add("contact_sample", ni, rows, sel.contact)
