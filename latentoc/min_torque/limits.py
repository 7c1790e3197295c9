"""The hard limits of a fixed-base motion from the robot's model (its URDF), each switchable.

Joint positions within [lowerPositionLimit, upperPositionLimit], |joint velocity| <= velocityLimit,
|tau| <= the problem's torque limits: none, one value for every joint, one per joint, or
``"urdf"`` (effortLimit). A joint whose model gives no limit (lower >= upper, or a velocity or
effort limit that is not positive and finite) is unlimited there. The same limits bound the NLP's
rows (:mod:`.nlp`) and are checked on the exported 1 kHz motion.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

__all__ = ["Limits", "torque_limit_vector"]


def _positive(values: np.ndarray) -> np.ndarray:
    """The limits that are positive and finite; inf elsewhere (no limit)."""
    v = np.asarray(values, dtype=float)
    return np.where(np.isfinite(v) & (v > 0), v, np.inf)


def torque_limit_vector(torque_limits: Sequence[float] | str, model: pin.Model) -> np.ndarray | None:
    """Per-joint torque bounds from the problem's ``torque_limits``: [] none, [s] every joint, nv
    values, or "urdf" (the model's effortLimit; inf where it gives none)."""
    nv = model.nv
    if isinstance(torque_limits, str):
        if torque_limits != "urdf":
            raise ValueError(f'torque_limits must be a list of numbers or "urdf", got {torque_limits!r}')
        return _positive(model.effortLimit)
    if len(torque_limits) == 0:
        return None
    if len(torque_limits) == 1:
        return np.full(nv, float(torque_limits[0]))
    if len(torque_limits) != nv:
        raise ValueError(f"torque_limits has {len(torque_limits)} values, the model has {nv} joints")
    return np.asarray(torque_limits, dtype=float)


@dataclass(frozen=True)
class Limits:
    """The limits that hold (None: switched off): ``q_lo``, ``q_hi`` (nq), ``v_max``, ``tau_max`` (nv)."""

    q_lo: np.ndarray | None = None
    q_hi: np.ndarray | None = None
    v_max: np.ndarray | None = None
    tau_max: np.ndarray | None = None

    @classmethod
    def of(cls, model: pin.Model, joint_limits: bool = True, velocity_limits: bool = False,
           torque_limits: Sequence[float] | str = ()) -> "Limits":
        """The model's limits that the switches turn on (module doc)."""
        q_lo = q_hi = v_max = None
        if joint_limits:
            lo, hi = np.asarray(model.lowerPositionLimit, float), np.asarray(model.upperPositionLimit, float)
            none = ~(lo < hi)
            q_lo, q_hi = np.where(none, -np.inf, lo), np.where(none, np.inf, hi)
        if velocity_limits:
            v_max = _positive(model.velocityLimit)
        return cls(q_lo, q_hi, v_max, torque_limit_vector(torque_limits, model))

    def arrays(self) -> dict[str, np.ndarray]:
        """The limits that hold as a result's trajectory records them (q_min, q_max, v_max, tau_min,
        tau_max; those switched off left out)."""
        out: dict[str, np.ndarray] = {}
        if self.q_lo is not None and self.q_hi is not None:
            out.update(q_min=self.q_lo, q_max=self.q_hi)
        if self.v_max is not None:
            out["v_max"] = self.v_max
        if self.tau_max is not None:
            out.update(tau_min=-self.tau_max, tau_max=self.tau_max)
        return out

    def slacks(self, motion: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The smallest distance to each limit at every sample (negative: violated), per kind:
        ``joint_limits_rad``, ``velocity_limits_rad_s``, ``torque_limits_nm``."""
        out = {}
        if self.q_lo is not None and self.q_hi is not None:
            q = motion["q"]
            out["joint_limits_rad"] = np.minimum(q - self.q_lo, self.q_hi - q).min(axis=1)
        if self.v_max is not None:
            out["velocity_limits_rad_s"] = (self.v_max - np.abs(motion["v"])).min(axis=1)
        if self.tau_max is not None:
            out["torque_limits_nm"] = (self.tau_max - np.abs(motion["tau"])).min(axis=1)
        return out

    def violations(self, motion: dict[str, np.ndarray]) -> dict[str, float]:
        """The largest amount each limit is left by over the motion's samples (0: held)."""
        return {k: float(max(0.0, -s.min())) for k, s in self.slacks(motion).items()}
