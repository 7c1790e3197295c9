"""The broad jump's row families, one per module, each a robot block (:mod:`latentoc.nlp.blocks`):
a Function of the joint motion (y, yd, ydd) and the node's other inputs r, never of the GPDM.

* :mod:`.contact` - a contact node or sample: base rows = sum J^T f, torques, clearance, CoP, ZMP, COM;
* :mod:`.flight` - the flight's inverse dynamics (at any time), foot clearance and pitch rate;
* :mod:`.transitions` - the takeoff state, the touchdown at rest and the hinge's switches;
* :mod:`.tube_rows` - the tube (Eq. 29), from the GP layer alone;
* :mod:`.joint_limits` - the robot's joint position and velocity limits (none for the CMU humanoid).

Each module names its blocks' inputs r (sizes, in order), builds them for latent dimension d and
wires its families (:mod:`latentoc.jump.transcription.wiring`): their nodes, inputs and rows; :func:`families`
lists them in the NLP's order.
"""
from __future__ import annotations

from dataclasses import replace

import casadi as ca

from latentoc.nlp.blocks import RobotBlock, block_inputs
from latentoc.jump.robot.jump_robot import JumpRobot

__all__ = ["inputs", "row_blocks", "families"]


def inputs(robot: JumpRobot, spec: dict[str, int]) -> tuple[tuple[ca.SX, ca.SX, ca.SX, ca.SX], dict[str, ca.SX]]:
    """Block symbols (y, yd, ydd, r) and r split by name as ``spec`` orders it."""
    sym = block_inputs(robot.n_learned, sum(spec.values()))
    r, parts, off = sym[3], {}, 0
    for name, n in spec.items():
        parts[name] = r[off:off + n]
        off += n
    return sym, parts


def row_blocks(robot: JumpRobot, d: int, joint_space: bool = False) -> dict[str, RobotBlock]:
    """Every row family's block for latent dimension d; ``joint_space``: for the joint path itself
    (the identity layer, d = 37), whose tangents are constant (:attr:`RobotBlock.identity`)."""
    from latentoc.jump.rows import contact, flight, joint_limits, transitions

    blocks = {"contact": contact.block(robot, d), "flight_dynamics": flight.dynamics_block(robot, d),
              "flight_clearance": flight.clearance_block(robot, d), "pitch_rate": flight.pitch_rate_block(robot, d),
              "takeoff": transitions.takeoff_block(robot, d), "touchdown": transitions.touchdown_block(robot, d)}
    if robot.closure is not None and robot.closure.hinge is not None:
        blocks["hinge"] = transitions.hinge_block(robot, d)
    if robot.has_joint_limits:
        blocks["joint_limits"] = joint_limits.block(robot, d)
    return {k: replace(b, identity=True) for k, b in blocks.items()} if joint_space else blocks


def families() -> tuple:
    """The wiring functions of the NLP's families, in the order of its rows."""
    from latentoc.jump.rows import contact, flight, joint_limits, transitions, tube_rows

    return (contact.wire_nodes, contact.wire_samples, transitions.wire_takeoff, flight.wire_pitch,
            flight.wire_samples, flight.wire_clearance, transitions.wire_touchdown, transitions.wire_hinge, tube_rows.wire,
            joint_limits.wire)
