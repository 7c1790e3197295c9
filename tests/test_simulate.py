"""The MuJoCo replay (latentoc.simulate): the MJCF has Pinocchio's dynamics, a flight replays to its
plan, contact forces carry the weight, the right foot mirrors the left, and bad input is an error."""
import json
import re

import numpy as np
import pinocchio as pin
import pytest

mujoco = pytest.importorskip("mujoco")

from latentoc.cli.parser import main  # noqa: E402
from latentoc.errors import SimulationError  # noqa: E402
from latentoc.simulate.command import DEFAULT_KP as SIM_KP  # noqa: E402
from latentoc.simulate.command import check_mirror, contact_points  # noqa: E402
from latentoc.simulate.mjcf import (  # noqa: E402
    force_from_mujoco, mjcf_from_model, state_from_mujoco, state_to_mujoco)
from latentoc.simulate.replay import replay  # noqa: E402

FEET = ["lfoot", "lfoot_end", "ltoes_end", "rfoot", "rfoot_end", "rtoes_end"]


def _cmu():
    from latentoc.robots.cmu_humanoid import symmetric_model

    return symmetric_model()[0]


def _talos():
    from latentoc.robots.catalog import load_robot

    try:
        return load_robot("talos")
    except (FileNotFoundError, LookupError) as exc:
        pytest.skip(f"talos does not load: {exc}")


def _chain():
    """A free body carrying a massless chain (RZ, RY, an unaligned hinge) with rotated, offset
    placements that ends in a massive RX joint: one MJCF body with four hinges."""
    rng = np.random.default_rng(1)
    model = pin.Model()
    j = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    model.appendBodyToJoint(j, pin.Inertia(5.0, np.zeros(3), np.diag([0.1, 0.2, 0.25])), pin.SE3.Identity())
    for k, joint in enumerate([pin.JointModelRZ(), pin.JointModelRY(), pin.JointModelRevoluteUnaligned(0.6, 0.0, 0.8),
                               pin.JointModelRX()]):
        j = model.addJoint(j, joint, pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.1, size=3)), f"j{k}")
    model.appendBodyToJoint(j, pin.Inertia(1.0, np.array([0.02, -0.01, 0.05]), np.diag([0.01, 0.012, 0.015])),
                            pin.SE3.Identity())
    model.addFrame(pin.Frame("tip", j, 0, pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(scale=0.1, size=3)),
                             pin.FrameType.OP_FRAME))
    return model


def _random_state(model, rng):
    q = pin.integrate(model, pin.neutral(model), rng.normal(size=model.nv))
    return q, rng.normal(size=model.nv), rng.normal(size=model.nv)


@pytest.mark.parametrize("build", [_cmu, _talos, _chain], ids=["cmu", "talos", "chain"])
def test_mjcf_has_pinocchios_mass_com_and_inverse_dynamics(build):
    model = build()
    rng = np.random.default_rng(7)
    on_mass = [f.name for f in model.frames if f.parentJoint > 0 and model.inertias[f.parentJoint].mass > 0]
    contacts = [(str(name), rng.normal(scale=0.05, size=3)) for name in rng.choice(on_mass, 2)]
    xml = mjcf_from_model(model, contacts, friction=0.4)
    assert "massless" not in xml  # every massless ASF joint merged into its chain's body
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    assert m.nv == model.nv and m.nu == model.nv - 6
    assert m.nbody == 1 + sum(model.inertias[j].mass > 0 for j in range(1, model.njoints))  # a body per chain
    mass = sum(Y.mass for Y in model.inertias)
    assert m.body_mass.sum() == pytest.approx(mass, rel=1e-12)
    m.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    data = model.createData()
    for _ in range(3):
        q, v, a = _random_state(model, rng)
        qpos, qvel = state_to_mujoco(model, q, v)
        back = state_from_mujoco(model, qpos, qvel)
        assert np.allclose(back[0], q, atol=1e-14) and np.allclose(back[1], v, atol=1e-14)
        R = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
        qacc = np.concatenate([R @ (a[:3] + np.cross(v[3:6], v[:3])), a[3:6], np.zeros(m.nv - 6)])
        qacc[6:] = state_to_mujoco(model, q, a)[1][6:]  # the joints in MuJoCo's order
        d.qpos[:], d.qvel[:], d.qacc[:] = qpos, qvel, qacc
        mujoco.mj_inverse(m, d)
        tau = pin.rnea(model, data, q, v, a)
        assert np.abs(force_from_mujoco(model, q, d.qfrc_inverse) - tau).max() <= 1e-8 * np.abs(tau).max()
        assert np.allclose(d.subtree_com[0], pin.centerOfMass(model, data, q), rtol=0, atol=1e-10)
        pin.framesForwardKinematics(model, data, q)
        for k, (frame, offset) in enumerate(contacts):
            gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"contact{k}_{frame}")
            assert np.allclose(d.geom_xpos[gid], data.oMf[model.getFrameId(frame)].act(offset), atol=1e-12)


def test_a_massless_joint_that_cannot_be_merged_gets_a_negligible_mass():
    model = _chain()
    leaf = model.addJoint(model.njoints - 1, pin.JointModelRY(), pin.SE3.Identity(), "leaf")  # no mass, no child
    xml = mjcf_from_model(model, [], friction=0.4)
    assert "massless, unmergeable: leaf" in xml
    m = mujoco.MjModel.from_xml_string(xml)
    assert m.body_mass[m.body("leaf").id] == pytest.approx(1e-6) and model.inertias[leaf].mass == 0.0


def _flight_plan(model, n=301, dt=1e-3, substeps=4):
    """A free fall 10 m above the floor with the limbs' joints swinging (0.3 rad, 1 to 2 Hz): the torques
    from the floating-base inverse dynamics (computed torque) at each sample, held over it, and
    q, v from Pinocchio's ABA under them (RK4), so that the base moves as the joints push it."""
    rng = np.random.default_rng(3)
    nj = model.nv - 6
    limbs = np.array([any(k in model.names[j] for k in ("femur", "tibia", "foot", "humerus", "radius"))
                      for j in range(2, model.njoints)])
    amp, w, phase = 0.3 * limbs, 2 * np.pi * rng.uniform(1, 2, nj), rng.uniform(0, 2 * np.pi, nj)
    q = pin.neutral(model)
    q[2] = 10.0
    q[7:] = amp * np.sin(phase)
    v = np.zeros(model.nv)
    v[6:] = amp * w * np.cos(phase)
    data = model.createData()
    t = np.arange(n) * dt
    Q, V, tau = np.zeros((n, model.nq)), np.zeros((n, model.nv)), np.zeros((n, nj))
    h = dt / substeps

    def acc(q, v, u):
        return pin.aba(model, data, q, v, np.concatenate([np.zeros(6), u]))

    for i in range(n):
        Q[i], V[i] = q, v
        s = np.sin(w * t[i] + phase)
        a_j = -amp * w**2 * s + 400.0 * (amp * s - q[7:]) + 40.0 * (amp * w * np.cos(w * t[i] + phase) - v[6:])
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        b = pin.nonLinearEffects(model, data, q, v)
        a_b = -np.linalg.solve(M[:6, :6], M[:6, 6:] @ a_j + b[:6])  # the base the joints push
        tau[i] = M[6:, :6] @ a_b + M[6:, 6:] @ a_j + b[6:]
        for _ in range(substeps):
            k1v, k1a = v, acc(q, v, tau[i])
            k2v, k2a = v + h / 2 * k1a, acc(pin.integrate(model, q, h / 2 * k1v), v + h / 2 * k1a, tau[i])
            k3v, k3a = v + h / 2 * k2a, acc(pin.integrate(model, q, h / 2 * k2v), v + h / 2 * k2a, tau[i])
            k4v, k4a = v + h * k3a, acc(pin.integrate(model, q, h * k3v), v + h * k3a, tau[i])
            q = pin.integrate(model, q, h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v))
            v = v + h / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)
    return {"t": t, "q": Q, "v": V, "tau": tau}


def test_a_flight_replays_to_its_plan_on_feedforward_torques():
    model = _cmu()
    plan = _flight_plan(model)
    assert np.abs(plan["q"][:, 7:] - plan["q"][0, 7:]).max() > 0.3  # the joints move
    assert plan["q"][-1, 2] < 10.0 - 0.4  # a free fall of 0.3 s
    contacts = [(f, np.zeros(3)) for f in FEET]
    sim = replay(model, plan, kp=0.0, contacts=contacts, friction=0.4, integrator="rk4", desc="test")
    assert not sim.summary["diverged"] and len(sim.t) == len(plan["t"])
    assert np.abs(sim.q - plan["q"]).max() < 1e-6 and np.abs(sim.v - plan["v"]).max() < 1e-4
    assert np.array_equal(sim.tau, plan["tau"])  # kp = kd = 0: the feedforward alone, held per sample
    assert not sim.forces.any()  # no contact 10 m above the floor
    for kp in (SIM_KP, 5000.0):  # the default integrator, its PD stable at any gain
        sim = replay(model, plan, kp=kp, contacts=contacts, friction=0.4, desc="test")
        assert np.abs(sim.q[:, 7:] - plan["q"][:, 7:]).max() < 2e-3 and sim.summary["base_tracking_max"] < 1.5e-3
        assert np.abs(sim.tau - plan["tau"]).max() < 0.5  # N m: the PD adds little


def _box():
    """A 10 kg box on four corner points with a 1 kg pendulum hanging from its centre."""
    model = pin.Model()
    root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    model.appendBodyToJoint(root, pin.Inertia.FromBox(10.0, 0.4, 0.3, 0.2), pin.SE3.Identity())
    leg = model.addJoint(root, pin.JointModelRY(), pin.SE3.Identity(), "leg")
    model.appendBodyToJoint(leg, pin.Inertia(1.0, np.array([0.0, 0.0, -0.05]), np.diag([1e-3, 1e-3, 1e-4])),
                            pin.SE3.Identity())
    model.addFrame(pin.Frame("base", root, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    for name, x in zip(FEET, (-0.2, 0.1, 0.2) * 2):  # a broad jump's contact frames on the bottom
        y = 0.15 if name[0] == "l" else -0.15
        model.addFrame(pin.Frame(name, root, 0, pin.SE3(np.eye(3), np.array([x, y, -0.1])), pin.FrameType.OP_FRAME))
    corners = [("base", np.array([x, y, -0.1])) for x in (-0.2, 0.2) for y in (-0.15, 0.15)]
    return model, corners


def test_standing_box_contact_forces_carry_the_weight_without_slip():
    model, corners = _box()
    n = 301
    q = pin.neutral(model)
    q[2] = 0.1  # the corner points on the ground
    plan = {"t": np.arange(n) * 1e-3, "q": np.tile(q, (n, 1)), "v": np.zeros((n, model.nv)),
            "tau": np.zeros((n, 1)), "tau_min": np.array([-2.0]), "tau_max": np.array([2.0])}
    sim = replay(model, plan, kp=50.0, contacts=corners, friction=0.4, desc="test")
    weight = 11.0 * 9.81
    assert sim.forces[-1, :, 2].sum() == pytest.approx(weight, rel=1e-3)
    assert np.allclose(sim.forces[-1, :, 2], weight / 4, rtol=0.02)  # the pendulum hangs centred
    assert np.abs(sim.forces[-1, :, :2]).max() < 1e-3 * weight
    s = sim.summary
    assert not s["fell"] and s["max_contact_slip"] < 1e-5 and s["base_tracking_max"] < 2e-4
    assert s["landing_distance"] == pytest.approx(0.0, abs=1e-5) and s["landing_distance_planned"] == 0.0
    assert s["torque_excess"]["max"] == 0.0 and s["clamped_fraction"] == 0.0


def test_torque_limits_that_do_not_fit_the_plan_are_refused_by_name():
    """tau_min and tau_max of another length than the plan's joint torques: a SimulationError naming
    them (the actuators' clamp and the excess report read them through one reader)."""
    model, corners = _box()
    n = 11
    q = pin.neutral(model)
    q[2] = 0.1
    plan = {"t": np.arange(n) * 1e-3, "q": np.tile(q, (n, 1)), "v": np.zeros((n, model.nv)),
            "tau": np.zeros((n, 1)), "tau_min": np.array([-2.0, -1.0]), "tau_max": np.array([2.0, 1.0])}
    with pytest.raises(SimulationError, match=r"tau_min \(2,\) and tau_max \(2,\) do not fit the 1 joint torques"):
        replay(model, plan, kp=10.0, contacts=corners, desc="test")


def test_the_actuators_are_clamped_to_the_plans_torque_limits():
    """A plan asking 5 N m of the pendulum joint with limits of +-2 N m: MuJoCo's actuator gives 2 at
    the most (forcerange), every sample reports the clamp, and the pendulum swings as 2 N m drive it,
    not as 5 would (its angle after 20 ms against the constant-torque motion, I = 3.5e-3 kg m^2)."""
    model, corners = _box()
    n = 101
    q = pin.neutral(model)
    q[2] = 0.1
    plan = {"t": np.arange(n) * 1e-3, "q": np.tile(q, (n, 1)), "v": np.zeros((n, model.nv)),
            "tau": np.full((n, 1), 5.0), "tau_min": np.array([-2.0]), "tau_max": np.array([2.0])}
    sim = replay(model, plan, kp=0.0, contacts=corners, friction=0.4, desc="test")
    assert np.abs(sim.tau).max() <= 2.0 + 1e-12 and sim.summary["clamped_fraction"] == 1.0
    assert sim.summary["torque_excess"]["max"] == 0.0
    inertia = 1e-3 + 1.0 * 0.05 ** 2  # about the joint axis (the hanging 1 kg at 5 cm)
    swing = sim.q[20, 7]  # 0.11 rad: gravity's moment is a few per cent of the drive's
    assert swing == pytest.approx(0.5 * 2.0 / inertia * 0.02 ** 2, rel=0.03)


def test_cli_replays_a_result_and_writes_its_files(tmp_path, capsys):
    from result_factory import make_result

    model, _ = _box()
    n = 201
    q = pin.neutral(model)
    q[2] = 0.1
    traj = {"q": np.tile(q, (n, 1)), "tau": np.zeros((n, 1)), "contact_frames": np.array(FEET),
            "contact_points": np.array(["heel", "ball", "toe", "pad"]), "heel_offset": np.zeros(3),
            "pad_offset": np.array([-0.01, 0.0, 0.0]), "friction": np.array(0.5), "tau_min": np.array([-1.0]),
            "tau_max": np.array([1.0])}
    make_result(model, n, trajectory=traj).save(tmp_path / "box")
    out = tmp_path / "sim"
    assert main(["simulate", str(tmp_path / "box"), "--quiet", "--out", str(out), "--sweep-gains", "50", "100"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"landing distance -?0\.000 m \(planned 0\.000 m\)", text), text
    assert "stayed upright; contact slip up to 0.0 mm; torques within their limits" in text
    assert sorted(p.name for p in out.iterdir()) == ["simulation.json", "simulation.npz"]  # no temporary files
    report = json.loads((out / "simulation.json").read_text())
    s = report["summary"]
    assert not s["fell"] and abs(s["landing_distance"]) < 1e-4 and s["torque_excess"]["max"] < 1e-3
    assert report["contact"]["friction"] == 0.5 and report["contact"]["mirror_axes"]["rtoes_end"] == "y"
    assert report["gains"]["kp"] == SIM_KP and [r["kp"] for r in report["sweep"]] == [50.0, 100.0]
    assert not any(r["fell"] for r in report["sweep"])
    with np.load(out / "simulation.npz") as f:
        assert f["q"].shape == (n, model.nq) and f["contact_forces"].shape == (n, 8, 3)
        assert f["contact_forces"][-1, :, 2].sum() == pytest.approx(11.0 * 9.81, rel=1e-3)


def _symmetric_trajectory(model, q0):
    return {"q": q0[None], "contact_frames": np.array(FEET), "contact_points": np.array(["heel", "ball", "toe", "pad"]),
            "heel_offset": np.array([0.004, -0.002, -0.03]), "pad_offset": np.array([0.001, 0.01, -0.001]),
            "toe_offset": np.array([-0.002, 0.003, -0.01])}


def test_the_right_foot_points_mirror_the_left_ones():
    model = _cmu()
    q0 = pin.neutral(model)
    traj = _symmetric_trajectory(model, q0)
    contacts, point, axes = contact_points(traj, model, "r")
    assert axes == {"rfoot": "x", "rfoot_end": "x", "rtoes_end": "x"}  # the CMU frames run along the bones in y
    assert check_mirror(model, q0, contacts) < 1e-9
    assert point is not None and point[0][0] == "ltoes_end" and np.array_equal(point[0][1], traj["toe_offset"])
    left, right = contacts[:4], [f for f, _ in contacts[4:]]
    y_negated = left + [(f, o * np.array([1.0, -1.0, 1.0])) for f, (_, o) in zip(right, left)]
    with pytest.raises(SimulationError, match="rtoes_end.*mirrored left"):
        check_mirror(model, q0, y_negated)
    bent = q0.copy()
    bent[model.idx_qs[model.getJointId("rtibia_rx")]] = 0.3
    with pytest.raises(SimulationError, match="'rfoot' is not the mirror image of 'lfoot'"):
        contact_points(_symmetric_trajectory(model, bent), model, "r")


def test_cli_errors_name_the_input(tmp_path, capsys):
    from result_factory import make_result

    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["simulate", str(empty), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(empty) in err and "result.json" in err
    arm = tmp_path / "arm"
    make_result().save(arm)
    assert main(["simulate", str(arm), "--quiet"]) == 2
    assert f"{arm}: trajectory.npz has no contact data" in capsys.readouterr().err
    bare = tmp_path / "bare"  # result.json without its trajectory
    bare.mkdir()
    (bare / "result.json").write_bytes((arm / "result.json").read_bytes())
    assert main(["simulate", str(bare), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert str(bare) in err and "trajectory.npz" in err
    for bad in (["--kp", "0"], ["--kp", "-5"], ["--sweep-gains", "100", "nan"]):
        assert main(["simulate", str(arm), "--quiet", *bad]) == 2
        assert "must be a positive gain" in capsys.readouterr().err
    assert main(["simulate", str(tmp_path / "missing"), "--quiet"]) == 2
    assert "missing: no such result folder" in capsys.readouterr().err
    assert sorted(p.name for p in arm.iterdir()) == ["result.json", "trajectory.npz"]  # nothing written
