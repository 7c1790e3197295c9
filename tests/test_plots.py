"""Plots: every figure is a Figure that draws on given axes and saves as PNG/PDF/SVG; what it draws
is checked against independent numbers (the tube's level set, forward kinematics, the limits given,
Ipopt's history, a static pose's ZMP)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from matplotlib.figure import Figure
from PIL import Image
from gif_pixels import colour_pixels
from result_factory import jump_trajectory, make_jump_result, make_result

from latentoc import plots
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.robots.human_arm import arm_trial, build_human_arm


@pytest.fixture(scope="module")
def arm():
    t, Q = arm_trial()
    return build_human_arm(), t, Q


@pytest.fixture(scope="module")
def gpdm3(arm):
    _, _, Q = arm
    return learn_gpdm(Q[::6], GPDMSettings(latent_dim=3, max_iterations=20))


@pytest.fixture(scope="module")
def gpdm2(arm):
    _, _, Q = arm
    return learn_gpdm(Q[::6], GPDMSettings(latent_dim=2, max_iterations=20))


def check_png(path, name, rows=1):
    assert path.exists() and path.stat().st_size > 1000
    with Image.open(path) as im:
        assert im.format == "PNG"
        assert im.size == plots.pixel_size(name, rows)


def limit_lines(ax) -> list[float]:
    """The y values of the horizontal limit lines drawn in ``ax`` (LIMIT_STYLE)."""
    return sorted(float(line.get_ydata()[0]) for line in ax.get_lines()
                  if line.get_color() == plots.LIMIT_STYLE["color"] and line.get_linestyle() == plots.LIMIT_STYLE["ls"])


def test_tube_mesh_lies_on_the_level_set(gpdm3):
    delta = 2.0 * gpdm3.tube_size()
    P, ok = plots.tube_mesh(gpdm3, delta, n_along=20, n_around=12)
    assert P.shape == (20, 12, 3) and ok.mean() > 0.9
    v = gpdm3.variance(P[ok])  # independent evaluation of Eq. 19
    assert np.allclose(v, delta, rtol=1e-4)
    # the centre curve is inside the tube and the surface is the first crossing along each ray
    C = plots.resample(gpdm3.latent_trajectories()[0], 20)
    assert np.all(gpdm3.variance(C) <= delta)
    R = P - C[:, None, :]
    for f in (0.25, 0.5, 0.9):
        assert np.all(gpdm3.variance((C[:, None, :] + f * R)[ok]) < delta)


def test_tube_mesh_requires_3d(gpdm2):
    with pytest.raises(ValueError, match="3-D"):
        plots.tube_mesh(gpdm2, 1.0)


@pytest.mark.parametrize("which", ["gpdm3", "gpdm2"])
def test_latent_tube_has_equal_axes(which, request, tmp_path):
    """One scale on every axis: the 3-D box's sides are proportional to the axes' data spans, the 2-D
    aspect is 1; every latent point is inside the limits."""
    g = request.getfixturevalue(which)
    X = g.latent_trajectories()[0]
    fig = plots.plot_latent_tube(g, 2.0 * g.tube_size(), paths={"initial": X, "optimised": X * 1.01},
                                 control_points=X[:: max(len(X) // 8, 1)])
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    if g.latent_dim == 3:
        lims = np.array([ax.get_xlim(), ax.get_ylim(), ax.get_zlim()])
        spans = lims[:, 1] - lims[:, 0]
        box = np.asarray(ax.get_box_aspect())
        assert np.allclose(box / box.max(), spans / spans.max())
        assert np.all((g.X >= lims[:, 0]) & (g.X <= lims[:, 1]))
    else:
        assert ax.get_aspect() == 1.0
    check_png(plots.save(fig, tmp_path / f"{which}.png"), "latent_tube")
    with pytest.raises(ValueError, match="axes"):
        plots.plot_latent_tube(g, 1.0, axes=Figure().add_subplot(projection="3d" if g.latent_dim == 2 else None))


def test_curves_draw_the_given_limits_and_skip_infinite_ones(arm, tmp_path):
    model, t, Q = arm
    names = list(model.names[1:])
    lo, hi = -np.arange(1.0, 8.0), np.arange(1.0, 8.0)
    hi[2] = np.inf  # no upper limit on the third joint
    fig = plots.plot_joint_curves(t, {"initial": Q, "optimised": 0.9 * Q}, names, limits=(lo, hi))
    for j, ax in enumerate(fig.axes[:7]):
        assert ax.get_title() == names[j]
        expected = [np.degrees(lo[j])] + ([np.degrees(hi[j])] if np.isfinite(hi[j]) else [])
        assert np.allclose(limit_lines(ax), sorted(expected))
        assert np.allclose(ax.get_lines()[1].get_ydata(), np.degrees(0.9 * Q[:, j]))  # the data, in degrees
    check_png(plots.save(fig, tmp_path / "q.png"), "joint_curves")
    v_max = np.full(7, 2.0)
    fig = plots.plot_velocities(t, np.gradient(Q, t, axis=0), names, v_max=v_max)
    assert np.allclose(limit_lines(fig.axes[0]), np.degrees([-2.0, 2.0]))
    check_png(plots.save(fig, tmp_path / "v.png"), "velocities")
    tau = np.sin(t)[:, None] * np.arange(1, 8)
    fig = plots.plot_torques(t, tau, names, limits=(-hi, hi))
    assert np.allclose(limit_lines(fig.axes[0]), [-1.0, 1.0]) and limit_lines(fig.axes[2]) == []
    check_png(plots.save(fig, tmp_path / "tau.png"), "torques")
    with pytest.raises(ValueError, match="expected shape"):
        plots.plot_torques(t, tau[:, :3], names)


def test_figures_draw_on_the_callers_axes(arm):
    """axes=: the caller's figure is returned and holds the drawing; too few axes is an error."""
    model, t, Q = arm
    fig = Figure()
    axes = fig.subplots(2, 4).ravel()
    names = list(model.names[1:])
    assert plots.plot_joint_curves(t, Q, names, axes=axes) is fig
    assert all(len(ax.get_lines()) == 1 for ax in axes[:7])
    with pytest.raises(ValueError, match="7 panels"):
        plots.plot_joint_curves(t, Q, names, axes=axes[:3])
    fig2 = Figure()
    row = fig2.subplots(1, 3)
    assert plots.plot_stick_frames(model, Q, frames=3, plane="yz", axes=row) is fig2
    assert all(ax.get_lines() for ax in row)


@pytest.mark.parametrize("fmt, magic", [("png", b"\x89PNG"), ("pdf", b"%PDF"), ("svg", b"<?xml")])
def test_save_formats(arm, tmp_path, fmt, magic):
    model, t, Q = arm
    fig = plots.plot_joint_curves(t, Q, list(model.names[1:]))
    path = plots.save(fig, tmp_path / f"q.{fmt}")
    assert path.read_bytes().startswith(magic)
    first = path.read_bytes()
    assert plots.save(fig, tmp_path / f"q.{fmt}").read_bytes() == first  # no date stamped in: the same file
    with pytest.raises(ValueError, match="format"):
        plots.save(fig, tmp_path / "q.jpg")


def test_stick_frames_carry_their_times_and_a_scale(arm, tmp_path):
    model, t, Q = arm
    fig = plots.plot_stick_frames(model, {"initial": Q, "optimised": Q[::-1]}, t=t, plane="yz", frames=5)
    check_png(plots.save(fig, tmp_path / "s.png"), "stick_frames", rows=2)
    idx = plots.frame_indices(len(Q), 5)
    titles = [ax.get_title() for ax in fig.axes[:5]]
    assert titles[0] == f"initial  t = {0:.2f} s"
    assert [s.split("t = ")[1] for s in titles] == [f"{t[i] - t[0]:.2f} s" for i in idx]
    bar = plots.scale_bar_length(1.0)
    assert bar == 0.2 and plots.scale_bar_length(3.0) == 0.5 and plots.scale_bar_length(0.05) == 0.01
    texts = [tx.get_text() for tx in fig.axes[0].texts]
    assert len(texts) == 1 and texts[0].endswith(" m")
    length = float(texts[0].split()[0])
    bar_line = [ln for ln in fig.axes[0].get_lines() if ln.get_linewidth() == 2.5][0]
    assert np.isclose(np.ptp(bar_line.get_xdata()), length)  # the bar is as long as it says
    with pytest.raises(ValueError, match="times"):
        plots.plot_stick_frames(model, Q, t=t[:-1])


def test_stick_segments_are_forward_kinematics(arm):
    model, _, Q = arm
    q = Q[len(Q) // 2]
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    joints = np.array([data.oMi[i].translation for i in range(model.njoints)])
    S, names = plots.skeleton_segments(model, q, return_names=True)
    for (a, b), n in zip(S, names):
        if n in model.names:  # a joint: its segment ends at that joint's placement
            j = model.getJointId(n)
            assert np.allclose(b, joints[j]) and np.allclose(a, joints[model.parents[j]])
        else:  # a bone end frame: starts at its parent joint
            f = model.frames[model.getFrameId(n)]
            assert np.allclose(a, joints[f.parentJoint])
    assert np.allclose(plots.joint_positions(model, q), joints)
    hand = model.getFrameId("lhand_end")
    pin.updateFramePlacements(model, data)
    assert any(np.allclose(b, data.oMf[hand].translation) for _, b in S)


def test_free_flyer_has_no_bone_to_world():
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    model.addJoint(j, pin.JointModelRX(), pin.SE3(np.eye(3), np.array([0, 0, -0.5])), "knee")
    q = pin.neutral(model)
    q[2] = 1.0
    S = plots.skeleton_segments(model, q)
    assert S.shape == (1, 2, 3) and np.allclose(S[0, 0], [0, 0, 1]) and np.allclose(S[0, 1], [0, 0, 0.5])


def test_convergence_draws_each_run_after_the_previous(tmp_path):
    runs = [{"phase": "phase 1", "round": 1, "history": {"iter": [0, 1, 2], "objective": [3.0, 2.0, 1.5],
                                                         "inf_pr": [1.0, 1e-3, 1e-9], "inf_du": [1.0, 0.1, 1e-9],
                                                         "mu": [0.1, 1e-3, 1e-9], "alpha_pr": [0, 1, 1],
                                                         "alpha_du": [0, 0.5, 1]}},
            {"phase": "phase 2", "round": 1, "history": {"iter": [0, 1], "objective": [1.5, 1.2], "inf_pr": [1e-9, 1e-10],
                                                         "inf_du": [1e-2, 1e-9], "mu": [1e-4, 1e-9],
                                                         "alpha_pr": [0, 1], "alpha_du": [0, 1]}}]
    fig = plots.plot_convergence(runs)
    ax = fig.axes[0]
    obj = [ln for ln in ax.get_lines() if ln.get_label().startswith("phase")]
    assert [ln.get_label() for ln in obj] == ["phase 1, round 1", "phase 2, round 1"]
    assert list(obj[0].get_xdata()) == [0, 1, 2] and list(obj[1].get_xdata()) == [3, 4]
    assert list(obj[1].get_ydata()) == [1.5, 1.2]
    assert fig.axes[1].get_yscale() == "log" and fig.axes[2].get_yscale() == "log"
    check_png(plots.save(fig, tmp_path / "c.png"), "convergence")
    with pytest.raises(ValueError, match="no convergence"):
        plots.plot_convergence([])


def test_contact_series_of_a_static_stance():
    """A pose held still on both feet: the ZMP is the COM's ground projection (Eq. 35 with dh = 0),
    inside the feet's polygon by the COM's margin; the friction ratio is the wrench's."""
    from latentoc.jump.demonstration.training import training_jumps
    from latentoc.robots.cmu_humanoid import symmetric_model

    model, _ = symmetric_model()
    q = training_jumps()[0].Q[0]
    n = 3
    wrench = np.tile([20.0, 0.0, 300.0, 0.0, 6.0, 0.0], (n, 1))
    traj = {"t": np.linspace(0, 0.002, n), "q": np.tile(q, (n, 1)), "v": np.zeros((n, model.nv)),
            "a": np.zeros((n, model.nv)), "wrench": wrench, "contact": np.ones(n, np.int8), "touchdown": 0.0,
            "settle": 0.0, "heel_offset": np.array([-0.05, 0.0, -0.03]), "friction": 0.4,
            "contact_frames": np.array(["lfoot", "lfoot_end", "ltoes_end", "rfoot", "rfoot_end", "rtoes_end"])}
    s = plots.contact_series(model, traj)
    c = pin.centerOfMass(model, model.createData(), q)
    assert np.allclose(s["zmp"], c[:2], atol=1e-9) and np.allclose(s["com"], c)
    assert np.allclose(s["zmp_margin"], s["com_margin"]) and np.all(s["zmp_margin"] > 0)
    assert np.allclose(s["friction_ratio"], 20.0 / 300.0) and np.allclose(s["normal"], 300.0)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    toe = data.oMf[model.getFrameId("ltoes_end")].translation  # an older result: no toe_offset, the toe tip
    heel = data.oMf[model.getFrameId("lfoot")].act(traj["heel_offset"])
    cop = toe[0] - (6.0 + toe[2] * 20.0) / 300.0  # on the ground below the wrench's point
    assert np.allclose(s["cop_margin"], min(cop - heel[0], toe[0] - cop))
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert plots.polygon_margin(square, np.array([0.25, 0.5])) == pytest.approx(0.25)
    assert plots.polygon_margin(square[::-1], np.array([1.5, 0.5])) == pytest.approx(-0.5)
    fig = plots.plot_contact_margins(traj["t"], s, 0.4)
    assert limit_lines(fig.axes[0]) == [0.4] and all(limit_lines(ax) == [0.0] for ax in fig.axes[1:4])
    assert plots.plot_contact_forces(traj["t"], wrench, traj["contact"]).axes[0].get_lines()[0].get_ydata()[0] == 300.0


def test_contact_series_agrees_with_the_jumps_own_check(small_export, small_jump):
    """On the broad jump's 1 kHz export: the ZMP and COM margins of the plots (from the result schema:
    the polygon of both feet's heel and toe tip, their own ZMP) against latentoc.jump.check.verify.series
    (the left foot mirrored: the feet agree to a fraction of a millimetre), in the same windows."""
    from latentoc.jump.check.verify import series

    model = small_jump.js.model
    traj = {**small_export, "friction": 0.4}
    ours = plots.contact_series(model, traj)
    theirs = series(model, traj, 0.4)
    zmp = np.nanmin(theirs["zmp"], axis=1)  # verify: per polygon edge, where enforced
    on = np.isfinite(zmp)
    assert on.sum() > 10 and np.array_equal(on, ours["zmp_enforced"])
    assert np.allclose(ours["zmp_margin"][on], zmp[on], atol=1e-3)
    com = np.nanmin(theirs["com"], axis=1)
    on = np.isfinite(com)
    assert np.array_equal(on, ours["com_enforced"]) and np.allclose(ours["com_margin"][on], com[on], atol=1e-3)


def test_every_contact_point_of_the_jump_is_drawn(tmp_path):
    """A broad jump in the export's format (four points per foot): the series and both contact
    figures carry each point's force and friction ratio by name; the support polygon's corners are
    the heels and toe points where the jump's own code puts them; the centre of pressure is the
    wrench's, between heel and toe point."""
    from latentoc.jump.robot.feet import FootGeometry, foot_points

    model, traj = jump_trajectory()
    s = plots.contact_series(model, traj)
    names = ["heel", "ball", "toe", "pad"]
    assert s["point_names"] == names and s["point_ratio"].shape == (len(traj["t"]), 4)
    F = traj["point_forces"]
    weight = sum(i.mass for i in model.inertias) * 9.81
    shown = traj["contact"].astype(bool)[:, None] & (F[..., 1] > 1e-3 * weight)
    assert shown.all(axis=0).sum() == 0 and shown.any(axis=0).all()  # each point loaded at some time, not always
    assert np.array_equal(np.isfinite(s["point_ratio"]), shown)
    assert np.allclose(s["point_ratio"][shown], np.abs(F[..., 0])[shown] / F[..., 1][shown])
    geom = FootGeometry.from_result(traj)
    data = model.createData()
    for i in range(0, len(traj["t"]), 20):
        pin.framesForwardKinematics(model, data, traj["q"][i])
        heel, _, toe, _ = foot_points(model, data, geom).T
        ends = np.array([heel, toe, heel * [1, -1, 1], toe * [1, -1, 1]])[:, :2]
        assert np.allclose(np.sort(s["polygon"][i], axis=0), np.sort(ends, axis=0), atol=1e-12)
        fx, _, fz, _, my, _ = traj["wrench"][i]
        if traj["contact"][i] and fz > 0:
            cop = toe[0] - (my + toe[2] * fx) / fz
            assert np.isclose(s["cop_margin"][i], min(cop - heel[0], toe[0] - cop))
        else:
            assert np.isnan(s["cop_margin"][i])
    fig = plots.plot_contact_forces(traj["t"], traj["wrench"], traj["contact"], F, point_names=names)
    normal, tangential = fig.axes[:2]
    on = traj["contact"].astype(bool)
    for k, name in enumerate(names):
        line = [ln for ln in normal.get_lines() if ln.get_label() == name][0]
        assert np.allclose(line.get_ydata()[on], F[on, k, 1])
        line = [ln for ln in tangential.get_lines() if ln.get_label() == f"$f_x$, {name}"][0]
        assert np.allclose(line.get_ydata()[on], F[on, k, 0])
    fig = plots.plot_contact_margins(traj["t"], s, 0.4)
    assert [ln.get_label() for ln in fig.axes[0].get_lines()][1:5] == names
    check_png(plots.save(fig, tmp_path / "m.png"), "contact_margins")


def test_contact_forces_zmp_gain(tmp_path):
    t = np.linspace(0, 1, 50)
    W = np.zeros((50, 6))
    W[:, 2] = 300 * (1 + np.cos(6 * t))
    W[:, 0] = 20 * np.sin(6 * t)
    check_png(plots.save(plots.plot_contact_forces(t, W, np.ones(50)), tmp_path / "f.png"), "contact_forces")
    poly = np.array([[0, -0.1], [0.25, -0.1], [0.25, 0.1], [0, 0.1]])
    zmp = np.column_stack([0.1 + 0.05 * t, 0.02 * np.sin(9 * t)])
    com = np.column_stack([0.12 + 0.02 * t, 0.01 * t, np.full(50, 0.9)])
    check_png(plots.save(plots.plot_zmp_com(zmp, com, poly), tmp_path / "zmp.png"), "zmp_com")
    results = [make_result(tube=d, gain=g) for d, g in [(1e-5, 19.0), (1e-4, 31.0), (1e-6, 3.0)]]
    fig = plots.plot_gain_vs_tube(results, reference=[(1e-6, 2.87), (1e-4, 31.3)])
    assert list(fig.axes[0].get_lines()[1].get_ydata()) == [3.0, 19.0, 31.0]  # sorted by delta
    check_png(plots.save(fig, tmp_path / "gain.png"), "gain_vs_tube")
    results += [make_result(tube=None, method="joint-range", gain=g, success=k < 40, joint_range_deg=k)
                for k, g in [(5, 5.3), (20, 23.5), (45, 38.5)]]
    check_png(plots.save(plots.plot_gain_vs_tube(results), tmp_path / "gain2.png"), "gain_vs_tube")
    with pytest.raises(ValueError, match="no result"):
        plots.plot_gain_vs_tube([])


def test_plot_start_poses(arm, tmp_path):
    model, _, Q = arm
    rows = [{"tube": d, "translational_distance": 0.1 * k, "pose_distance": 0.15 * k, "q": Q[5 * k].tolist()}
            for k, d in enumerate([1e-3, 1e-2, 1e-1])]
    check_png(plots.save(plots.plot_start_poses(rows, model=model), tmp_path / "sp.png"), "start_poses")
    check_png(plots.save(plots.plot_start_poses(rows), tmp_path / "sp2.png"), "start_poses")


@pytest.mark.slow  # stick frames of 50 poses and the tube mesh
def test_plot_solution_arm(arm, gpdm3, tmp_path, fmt="png"):
    """An arm result (latent path, training fit, its GPDM, limits, Ipopt's history): every figure."""
    model, t, Q = arm
    X = gpdm3.latent_trajectories()[0]
    t, Q = t[::6], Q[::6]
    n = len(t)
    history = {"iter": [0, 1], "objective": [2.0, 1.0], "inf_pr": [1, 0], "inf_du": [1, 0], "mu": [0.1, 0.01],
               "alpha_pr": [0, 1], "alpha_du": [0, 1]}
    traj = {"q": Q, "v": np.gradient(Q, t, axis=0), "tau": np.sin(np.outer(t, np.arange(1, 8))),
            "q_initial": Q[::-1].copy(), "x": X, "x_initial": X[::-1].copy(), "P": X[::10], "P_initial": X[::10] + 0.01,
            "q_min": model.lowerPositionLimit, "q_max": model.upperPositionLimit}
    r = make_result(model, n, tube=2.0 * gpdm3.tube_size(), trajectory=traj, gpdm=gpdm3)
    r.convergence = [{"phase": "latent", "round": 1, "history": history}]
    r.save(tmp_path)
    paths = plots.plot_solution(tmp_path, format=fmt)
    assert {p.name for p in paths} == {f"{k}.{fmt}" for k in ("joint_angles", "joint_velocities", "torques",
                                                             "stick_frames", "latent_tube", "convergence")}
    assert all(p.parent == tmp_path / "plots" for p in paths)
    if fmt == "png":
        figure = {"joint_angles": "joint_curves", "joint_velocities": "velocities", "torques": "torques",
                  "stick_frames": "stick_frames", "latent_tube": "latent_tube", "convergence": "convergence"}
        for p in paths:
            check_png(p, figure[p.stem], rows=2)  # rows: initial and optimised stick frames
    figs = plots.solution_figures(r)
    assert np.allclose(limit_lines(figs["joint_angles"].axes[0]),
                       np.degrees([model.lowerPositionLimit[0], model.upperPositionLimit[0]]))
    assert limit_lines(figs["torques"].axes[0]) == [] and limit_lines(figs["joint_velocities"].axes[0]) == []


@pytest.mark.slow  # the humanoid's frames and animation
def test_plot_solution_jump_format(tmp_path):
    """A broad-jump result in the export's format (actuated tau, toe-point wrench, four points' forces,
    q_initial: the training jump on the result's grid): every figure, the contact figures with each
    point; the GIF of the floating-base robot shows the training jump's ghost."""
    from latentoc.plots.animation import GHOST_COLOUR, animate

    r = make_jump_result(stride=2)
    r.save(tmp_path)
    paths = {p.name: p for p in plots.plot_solution(tmp_path, gif=True)}
    assert set(paths) == {"joint_angles.png", "joint_velocities.png", "torques.png", "stick_frames.png",
                          "contact_forces.png", "contact_margins.png", "zmp_com.png", "motion.gif"}
    check_png(paths["stick_frames.png"], "stick_frames", rows=2)
    check_png(paths["contact_margins.png"], "contact_margins")
    check_png(paths["contact_forces.png"], "contact_forces")
    figs = plots.solution_figures(r)
    labels = [ln.get_label() for ln in figs["contact_forces"].axes[0].get_lines()]
    assert all(name in labels for name in ("heel", "ball", "toe", "pad"))
    assert len(figs["joint_angles"].axes[0].get_lines()) >= 2  # the initial and the optimised motion
    grey = np.array([int(GHOST_COLOUR[k:k + 2], 16) for k in (1, 3, 5)])


    traj = r.trajectory
    model = plots.model_of(traj)
    alone = animate(model, traj["t"], traj["q"], tmp_path / "alone.gif", fps=20, plane="xz")
    more = np.array(colour_pixels(paths["motion.gif"], grey)) - np.array(colour_pixels(alone, grey))
    apart = np.arange(len(more)) / 20.0 > float(traj["takeoff"]) + 0.1  # the optimised jump has left the ghost
    assert more.min() > 100  # the ghost's tip trace, its figure hidden under the same stance
    assert apart.sum() > 10 and more[apart].min() > 1000
