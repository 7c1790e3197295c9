"""Replay of a plan's joint torques in MuJoCo, with joint PD tracking, and its summary.

The model is :func:`.mjcf.mjcf_from_model`'s; it starts at the plan's first state ``q[0], v[0]``.
Every joint gets ``tau_ff(t) + kp (q_plan - q) + kd (v_plan - v)``: ``tau_ff`` held per sample of
the plan (zero-order hold), the plan interpolated linearly in time. MuJoCo's actuators compute the
PD (``ctrl = tau_ff + kp q_plan + kd v_plan``, bias ``-kp q - kd' v``), so it acts within the step,
and clamp its force to the plan's torque limits (``tau_min``, ``tau_max``) as a robot's actuators
would; the summary's ``clamped_fraction`` is the share of samples at which one did.

Gains (:func:`gains`): one ``kp`` (N m/rad) for every joint and, by default, each joint's
``kd = 2 sqrt(kp I)`` (critical damping), ``I`` the joint's diagonal of the joint-space inertia
matrix at ``q[0]``; or one uniform ``kd``. ``kp = 0`` (the default kd then 0) replays the
feedforward torques alone.

Integrators: ``implicitfast`` (default) integrates the PD implicitly ("stable PD", Tan, Liu &
Turk 2011): the actuators' velocity gain is ``kd' = kd + h kp`` and MuJoCo treats it implicitly, so
the PD acts on the end-of-step state ``q + h v_next, v_next`` (the targets taken at the step's end)
and stays stable at any gain, even on joints of 1e-5 kg m^2 (fingers). It is first order: with
``kp = 0`` a skeleton's light twist joints drift (tenths of a rad in 0.3 s of a swinging flight at
0.5 ms steps), which the PD removes. ``rk4`` is MuJoCo's explicit RK4 (targets at mid-step): exact
for a feedforward replay, but its PD diverges on light joints above a few hundred N m/rad.

Recorded at the plan's samples: q and v (Pinocchio's conventions), the torque each joint received
over the sample's interval (the mean over its steps; the last sample: the command at the final
state), the sphere centres and the world contact force on each sphere
(:func:`mujoco.mj_contactForce`) at the sample. The summary is :func:`summarize`'s.
"""
from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np
import pinocchio as pin

from latentoc.errors import SimulationError
from latentoc.runtime.progress import bar
from latentoc.simulate.mjcf import base_rotations, dof_order, floating_base, mjcf_from_model, state_from_mujoco, state_to_mujoco

__all__ = ["Simulation", "Gains", "gains", "replay", "summarize", "LOADED", "FALL_HEIGHT", "FALL_TILT_DEG"]

LOADED = 0.01  # a sphere is loaded above this fraction of the body weight (contact slip)
FALL_HEIGHT = 0.5  # fell: the base below this fraction of its initial height ...
FALL_TILT_DEG = 60.0  # ... or its up axis this far from the plan's

Contact = tuple[str, np.ndarray]


@dataclass(frozen=True)
class Gains:
    """The joint PD gains: ``kp`` for every joint, ``kd`` per joint (Pinocchio's column order)."""

    kp: float
    kd: np.ndarray
    rule: str  # "critical" (2 sqrt(kp I) per joint) or "uniform"

    def describe(self, names: Sequence[str]) -> dict[str, Any]:
        """JSON-ready: kp, the kd rule, its range and each joint's kd."""
        return {"kp": self.kp, "kd_rule": self.rule, "kd_min": float(self.kd.min()) if self.kd.size else 0.0,
                "kd_max": float(self.kd.max()) if self.kd.size else 0.0, "kd": dict(zip(names, map(float, self.kd)))}


def gains(model: pin.Model, q0: np.ndarray, kp: float, kd: float | None = None) -> Gains:
    """``kp`` for every joint; ``kd`` uniform if given, else critical damping at ``q0`` (module doc)."""
    if not (np.isfinite(kp) and kp >= 0):
        raise SimulationError(f"kp must be a finite number >= 0, got {kp}")
    if kd is not None:
        if not (np.isfinite(kd) and kd >= 0):
            raise SimulationError(f"kd must be a finite number >= 0, got {kd}")
        return Gains(float(kp), np.full(model.nv - 6, float(kd)), "uniform")
    I = np.diag(pin.crba(model, model.createData(), np.asarray(q0, dtype=float)))[6:]
    return Gains(float(kp), 2.0 * np.sqrt(kp * I), "critical")


@dataclass
class Simulation:
    """A replay: the plan's times ``t`` (up to a divergence), simulated ``q``, ``v`` (Pinocchio's),
    applied joint torques ``tau`` (as the plan's columns), world contact ``forces`` (n x spheres x 3)
    and sphere centres ``points`` (n x spheres x 3), and the :func:`summarize` dict."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    forces: np.ndarray
    points: np.ndarray
    contacts: list[str]
    gains: Gains
    summary: dict[str, Any] = field(default_factory=dict)
    mjcf: str = field(default="", repr=False)

    def arrays(self) -> dict[str, Any]:
        """What ``simulation.npz`` holds."""
        return {"t": self.t, "q": self.q, "v": self.v, "tau": self.tau, "contact_forces": self.forces,
                "contact_positions": self.points, "contact_names": np.array(self.contacts), "kp": np.array(self.gains.kp),
                "kd": self.gains.kd}


def _plan(model: pin.Model, arrays: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """t, q, v and the joint torques (n x (nv - 6)) of ``arrays``, and their sample period."""
    try:
        t, q, v, tau = (np.asarray(arrays[k], dtype=float) for k in ("t", "q", "v", "tau"))
    except KeyError as exc:
        raise SimulationError(f"the plan lacks the array {exc}") from None
    n, nj = len(t), model.nv - 6
    if tau.ndim == 2 and tau.shape[1] == model.nv:
        tau = tau[:, 6:]
    if n < 2 or q.shape != (n, model.nq) or v.shape != (n, model.nv) or tau.shape != (n, nj):
        raise SimulationError(f"the plan's t {t.shape}, q {q.shape}, v {v.shape}, tau {tau.shape} do not fit "
                              f"the model (nq {model.nq}, nv {model.nv}, {nj} joint torques)")
    dt = np.diff(t)
    if not np.allclose(dt, dt[0], rtol=1e-6, atol=1e-9) or dt[0] <= 0:
        raise SimulationError("the plan's times t must be evenly spaced and increasing")
    return t, q, v, tau, float(dt[0])


def replay(model: pin.Model, arrays: Mapping[str, Any], kp: float, kd: float | None = None,
           contacts: Sequence[Contact] = (), friction: float = 0.4, *, radius: float = 0.005,
           timestep: float = 0.0005, distance_point: Sequence[Contact] | None = None,
           integrator: str = "implicitfast", desc: str = "simulate") -> Simulation:
    """Replay the plan ``arrays`` (t, q, v, tau; optional tau_min, tau_max) of ``model`` in MuJoCo
    with contact spheres ``contacts`` on a floor of ``friction`` (module doc). ``distance_point``:
    the points whose mean's forward travel is the landing distance (default: every contact)."""
    if not floating_base(model):
        raise SimulationError(f"model {model.name!r}: the replay needs a free-flyer root")
    t, Q, V, tau_ff, dt = _plan(model, arrays)
    sub = int(round(dt / timestep))
    if sub < 1 or abs(sub * timestep - dt) > 1e-9:
        raise SimulationError(f"the timestep {timestep} s must divide the plan's sample period {dt} s")
    g = gains(model, Q[0], kp, kd)
    xml = mjcf_from_model(model, list(contacts), friction, radius=radius, timestep=timestep)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    order = dof_order(model)
    col = np.array([model.idx_vs[int(j)] for j in order]) - 6  # plan column of each actuator
    qpos_plan, qvel_plan = state_to_mujoco(model, Q, V)
    Qj, Vj, F, Kd = qpos_plan[:, 7:], qvel_plan[:, 6:], tau_ff[:, col], g.kd[col]
    implicit = integrator == "implicitfast"
    if not implicit and integrator != "rk4":
        raise SimulationError(f"integrator must be 'implicitfast' or 'rk4', got {integrator!r}")
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST if implicit else mujoco.mjtIntegrator.mjINT_RK4
    m.actuator_biastype[:] = mujoco.mjtBias.mjBIAS_AFFINE  # force = ctrl - kp q - (kd [+ h kp]) v
    m.actuator_biasprm[:] = 0.0
    m.actuator_biasprm[:, 1] = -g.kp
    m.actuator_biasprm[:, 2] = -(Kd + timestep * g.kp) if implicit else -Kd
    bound = _actuator_bounds(arrays, col, tau_ff.shape[1])
    m.actuator_forcelimited[:] = np.isfinite(bound[0])  # an actuator gives no more than its joint's limit
    m.actuator_forcerange[:] = np.where(np.isfinite(bound), bound, 0.0).T
    spheres = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"contact{k}_{name}") for k, (name, _) in enumerate(contacts)]
    d.qpos[:], d.qvel[:] = qpos_plan[0], qvel_plan[0]
    mujoco.mj_forward(m, d)

    n, nc = len(t), len(spheres)
    qpos, qvel = np.zeros((n, m.nq)), np.zeros((n, m.nv))
    applied, forces, points = np.zeros((n, m.nu)), np.zeros((n, nc, 3)), np.zeros((n, nc, 3))
    clamped = np.zeros(n, bool)  # samples where an actuator met its limit
    done = n
    with bar(total=n, desc=desc, unit="sample") as progress:
        for i in range(n):
            qpos[i], qvel[i] = d.qpos, d.qvel
            points[i] = d.geom_xpos[spheres]
            if i == n - 1:
                mujoco.mj_forward(m, d)  # the contacts of the final state
                forces[i] = _sphere_forces(m, d, spheres)
                wanted = F[i] + g.kp * (Qj[i] - d.qpos[7:]) + Kd * (Vj[i] - d.qvel[6:])
                applied[i] = np.clip(wanted, bound[0], bound[1])
                clamped[i] = bool(np.any(applied[i] != wanted))
            for s in range(sub if i < n - 1 else 0):
                w = (s + 1.0) / sub if implicit else (s + 0.5) / sub  # the targets at the step's end (middle)
                d.ctrl[:] = F[i] + g.kp * ((1 - w) * Qj[i] + w * Qj[i + 1]) + Kd * ((1 - w) * Vj[i] + w * Vj[i + 1])
                before = (d.qpos[7:].copy(), d.qvel[6:].copy())
                mujoco.mj_step(m, d)
                if s == 0:
                    forces[i] = _sphere_forces(m, d, spheres)  # this step's contacts: the state at t[i]
                qj, vj = (d.qpos[7:], d.qvel[6:]) if implicit else ((before[0] + d.qpos[7:]) / 2, (before[1] + d.qvel[6:]) / 2)
                wanted = d.ctrl - g.kp * qj - Kd * vj
                force = np.clip(wanted, bound[0], bound[1])  # as MuJoCo clamps it (actuator forcerange)
                applied[i] += force / sub
                clamped[i] |= bool(np.any(force != wanted))
            progress.update(1)
            if d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
                done = i + 1  # MuJoCo reset the state: keep what came before
                break
    q, v = state_from_mujoco(model, qpos[:done], qvel[:done])
    tau = np.zeros((done, model.nv - 6))
    tau[:, col] = applied[:done]
    sim = Simulation(t[:done], q, v, tau, forces[:done], points[:done], [name for name, _ in contacts], g, mjcf=xml)
    sim.summary = summarize(model, arrays, sim, contacts, distance_point, diverged=done < n)
    sim.summary["clamped_fraction"] = float(np.mean(clamped[:done]))
    return sim


def _limits(arrays: Mapping[str, Any], n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The plan's torque limits (tau_min, tau_max as its n joint torques' columns) and which columns they
    hold (a nonempty interval: not the joints a symmetric plan leaves unloaded, limits 0, 0); None
    without limits."""
    if "tau_min" not in arrays or "tau_max" not in arrays:
        return None
    lo, hi = np.asarray(arrays["tau_min"], dtype=float), np.asarray(arrays["tau_max"], dtype=float)
    if lo.shape != (n,) or hi.shape != (n,):
        raise SimulationError(f"tau_min {lo.shape} and tau_max {hi.shape} do not fit the {n} joint torques")
    return lo, hi, lo < hi


def _actuator_bounds(arrays: Mapping[str, Any], col: np.ndarray, n: int) -> np.ndarray:
    """Each actuator's force range (2 x actuators, columns ``col`` of the plan's limits): -inf, inf where
    :func:`_limits` holds none."""
    held = _limits(arrays, n)
    if held is None:
        return np.vstack([np.full(len(col), -np.inf), np.full(len(col), np.inf)])
    lo, hi, on = (x[col] for x in held)
    return np.vstack([np.where(on, lo, -np.inf), np.where(on, hi, np.inf)])


def _sphere_forces(m: mujoco.MjModel, d: mujoco.MjData, spheres: list[int]) -> np.ndarray:
    """World force (spheres x 3) the floor exerts on each sphere, from the current contacts."""
    out = np.zeros((len(spheres), 3))
    where = {gid: k for k, gid in enumerate(spheres)}
    f6 = np.zeros(6)
    for c in range(d.ncon):
        con = d.contact[c]
        k, sign = (where.get(con.geom2), 1.0) if con.geom2 in where else (where.get(con.geom1), -1.0)
        if k is None:
            continue
        mujoco.mj_contactForce(m, d, c, f6)  # on geom2, in the contact frame (rows: normal, tangents)
        out[k] += sign * con.frame.reshape(3, 3).T @ f6[:3]
    return out


def _points(model: pin.Model, Q: np.ndarray, points: Sequence[Contact]) -> np.ndarray:
    """World positions (n x 3) of the mean of ``points`` along configurations Q."""
    data = model.createData()
    out = np.zeros((len(Q), 3))
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, data, q)
        out[i] = np.mean([data.oMf[model.getFrameId(f)].act(np.asarray(o, dtype=float)) for f, o in points], axis=0)
    return out


def _slip(points: np.ndarray, loaded: np.ndarray) -> float:
    """Largest horizontal travel of a sphere from where its loaded stretch began."""
    worst = 0.0
    for k in range(points.shape[1]):
        start = None
        for i in range(len(points)):
            if not loaded[i, k]:
                start = None
                continue
            if start is None:
                start = points[i, k, :2]
            worst = max(worst, float(np.linalg.norm(points[i, k, :2] - start)))
    return worst


def summarize(model: pin.Model, arrays: Mapping[str, Any], sim: Simulation, contacts: Sequence[Contact],
              distance_point: Sequence[Contact] | None = None, diverged: bool = False) -> dict[str, Any]:
    """The replay's summary: landing distance (simulated and planned), base tracking, fall,
    contact slip, torque excess, the contact points' initial heights and the gains."""
    Q = np.asarray(arrays["q"], dtype=float)[: len(sim.t)]
    point = list(distance_point) if distance_point else list(contacts)
    out: dict[str, Any] = {"duration": float(sim.t[-1] - sim.t[0]), "planned_duration": float(np.ptp(arrays["t"])),
                           "diverged": bool(diverged)}
    if point:
        planned = _points(model, np.asarray(arrays["q"], dtype=float)[[0, -1]], point)
        simulated = _points(model, sim.q[[0, -1]], point)
        out["landing_point"] = [f for f, _ in point]
        out["landing_distance_planned"] = float(planned[1, 0] - planned[0, 0])
        out["landing_distance"] = float("nan") if diverged else float(simulated[1, 0] - simulated[0, 0])
    err = np.linalg.norm(sim.q[:, :3] - Q[:, :3], axis=1)
    out["base_tracking_rms"], out["base_tracking_max"] = float(np.sqrt(np.mean(err**2))), float(err.max())
    R_plan, _ = base_rotations(Q)
    R_sim, _ = base_rotations(sim.q)
    up = R_plan[0].T @ np.array([0.0, 0.0, 1.0])  # the base axis that is vertical at the start
    cos = np.einsum("ni,ni->n", R_plan @ up, R_sim @ up)
    tilt = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    low = sim.q[:, 2] < FALL_HEIGHT * sim.q[0, 2]
    over = low | (tilt > FALL_TILT_DEG)
    out["fell"] = bool(over.any() or diverged)
    out["fall_time"] = float(sim.t[np.argmax(over)]) if over.any() else (float(sim.t[-1]) if diverged else None)
    out["max_tilt_deg"], out["min_base_height"] = float(tilt.max()), float(sim.q[:, 2].min())
    weight = sum(Y.mass for Y in model.inertias) * float(np.linalg.norm(model.gravity.linear))
    out["max_contact_slip"] = _slip(sim.points, sim.forces[..., 2] > LOADED * weight) if len(contacts) else 0.0
    out["max_contact_force_bw"] = float(np.sum(sim.forces[..., 2], axis=1).max() / weight) if len(contacts) else 0.0
    if contacts:
        z0 = _contact_heights(model, Q[0], contacts)
        out["initial_contact_height_min"], out["initial_contact_height_max"] = float(z0.min()), float(z0.max())
    names = [model.names[int(j)] for j in range(2, model.njoints)]
    out["torque_excess"] = _excess(sim.tau, arrays, names)
    out["gains"] = sim.gains.describe(names)
    return out


def _contact_heights(model: pin.Model, q: np.ndarray, contacts: Sequence[Contact]) -> np.ndarray:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return np.array([data.oMf[model.getFrameId(f)].act(np.asarray(o, dtype=float))[2] for f, o in contacts])


def _excess(tau: np.ndarray, arrays: Mapping[str, Any], names: Sequence[str]) -> dict[str, Any] | None:
    """How far the applied torques leave [tau_min, tau_max]: the largest excess (N m), its joint and
    time, the fraction of samples with any joint over; None without limits. Columns whose interval
    is empty or a point (the joints a symmetric plan leaves unloaded: limits 0, 0) are not checked."""
    held = _limits(arrays, tau.shape[1])
    if held is None:
        return None
    lo, hi, checked = held
    over = np.where(checked, np.maximum(np.maximum(tau - hi, lo - tau), 0.0), 0.0)
    i, j = np.unravel_index(int(np.argmax(over)), over.shape)
    return {"max": float(over.max()), "joint": names[int(j)], "time_index": int(i),
            "fraction": float(np.mean((over > 1e-9).any(axis=1))), "unchecked_joints": int((~checked).sum())}
