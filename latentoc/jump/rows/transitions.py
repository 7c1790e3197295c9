"""The phase transitions: takeoff (the flight's state from the stance) and touchdown (Eq. 4-5).

Takeoff inputs r: the stance base (b, bd) and the flight variables (c_to, cd_to, L, p); rows:
the flight variables equal the stance's COM, COM velocity, angular momentum and pitch.

Touchdown inputs r: the landing base (b, bd), the flight's pitch p and momentum L, its takeoff
COM state, the flight time and the impulse's edge weights (0.1 s of body weight). Rows: the
flight's base pose meets the landing's, and the perfectly inelastic impact
``M_bb (v+ - v-) = (sum J^T Pi)_base``: the feet stop, the joints keep their velocities.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from ...nlp.blocks import RobotBlock
from ..base import base_function
from ..contact import EDGES, point_forces, point_generalized_force
from ..flight import flight_functions
from ..robot import SAGITTAL_ROWS, JumpRobot
from ..wiring import Rows, Wiring
from . import inputs
from .flight import ballistic_com, flight_base

TAKEOFF_INPUTS = {"b": 3, "bd": 3, "c_to": 2, "cd_to": 2, "L": 1, "p": 1}
TOUCHDOWN_INPUTS = {"b": 3, "bd": 3, "p": 1, "L": 1, "c_to": 2, "cd_to": 2, "t": 1, "impulse": EDGES}


def takeoff_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, TAKEOFF_INPUTS)
    b, bd = u["b"], u["bd"]
    c, cd, L = flight_functions(robot.sym, robot.smap)["momentum"](y, yd, b, bd)
    rows = ca.vertcat(c - u["c_to"], cd - u["cd_to"], L - u["L"], b[2] - u["p"])
    return RobotBlock.from_parts("jump_takeoff", (y, yd, ydd, r), {"takeoff": rows}, d, hot=False)


def touchdown_block(robot: JumpRobot, d: int) -> RobotBlock:
    (y, yd, ydd, r), u = inputs(robot, TOUCHDOWN_INPUTS)
    W = robot.weight
    bm, bdm, _ = flight_base(robot, y, yd, ydd, u["p"], u["L"], *ballistic_com(u["c_to"], u["cd_to"], u["t"]))
    bp, bdp = u["b"], u["bd"]
    z3 = ca.DM.zeros(3)
    E = ca.DM(robot.E)
    q = ca.vertcat(base_function()(bp, z3, z3)[0], E @ y)
    v_minus = base_function()(bp, bdm, z3)[1]
    v_plus = base_function()(bp, bdp, z3)[1]
    Mbb = robot.sym.mass_matrix(q)[:6, :6]
    gen = point_generalized_force(robot.sym, robot.geom, q, point_forces(u["impulse"] * W * 0.1, robot.mu))
    impact = Mbb @ (v_plus - v_minus) - gen[:6]
    return RobotBlock.from_parts("jump_touchdown", (y, yd, ydd, r),
                                 {"touchdown_position": bm - bp, "impact": impact[SAGITTAL_ROWS] / W}, d, hot=False)


def wire_takeoff(w: Wiring) -> None:
    """The takeoff: the flight's state variables are the stance's at takeoff."""
    var, t = w.variables, np.array([w.phases.takeoff])
    ni = w.inputs(1)
    w.latent(ni, t)
    w.base(ni, t, orders=2)
    ni.variables(np.concatenate([var.index("c_to"), var.index("cd_to"), var.index("L_to"),
                                 var.index("pitch_flight")[:1]])[None, :])
    rows = Rows(w.blocks["takeoff"])
    rows.add(0, "takeoff")
    w.add("takeoff", ni, rows, t)


def wire_touchdown(w: Wiring) -> None:
    """The touchdown: the flight's base meets the landing's; the inelastic impact."""
    var, ph = w.variables, w.phases
    t = np.array([ph.touchdown])
    ni = w.inputs(1)
    w.latent(ni, t)
    w.base(ni, t, orders=2)
    ni.variables(np.concatenate([var.index("pitch_flight")[-1:], var.index("L_to"), var.index("c_to"),
                                 var.index("cd_to")])[None, :])
    ni.constant(np.array([[ph.touchdown - ph.takeoff]]))
    ni.variables(var.index("lam_impact")[None, :])
    rows = Rows(w.blocks["touchdown"])
    rows.add(0, "touchdown_position")
    rows.add(0, "impact")
    w.add("touchdown", ni, rows, t)
