"""Phase timing of the jump and the node grid (Sect. 4.2).

Takeoff and touchdown come from the training motion's contact timing, refined to the toe
tip, the point the stance and landing are pinned at (:mod:`.contact`):
:func:`latentoc.mocap.jumps.detect_jumps` finds the flight by the feet's height (1.5 cm
above their floor: 0.350 s and 0.683 s on the paper's jump); the toe tip, however, leaves
the ground earlier and lands later.  Takeoff is the toe-off, the frame at which the toe tip
is lowest in the 0.1 s before the detected takeoff (0.308 s: it then rises and is 2.2 cm up,
moving at 1.4 m/s, by 0.350 s, so a toe pinned until 0.350 s cannot take the captured
takeoff velocity, measured in issue 6); touchdown is the first frame after the detected one
at which the toe tip is back at its standing height (0.692 s).
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
from .training import FOOT, TOE, JumpTraining


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


def toe_heights(model: pin.Model, Q: np.ndarray) -> np.ndarray:
    """Height of the left toe tip (frame ``ltoes_end``) in every configuration."""
    d = model.createData()
    fid = model.getFrameId(TOE)
    out = np.zeros(len(Q))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, d, q)
        out[i] = d.oMf[fid].translation[2]
    return out


def training_phases(model: pin.Model, tr: JumpTraining, fps: float = 120.0) -> Phases:
    """Phases of a symmetric training jump: toe-off, toe touchdown, settle (see module doc)."""
    jumps = detect_jumps(model, tr.Q, fps)
    if not jumps:
        raise ValueError("no jump detected in the training motion")
    j = jumps[0]
    z = toe_heights(model, tr.Q)
    lo = max(0, j.takeoff - int(round(0.1 * fps)))
    i_off = lo + int(np.argmin(z[lo:j.takeoff + 1]))
    down = np.where(z[j.touchdown:] <= z[0])[0]
    i_td = j.touchdown + int(down[0]) if len(down) else j.touchdown
    d = model.createData()
    settle = None
    for i in range(i_td, len(tr.Q)):
        pin.framesForwardKinematics(model, d, tr.Q[i])
        c = pin.centerOfMass(model, d, tr.Q[i])
        heel_x = d.oMf[model.getFrameId(FOOT)].translation[0]
        toe_x = d.oMf[model.getFrameId(TOE)].translation[0]
        if heel_x <= c[0] <= toe_x:
            settle = tr.t[i]
            break
    if settle is None:
        settle = tr.t[-1]
    return Phases(float(tr.t[i_off]), float(tr.t[i_td]), float(settle), tr.duration)
