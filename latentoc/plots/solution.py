"""Every figure of a result folder, from its files alone (``python -m latentoc plot RESULT``).

Only the result schema is read (``result.json``, :data:`latentoc.results.TRAJECTORY_KEYS`,
``gpdm.npz``): joint angles, velocities and torques with the limits the trajectory records
(``q_min``/``q_max``, ``v_max``, ``tau_min``/``tau_max``) and the initial motion (``q_initial``)
beside the optimised one; stick frames; the latent tube (``x``, ``P`` and their initial
values in the result's GPDM); Ipopt's convergence (``convergence``); for a contact motion
(``wrench``) the contact forces, the friction cone, centre-of-pressure, ZMP and COM margins over
time and the support polygon; with ``gif`` the animation ``motion.gif``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
from matplotlib.figure import Figure

from latentoc.results import Result, result_and_output
from latentoc.plots.animation import animate
from latentoc.plots.forces import contact_series, plot_contact_forces, plot_contact_margins, plot_zmp_com
from latentoc.plots.convergence import plot_convergence
from latentoc.plots.figure import FORMATS, save
from latentoc.plots.joints import plot_joint_curves, plot_torques, plot_velocities
from latentoc.plots.kinematics import floating_base, model_of
from latentoc.plots.latent import plot_latent_tube
from latentoc.plots.stick import plot_stick_frames

__all__ = ["plot_solution", "solution_figures", "actuated_joints"]


def actuated_joints(model: pin.Model, max_joints: int, Q: np.ndarray) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, q indices and v indices of the 1-DOF joints; if more than ``max_joints``, those
    moving most in Q."""
    js = [j for j in range(1, model.njoints) if model.joints[j].nq == 1]
    if len(js) > max_joints:
        ranges = np.ptp(Q[:, [model.joints[j].idx_q for j in js]], axis=0)
        js = sorted(js[k] for k in np.argsort(-ranges)[:max_joints])
    return ([model.names[j] for j in js], np.array([model.joints[j].idx_q for j in js], dtype=int),
            np.array([model.joints[j].idx_v for j in js], dtype=int))


def _initial_dynamics(model: pin.Model, t: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and torques of a sampled fixed-base motion (finite differences, numeric RNEA)."""
    V = np.gradient(Q, t, axis=0)
    A = np.gradient(V, t, axis=0)
    data = model.createData()
    return V, np.array([pin.rnea(model, data, q, v, a) for q, v, a in zip(Q, V, A)])


def solution_figures(result: Result, max_joints: int = 12, plane: str | None = None) -> dict[str, Figure]:
    """The figures of ``result`` by file stem (module doc), without the GIF."""
    traj = result.trajectory
    model = model_of(traj)
    t, q, v, tau = (np.asarray(traj[k], dtype=float) for k in ("t", "q", "v", "tau"))
    q0 = np.asarray(traj["q_initial"], dtype=float) if "q_initial" in traj else None
    same_grid = q0 is not None and len(q0) == len(t)  # an initial motion may have its own rate
    names, iq, iv = actuated_joints(model, max_joints, q)
    jv = iv - (model.nv - tau.shape[1])  # tau may hold the actuated joints only
    floating = floating_base(model)
    plane = plane or ("xz" if floating else "yz")
    figs: dict[str, Figure] = {}

    qs, vs, taus = {"optimised": q[:, iq]}, {"optimised": v[:, iv]}, {"optimised": tau[:, jv]}
    if q0 is not None and same_grid:
        qs = {"initial": q0[:, iq], **qs}
        if model.nq == model.nv and len(t) > 2:
            v0, tau0 = _initial_dynamics(model, t, q0)
            vs, taus = {"initial": v0[:, iv], **vs}, {"initial": tau0[:, jv], **taus}
    q_lim = (traj["q_min"][iq], traj["q_max"][iq]) if "q_min" in traj else None
    figs["joint_angles"] = plot_joint_curves(t, qs, names, limits=q_lim)
    figs["joint_velocities"] = plot_velocities(t, vs, names, v_max=traj["v_max"][iv] if "v_max" in traj else None)
    tau_lim = (traj["tau_min"][jv], traj["tau_max"][jv]) if "tau_min" in traj else None
    figs["torques"] = plot_torques(t, taus, names, limits=tau_lim)
    motions = {"optimised": q} if q0 is None else {"initial": q0, "optimised": q}
    times = {"optimised": t} if q0 is None else \
        {"initial": t if same_grid else np.linspace(t[0], t[-1], len(q0)), "optimised": t}
    figs["stick_frames"] = plot_stick_frames(model, motions, t=times, plane=plane)

    if "x" in traj and result.gpdm is not None and result.tube is not None and result.gpdm.latent_dim in (2, 3):
        paths = {"optimised": traj["x"]}
        if "x_initial" in traj:
            paths = {"initial": traj["x_initial"], **paths}
        ctrl = {"optimised control points": traj["P"]}
        if "P_initial" in traj:
            ctrl = {"initial control points": traj["P_initial"], **ctrl}
        delta = result.tube.delta
        figs["latent_tube"] = plot_latent_tube(result.gpdm, delta, paths=paths, control_points=ctrl,
                                               title=f"{result.problem}: delta = {delta:.3g}")
    if result.convergence:
        figs["convergence"] = plot_convergence(result.convergence, title=f"{result.problem}: Ipopt's convergence")
    if "wrench" in traj:  # a contact motion: one toe-point wrench per (symmetric) foot, its points' forces
        s = contact_series(model, traj)
        figs["contact_forces"] = plot_contact_forces(t, traj["wrench"], s["contact"], traj.get("point_forces"),
                                                     point_names=s["point_names"])
        figs["contact_margins"] = plot_contact_margins(t, s, float(traj["friction"]))
        land = s["zmp_enforced"]
        figs["zmp_com"] = plot_zmp_com(s["zmp"][land], s["com"][land], s["polygon"][-1], t=t[land])
    return figs


def plot_solution(result: Result | str | Path, max_joints: int = 12, plane: str | None = None, gif: bool = False,
                  out_dir: str | Path | None = None, format: str = "png") -> list[Path]:
    """Write the figures of a :class:`~latentoc.results.Result` or of the result folder a path
    names (module doc) into ``out_dir`` (default: the folder's ``plots/``) as ``format`` (png,
    pdf or svg), with ``gif`` also ``motion.gif``; returns the paths."""
    if format not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {format!r}")
    result, out = result_and_output(result, out_dir, "plots", "plot_solution")
    written = [save(fig, out / f"{name}.{format}", format) for name, fig in
               solution_figures(result, max_joints, plane).items()]
    if gif:
        traj = result.trajectory
        model = model_of(traj)
        written.append(animate(model, traj["t"], traj["q"], out / "motion.gif", fps=20,  # 5 cs a frame, exactly
                               plane=plane or ("xz" if floating_base(model) else "yz"), title=result.problem,
                               initial=traj.get("q_initial")))
    return written
