"""How a row family's nodes see the decision vector, and what its rows are: the pieces each row
module (:mod:`..rows`) wires its block with.

A :class:`Wiring` holds what every family needs (the robot, the GP or identity layer, the blocks, the phases,
the settings, the selection, the variables and the path's spline); :class:`Rows` picks a block's outputs at
its nodes as constraint rows, each with a name, a time and a component (the joint among the kept
ones, the polygon edge, or the output's index), the row's identity across NLPs
(:mod:`..solve.warm`). :meth:`Wiring.add` turns them into a :class:`~latentoc.nlp.assemble.Family`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from latentoc.latent.gp_layer import Layer
from latentoc.nlp.assemble import Family
from latentoc.nlp.blocks import RobotBlock
from latentoc.nlp.evaluators import BlockEvaluator
from latentoc.nlp.inputs import NodeInputs
from latentoc.latent.spline import BSpline
from latentoc.jump.schedule.phases import Phases
from latentoc.jump.robot.jump_robot import JumpRobot
from latentoc.jump.transcription.selection import Selection
from latentoc.jump.settings import JumpSettings
from latentoc.jump.transcription.variables import JumpVariables

__all__ = ["Rows", "Wiring"]


class Rows:
    """Row selection of one family: (node, output, scale) entries with each row's name and component."""

    def __init__(self, block: RobotBlock):
        self.block = block
        self.entries: list[tuple[int, float]] = []
        self.names: list[str] = []
        self.nodes: list[int] = []
        self.comps: list[int] = []

    def add(self, k: int, part: str, scale: np.ndarray | float = 1.0, subset: np.ndarray | None = None) -> None:
        """Output ``part`` of node k (its ``subset`` of components), times ``scale``."""
        s = self.block.layout[part]
        local = np.arange(s.stop - s.start) if subset is None else np.asarray(subset, int)
        scale = np.broadcast_to(np.asarray(scale, float), local.shape)
        for o, c in zip(s.start + local, scale):
            self.entries.append((k * self.block.n_out + o, float(c)))
        self.names.extend([part] * len(local))
        self.nodes.extend([k] * len(local))
        self.comps.extend(local.tolist())

    def matrix(self, K: int) -> sp.csr_matrix:
        cols = np.array([e[0] for e in self.entries], np.int64)
        vals = np.array([e[1] for e in self.entries], float)
        return sp.csr_matrix((vals, (np.arange(len(cols)), cols)), shape=(len(cols), K * self.block.n_out))


@dataclass
class Wiring:
    """What the row modules wire their families with, and the families they add (module doc)."""

    robot: JumpRobot
    layer: Layer
    blocks: dict[str, RobotBlock]
    phases: Phases
    settings: JumpSettings
    selection: Selection
    variables: JumpVariables
    spline: BSpline  # the latent (or joint) path's
    P_fixed: np.ndarray
    grid: dict[str, np.ndarray]
    families: list[Family] = field(default_factory=list)
    names: list[str] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    comps: list[int] = field(default_factory=list)

    @property
    def n_w(self) -> int:
        return self.variables.n

    def inputs(self, K: int) -> NodeInputs:
        return NodeInputs(K, self.n_w)

    def latent(self, ni: NodeInputs, t: np.ndarray, orders: int = 3) -> None:
        """The path's value and time derivatives (``orders`` of them) at times t, at an event from the
        side of the phase it ends (:meth:`..schedule.phases.Phases.closing`)."""
        left = self.phases.closing(t)
        ni.spline([self.spline.basis(t, k, left) for k in range(orders)], self.variables.latent_index(), self.P_fixed)

    def add(self, name: str, ni: NodeInputs, rows: Rows, node_t: np.ndarray, L: sp.spmatrix | None = None) -> None:
        """Family ``name``: ``rows`` of its block at nodes ``ni`` (times ``node_t``), plus ``L w``."""
        if not rows.entries:
            return
        S, s0 = ni.build()
        self.families.append(Family(name, BlockEvaluator(rows.block, self.layer), S, s0, Cg=rows.matrix(ni.K), L=L))
        self.record(rows.names, np.asarray(node_t, float)[rows.nodes], rows.comps)

    def record(self, names: list[str], times: np.ndarray, comps: list[int]) -> None:
        """Names, times and components of rows a family adds by itself."""
        self.names.extend(names)
        self.times.extend(np.asarray(times, float).tolist())
        self.comps.extend(comps)
