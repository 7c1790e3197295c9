"""Results built by hand for the tests of the result schema, the plots and the 3-D view (no solve);
a broad jump in the export's format from the real CMU model and training jump."""
from __future__ import annotations
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

from functools import lru_cache
from typing import Any

import numpy as np
import pinocchio as pin

from latentoc.runtime.environment import Environment
from latentoc.results import Result, Times
from latentoc.latent.tube import TubeResult


def make_result(model: pin.Model | None = None, n: int = 11, *, tube: float | None = 0.5, method: str = "latent",
                gain: float = 12.5, success: bool = True, trajectory: dict[str, Any] | None = None,
                gpdm: Any = None, **details: Any) -> Result:
    """A Result of ``model`` (default: the human arm at rest for 1 s) with the given fields."""
    if model is None:
        from latentoc.robots import load_robot
        model = load_robot("human-arm")
    t = np.linspace(0.0, 1.0, n)
    q = np.tile(pin.neutral(model), (n, 1))
    arrays = {"t": t, "q": q, "v": np.zeros((n, model.nv)), "a": np.zeros((n, model.nv)),
              "tau": np.zeros((n, model.nv)), "model": np.str_(model.saveToString())}
    arrays.update(trajectory or {})
    tube_result = None if tube is None else TubeResult(spec=f"{tube:g}", delta=tube, relative=10 * tube,
                                                        training=tube / 5, max_sigma2=0.9 * tube)
    return Result(problem="test", kind="latent-min-torque", method=method, status="Solve_Succeeded" if success
                  else "Maximum_Iterations_Exceeded", success=success, iterations=7, cost_initial=2.0,
                  cost=2.0 * (1 - gain / 100), gain_pct=gain, cost_meaning="test cost", times=Times(solve_s=0.25),
                  tube=tube_result, violations={"tube": 0.0}, environment=Environment.current(),
                  settings={"latent_dim": 3}, details=details, trajectory=arrays, gpdm=gpdm)


JUMP_SHIFT = 0.3  # m the factory's optimised jump lands beyond the training jump (its ghost)
LOADED_HEIGHT = 0.015  # m: a contact point this close to the ground carries load
SHARES = np.array([0.4, 0.3, 0.2, 0.1])  # of a foot's force: heel, ball, toe, pad (those loaded)


@lru_cache(maxsize=4)
def _jump_arrays(stride: int) -> tuple[pin.Model, dict[str, np.ndarray]]:
    from latentoc.jump.robot.feet import MU, POINTS, foot_points
    from latentoc.jump.demonstration.training import training_jumps
    from latentoc.robots.cmu_humanoid import symmetric_model

    model, _ = symmetric_model()
    training = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, training.Q[0])
    t, Q0 = training.t[::stride], training.Q[::stride]
    n, dt = len(t), float(t[1] - t[0])
    data = model.createData()

    def left_points(Q: np.ndarray) -> np.ndarray:  # (n, 4, 3): heel, ball, toe, pad of the left foot
        out = []
        for q in Q:
            pin.framesForwardKinematics(model, data, q)
            out.append(foot_points(model, data, geom).T)
        return np.array(out)

    # the contact schedule of the training motion: in flight while every point is above 1 cm
    flight = np.flatnonzero(left_points(Q0)[:, :, 2].min(axis=1) > 0.01)
    takeoff, touchdown = float(t[flight[0] - 1]), float(t[flight[-1] + 1])
    contact = (t <= takeoff + 1e-9) | (t >= touchdown - 1e-9)
    # the "optimised" jump: the training jump carried JUMP_SHIFT further forward during the flight
    s = np.clip((t - takeoff) / (touchdown - takeoff), 0.0, 1.0)
    Q = Q0.copy()
    Q[:, 0] += JUMP_SHIFT * s * s * (3.0 - 2.0 * s)
    near = [(max(i - 1, 0), min(i + 1, n - 1)) for i in range(n)]  # central differences, one-sided at the ends
    V = np.array([pin.difference(model, Q[i0], Q[i1]) / ((i1 - i0) * dt) for i0, i1 in near])
    A = np.gradient(V, t, axis=0)
    P = left_points(Q)
    loaded = contact[:, None] & (P[:, :, 2] < LOADED_HEIGHT)
    # the ground force the momentum rate needs, half per foot, shared by its loaded points, in the cone
    mass = sum(i.mass for i in model.inertias)
    forces, wrench, tau = np.zeros((n, len(POINTS), 2)), np.zeros((n, 6)), np.zeros((n, model.nv - 6))
    for i in range(n):
        dh = pin.computeCentroidalMomentumTimeVariation(model, data, Q[i], V[i], A[i]).vector
        tau[i] = pin.rnea(model, data, Q[i], V[i], A[i])[6:]
        if loaded[i].any():  # unequal shares, so that the points can be told apart
            share = np.where(loaded[i], SHARES, 0.0) / np.sum(SHARES[loaded[i]])
            fz = max(0.5 * (dh[2] + mass * 9.81), 0.0) * share
            forces[i, :, 1], forces[i, :, 0] = fz, np.clip(0.5 * dh[0] * share, -0.9 * MU * fz, 0.9 * MU * fz)
        r = P[i] - P[i, 2]  # about the toe point (latentoc.jump.robot.feet.toe_wrench)
        wrench[i] = [forces[i, :, 0].sum(), 0.0, forces[i, :, 1].sum(), 0.0,
                     float(np.sum(r[:, 2] * forces[i, :, 0] - r[:, 0] * forces[i, :, 1])), 0.0]
    arrays = {"t": t, "q": Q, "v": V, "a": A, "tau": tau, "wrench": wrench, "point_forces": forces,
              "contact": contact.astype(np.int8), "loaded": loaded.astype(np.int8),
              "contact_frames": np.array(["lfoot", "lfoot_end", "ltoes_end", "rfoot", "rfoot_end", "rtoes_end"]),
              "contact_points": np.array(POINTS), "heel_offset": geom.heel_offset, "pad_offset": geom.pad_offset,
              "takeoff": np.float64(takeoff), "touchdown": np.float64(touchdown),
              "settle": np.float64(touchdown + 0.07), "tau_min": np.full(model.nv - 6, -300.0),
              "tau_max": np.full(model.nv - 6, 300.0), "friction": np.float64(MU), "q_initial": Q0,
              "model": np.str_(model.saveToString())}
    return model, arrays


def jump_trajectory(stride: int = 1) -> tuple[pin.Model, dict[str, np.ndarray]]:
    """The model and ``trajectory.npz`` arrays of a broad jump in the export's format
    (:func:`latentoc.jump.check.export.trajectory`), from the real CMU model and training jump (every
    ``stride``-th of its 120 Hz frames): the training jump carried ``JUMP_SHIFT`` further in its
    flight as the optimised motion, the training jump itself as ``q_initial``; each foot's heel,
    ball, toe and pad loaded near the ground, sharing (by ``SHARES``) the ground force the
    momentum rate needs, within the friction cone; the toe-point wrench of those forces."""
    model, arrays = _jump_arrays(stride)
    return model, {k: np.array(v, copy=True) for k, v in arrays.items()}


def make_jump_result(stride: int = 1, **trajectory: Any) -> Result:
    """A broad-jump Result of :func:`jump_trajectory` (entries of ``trajectory`` replace or, as
    None, drop its arrays)."""
    model, arrays = jump_trajectory(stride)
    for key, value in trajectory.items():
        if value is None:
            arrays.pop(key, None)
        else:
            arrays[key] = value
    r = make_result(model, len(arrays["t"]), tube=None, trajectory=arrays)
    r.problem, r.kind = "broad-jump", "broad-jump"
    return r
