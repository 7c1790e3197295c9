"""Plots: every figure writes a PNG of its documented size; tube mesh and stick figures are exact."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from PIL import Image
from result_factory import make_result

from latentoc import plots
from latentoc.gpdm import GPDMSettings, learn_gpdm
from latentoc.human_models import arm_training_motion, build_human_arm


@pytest.fixture(scope="module")
def arm():
    t, Q = arm_training_motion()
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


def test_tube_mesh_lies_on_the_level_set(gpdm3):
    delta = 2.0 * gpdm3.tube_size()
    P, ok = plots.tube_mesh(gpdm3, delta, n_along=20, n_around=12)
    assert P.shape == (20, 12, 3) and ok.mean() > 0.9
    v = gpdm3.variance(P[ok])  # independent evaluation of Eq. 19
    assert np.allclose(v, delta, rtol=1e-4)
    # the centre curve is inside the tube and the surface is the first crossing along each ray
    C = plots._resample(gpdm3.latent_trajectories()[0], 20)
    assert np.all(gpdm3.variance(C) <= delta)
    R = P - C[:, None, :]
    for f in (0.25, 0.5, 0.9):
        assert np.all(gpdm3.variance((C[:, None, :] + f * R)[ok]) < delta)


def test_tube_mesh_requires_3d(gpdm2):
    with pytest.raises(ValueError, match="3-D"):
        plots.tube_mesh(gpdm2, 1.0)


@pytest.mark.parametrize("which", ["gpdm3", "gpdm2"])
def test_plot_latent_tube(which, request, tmp_path):
    g = request.getfixturevalue(which)
    X = g.latent_trajectories()[0]
    p = plots.plot_latent_tube(g, 2.0 * g.tube_size(), tmp_path / f"{which}.png",
                               paths={"initial": X, "optimised": X * 1.01},
                               control_points=X[:: max(len(X) // 8, 1)])
    check_png(p, "latent_tube")


def test_joint_curves_and_torques(arm, tmp_path):
    model, t, Q = arm
    names = list(model.names[1:])
    check_png(plots.plot_joint_curves(t, {"initial": Q, "optimised": 0.9 * Q}, names,
                                      tmp_path / "q.png"), "joint_curves")
    tau = np.sin(t)[:, None] * np.arange(1, 8)
    lim = (tau.min(axis=0), tau.max(axis=0))
    check_png(plots.plot_torques(t, tau, names, tmp_path / "tau.png", limits=lim), "torques")
    with pytest.raises(ValueError, match="expected shape"):
        plots.plot_torques(t, tau[:, :3], names, tmp_path / "bad.png")


def test_contact_forces_zmp_gain(tmp_path):
    t = np.linspace(0, 1, 50)
    F = np.zeros((50, 2, 3))
    F[:, :, 2] = 300 * (1 + np.cos(6 * t))[:, None]
    F[:, 0, 0] = 20 * np.sin(6 * t)
    check_png(plots.plot_contact_forces(t, F, ["lfoot", "rfoot"], tmp_path / "f.png"),
              "contact_forces")
    poly = np.array([[0, -0.1], [0.25, -0.1], [0.25, 0.1], [0, 0.1]])
    zmp = np.column_stack([0.1 + 0.05 * t, 0.02 * np.sin(9 * t)])
    com = np.column_stack([0.12 + 0.02 * t, 0.01 * t, np.full(50, 0.9)])
    check_png(plots.plot_zmp_com(zmp, com, poly, tmp_path / "zmp.png"), "zmp_com")
    results = [make_result(tube=d, gain=g) for d, g in [(1e-5, 19.0), (1e-4, 31.0), (1e-6, 3.0)]]
    check_png(plots.plot_gain_vs_tube(results, tmp_path / "gain.png",
                                      reference=[(1e-6, 2.87), (1e-4, 31.3)]), "gain_vs_tube")
    results += [make_result(tube=None, method="joint-range", gain=g, success=k < 40, joint_range_deg=k)
                for k, g in [(5, 5.3), (20, 23.5), (45, 38.5)]]
    check_png(plots.plot_gain_vs_tube(results, tmp_path / "gain2.png"), "gain_vs_tube")
    with pytest.raises(ValueError, match="no result"):
        plots.plot_gain_vs_tube([], tmp_path / "gain3.png")


def test_plot_start_poses(arm, tmp_path):
    model, _, Q = arm
    rows = [{"tube": d, "translational_distance": 0.1 * k, "pose_distance": 0.15 * k, "q": Q[5 * k].tolist()}
            for k, d in enumerate([1e-3, 1e-2, 1e-1])]
    check_png(plots.plot_start_poses(rows, tmp_path / "sp.png", model=model), "start_poses")
    check_png(plots.plot_start_poses(rows, tmp_path / "sp2.png"), "start_poses")


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


@pytest.mark.parametrize("layout", ["panels", "overlay"])
def test_plot_stick_frames(arm, tmp_path, layout):
    model, _, Q = arm
    p = plots.plot_stick_frames(model, {"initial": Q, "optimised": Q[::-1]}, tmp_path / "s.png",
                                plane="yz", layout=layout)
    check_png(p, "stick_frames", rows=2)
    assert list(plots.frame_indices(len(Q), 8)) [0] == 0
    assert plots.frame_indices(len(Q), 8)[-1] == len(Q) - 1
    assert len(plots.frame_indices(len(Q), 8)) == 8


@pytest.mark.slow  # stick frames of 50 poses and the tube mesh
def test_plot_solution_arm(arm, gpdm3, tmp_path):
    """An arm result (latent path, training fit, its GPDM): angles, torques (the training fit's by
    numeric RNEA), stick frames and the latent tube."""
    model, t, Q = arm
    X = gpdm3.latent_trajectories()[0]
    t, Q = t[::6], Q[::6]
    n = len(t)
    traj = {"q": Q, "tau": np.sin(np.outer(t, np.arange(1, 8))), "q_initial": Q[::-1].copy(), "x": X,
            "x_initial": X[::-1].copy(), "P": X[::10], "P_initial": X[::10] + 0.01}
    make_result(model, n, tube=2.0 * gpdm3.tube_size(), trajectory=traj, gpdm=gpdm3).save(tmp_path)
    paths = plots.plot_solution(tmp_path)
    assert {p.name for p in paths} == {"joint_angles.png", "torques.png", "stick_frames.png", "latent_tube.png"}
    assert all(p.parent == tmp_path / "plots" for p in paths)
    figure = {"joint_angles": "joint_curves", "torques": "torques", "stick_frames": "stick_frames",
              "latent_tube": "latent_tube"}
    for p in paths:
        check_png(p, figure[p.stem], rows=2)  # rows: initial and optimised stick frames


@pytest.mark.slow  # the humanoid's frames and animation
def test_plot_solution_jump_format(tmp_path):
    """A broad-jump result (actuated tau, one wrench per foot, touchdown, heel offset): contact
    forces and landing balance are derived; a static pose has its ZMP at the COM."""
    from latentoc.human_models import broad_jump_training_motion, build_cmu_humanoid

    model = build_cmu_humanoid()
    tj, Qj = broad_jump_training_motion()
    t, Q = tj[::8], Qj[::8]
    n = len(t)
    wrench = np.zeros((n, 6))
    wrench[:, 2] = 300.0
    traj = {"t": t, "q": Q, "tau": np.zeros((n, model.nv - 6)), "wrench": wrench, "contact": np.ones(n, np.int8),
            "touchdown": np.float64(t[n // 2]), "heel_offset": np.array([-0.05, 0.0, 0.0]),
            "tau_min": -np.ones(model.nv - 6), "tau_max": np.ones(model.nv - 6),
            "q_initial": Qj}  # the training jump at its own frame rate: stick frames only
    make_result(model, n, tube=None, trajectory=traj).save(tmp_path)
    paths = {p.name: p for p in plots.plot_solution(tmp_path, gif=True)}
    assert set(paths) == {"joint_angles.png", "torques.png", "stick_frames.png", "contact_forces.png", "zmp_com.png",
                          "motion.gif"}
    check_png(paths["stick_frames.png"], "stick_frames", rows=2)
    with Image.open(paths["motion.gif"]) as im:
        assert im.n_frames == int(round(15 * (t[-1] - t[0]))) + 1  # 15 fps, both ends
    full = {**traj, "v": np.zeros((n, model.nv)), "a": np.zeros((n, model.nv))}
    zmp, com, poly, tz = plots._landing_balance(model, full)
    assert len(zmp) == len(com) == len(tz) == np.sum(t >= t[n // 2])
    assert np.allclose(zmp, com[:, :2], atol=1e-9)  # static: ZMP = ground projection of the COM
    data = model.createData()
    assert np.allclose(com[-1], pin.centerOfMass(model, data, Q[-1]))
    assert poly.shape == (4, 2) and np.allclose(poly[0, 1], -poly[3, 1])
