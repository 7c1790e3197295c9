"""Phase timing of the jump and the node grid (Sect. 4.2).

Takeoff and touchdown come from the training motion's contact timing
(:func:`latentoc.mocap.jumps.detect_jumps` on the symmetric training configurations).
The landing is "settled" (Eq. 36's COM-in-polygon constraint applies) from the first
training frame after touchdown at which the projected COM is inside the feet's polygon.
Nodes: ``n_stance`` on [0, t_to], ``n_flight`` on [t_to, t_td], ``n_land`` on [t_td, T]
(the phase boundaries appear in both neighbouring phases).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..mocap.jumps import detect_jumps
from .training import BALL, FOOT, TOE, JumpTraining


@dataclass(frozen=True)
class Phases:
    """Times in seconds."""

    takeoff: float
    touchdown: float
    settle: float
    duration: float

    def grid(self, n_stance: int, n_flight: int, n_land: int) -> dict[str, np.ndarray]:
        return {"stance": np.linspace(0.0, self.takeoff, n_stance),
                "flight": np.linspace(self.takeoff, self.touchdown, n_flight),
                "land": np.linspace(self.touchdown, self.duration, n_land)}


def training_phases(model: pin.Model, tr: JumpTraining, fps: float = 120.0) -> Phases:
    """Phases of a symmetric training jump."""
    jumps = detect_jumps(model, tr.Q, fps)
    if not jumps:
        raise ValueError("no jump detected in the training motion")
    j = jumps[0]
    d = model.createData()
    settle = None
    for i in range(j.touchdown, len(tr.Q)):
        pin.framesForwardKinematics(model, d, tr.Q[i])
        c = pin.centerOfMass(model, d, tr.Q[i])
        heel_x = d.oMf[model.getFrameId(FOOT)].translation[0]
        toe_x = d.oMf[model.getFrameId(TOE)].translation[0]
        if heel_x <= c[0] <= toe_x:
            settle = tr.t[i]
            break
    if settle is None:
        settle = tr.t[-1]
    return Phases(float(tr.t[j.takeoff]), float(tr.t[j.touchdown]), float(settle), tr.duration)
