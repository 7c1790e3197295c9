"""End to end from a user-made CSV on the UR5 (the worked example is the Panda): `learn`, `solve` with the
learned model, then the exported 1 kHz motion against independent numbers: its torques from numeric
pinocchio.rnea on the robot loaded by name, its end poses against the demonstration, the URDF's joint,
velocity and torque limits, the tube, and its cost against the demonstration's own cost from the
analytic motion the CSV was sampled from. The energy objective and an end-effector goal likewise."""
import json

import numpy as np
import pinocchio as pin
import pytest

from latentoc.cli.parser import main
from latentoc.gpdm import GPDM
from latentoc.results import load_result
from latentoc.robots import load_robot

pytestmark = pytest.mark.slow

UR5 = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]
T = 2.0
Q0 = np.array([0.0, -1.8, 1.6, -1.4, -1.57, 0.0])
Q1 = np.array([1.2, -1.0, 1.0, -1.6, -1.2, 0.8])
DETOUR = np.array([0.3, -0.4, 0.5, 0.3, 0.3, -0.4])


def demonstration(t: np.ndarray, r: int = 0) -> np.ndarray:
    """The reach the user recorded and its r-th time derivative: a minimum-jerk blend from Q0 to Q1 plus a
    detour bump, both at rest at the ends."""
    u = np.asarray(t) / T
    s = [10 * u ** 3 - 15 * u ** 4 + 6 * u ** 5, 30 * u ** 2 * (1 - u) ** 2, 60 * u * (1 - u) * (1 - 2 * u)][r]
    b = [64 * u ** 3 * (1 - u) ** 3, 192 * u ** 2 * (1 - u) ** 2 * (1 - 2 * u),
         384 * u * (1 - u) * (1 - 5 * u + 5 * u ** 2)][r]
    return (Q0 if r == 0 else 0) + (np.outer(s, Q1 - Q0) + np.outer(b, DETOUR)) / T ** r


def demonstration_costs(model: pin.Model, n: int = 2001) -> dict[str, float]:
    """int |tau|^2 dt and int sqrt((tau . qd)^2 + eps^2) - eps dt (eps 0.1) of the analytic reach (trapezoid)."""
    t = np.linspace(0.0, T, n)
    data = model.createData()
    q, v, a = (demonstration(t, r) for r in range(3))
    tau = np.array([pin.rnea(model, data, *x) for x in zip(q, v, a)])
    p = np.sum(tau * v, axis=1)
    return {"torque": float(np.trapezoid(np.sum(tau * tau, axis=1), t)),
            "energy": float(np.trapezoid(np.sqrt(p * p + 0.01) - 0.1, t))}


PROBLEM = """kind = "latent-min-torque"
robot = "ur5"
training = {{ file = "recording.csv", rate = 50.0 }}
[latent]
dim = 3
control_points = 9
tube = "20x"
[objective]
cost = "{cost}"
[transcription]
velocity_limits = true
torque_limits = "urdf"
[gpdm]
training_stride = 2
{extra}"""


@pytest.fixture(scope="module")
def user(tmp_path_factory):
    """The user's folder: a recording at about 50 Hz with jittered time stamps, columns in their own order."""
    d = tmp_path_factory.mktemp("ur5-user")
    t = np.linspace(0.0, T, 101)
    stamps = t + np.r_[0.0, np.random.default_rng(3).uniform(-2e-3, 2e-3, 99), 0.0]
    Q = demonstration(stamps)
    order = [2, 0, 5, 1, 4, 3]
    rows = [",".join([UR5[i] for i in order] + ["t"])]
    rows += [",".join(f"{v:.12g}" for v in (*q[order], s)) for q, s in zip(Q, stamps)]
    (d / "recording.csv").write_text("\n".join(rows) + "\n")
    assert main(["learn", str(d / "recording.csv"), "--robot", "ur5", "--rate", "50", "--stride", "2",
                 "--out", str(d / "learned")]) == 0
    return d


def solve(user, name: str, cost: str = "torque", extra: str = "", gpdm: bool = True):
    (user / f"{name}.toml").write_text(PROBLEM.format(cost=cost, extra=extra))
    args = ["solve", str(user / f"{name}.toml"), "--out", str(user / name), "--quiet"]
    assert main(args + (["--gpdm", str(user / "learned" / "gpdm.npz")] if gpdm else [])) == 0
    return load_result(user / name)


@pytest.fixture(scope="module")
def torque(user):
    return solve(user, "torque")


def test_learn_saw_the_recording_resampled(user):
    summary = json.loads((user / "learned" / "learn.json").read_text())
    assert summary["demonstration"]["resampled"] and summary["demonstration"]["joints"] == UR5
    assert summary["demonstration"]["frames"] == 101 and summary["learned_frames"] == 51


def test_the_torques_are_numeric_rnea_of_the_exported_motion(torque):
    model = load_robot("ur5")
    data = model.createData()
    tr = torque.trajectory
    tau = np.array([pin.rnea(model, data, q, v, a) for q, v, a in zip(tr["q"], tr["v"], tr["a"])])
    assert np.allclose(tr["tau"], tau, rtol=1e-8, atol=1e-8 * np.abs(tau).max())
    assert torque.cost == pytest.approx(np.trapezoid(np.sum(tau * tau, axis=1), tr["t"]), rel=1e-3)


def test_the_end_poses_are_the_demonstrations_and_at_rest(user, torque):
    tr = torque.trajectory
    gp = GPDM.load(user / "learned" / "gpdm.npz")
    # the motion starts and ends on the GP mean of the demonstration's first and last latent points (Eq. 18),
    # which is the demonstration's pose up to the GPDM's reconstruction error there
    assert np.allclose(tr["q"][0], gp.mean(gp.X[0]), rtol=0, atol=1e-9)
    assert np.allclose(tr["q"][-1], gp.mean(gp.X[-1]), rtol=0, atol=1e-9)
    for q, demo in ((tr["q"][0], Q0), (tr["q"][-1], demonstration(np.array([T]))[0])):
        assert np.max(np.abs(q - demo)) < 5e-3  # the converged GPDM's reconstruction error (0.3 deg)
    errors = torque.details["boundary_error_rad"]
    assert errors["start"] == pytest.approx(np.max(np.abs(tr["q"][0] - Q0)), abs=1e-9)
    assert np.allclose(tr["v"][[0, -1]], 0.0, atol=1e-10)


def test_the_limits_and_the_tube_hold_on_the_1khz_grid(user, torque):
    model = load_robot("ur5")
    tr = torque.trajectory
    assert np.allclose(np.diff(tr["t"]), 1e-3) and tr["t"][-1] == pytest.approx(T)
    tol = 1e-6
    assert np.all(tr["q"] >= model.lowerPositionLimit - tol) and np.all(tr["q"] <= model.upperPositionLimit + tol)
    assert np.all(np.abs(tr["v"]) <= model.velocityLimit + tol)
    assert np.all(np.abs(tr["tau"]) <= model.effortLimit + tol)
    gp = GPDM.load(user / "learned" / "gpdm.npz")
    assert np.max(gp.variance(tr["x"])) <= torque.tube.delta * (1 + 1e-6)
    assert set(torque.violations) == {"tube", "joint_limits_rad", "velocity_limits_rad_s", "torque_limits_nm"}
    assert max(torque.violations.values()) <= 1e-6


def test_the_figures_draw_the_urdfs_limits(torque):
    """`plot`'s joint-angle, velocity and torque panels draw each joint's limits as the UR5's URDF
    gives them (read here from the XML, not through pinocchio)."""
    import xml.etree.ElementTree as ET

    from latentoc.plots import LIMIT_STYLE, solution_figures
    from latentoc.robots import example_robot_data_dir

    urdf = ET.parse(example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf").getroot()
    limits = {j.get("name"): {k: float(v) for k, v in j.find("limit").attrib.items()}
              for j in urdf.iter("joint") if j.get("type") == "revolute"}
    figs = solution_figures(torque)

    def drawn(ax):
        return sorted(float(line.get_ydata()[0]) for line in ax.get_lines() if line.get_color() == LIMIT_STYLE["color"])

    for name, scale, keys in (("joint_angles", np.degrees(1.0), ("lower", "upper")),
                              ("joint_velocities", np.degrees(1.0), ("velocity",)),
                              ("torques", 1.0, ("effort",))):
        panels = [ax for ax in figs[name].axes if ax.get_title() in UR5]
        assert sorted(ax.get_title() for ax in panels) == sorted(UR5)
        for ax in panels:
            lim = limits[ax.get_title()]
            expected = [lim["lower"], lim["upper"]] if len(keys) == 2 else [-lim[keys[0]], lim[keys[0]]]
            assert np.allclose(drawn(ax), scale * np.array(sorted(expected)), rtol=1e-12), (name, ax.get_title())


def test_the_cost_is_below_the_demonstrations(torque):
    demo = demonstration_costs(load_robot("ur5"))["torque"]
    assert torque.success and torque.cost < demo
    assert torque.details["objective"] == "torque" and torque.details["robot"] == "ur5"


def test_the_energy_objective(user):
    r = solve(user, "energy", cost="energy")
    tr = r.trajectory
    p = np.sum(tr["tau"] * tr["v"], axis=1)
    energy = np.trapezoid(np.sqrt(p * p + 0.01) - 0.1, tr["t"])
    assert r.success and "mechanical energy" in r.cost_meaning
    assert r.cost == pytest.approx(energy, rel=1e-2)  # |tau . qd| bends sharply where it changes sign
    assert r.cost < demonstration_costs(load_robot("ur5"))["energy"]
    assert max(r.violations.values()) <= 1e-6


@pytest.mark.parametrize("tolerance", [0.005, 0.02])
def test_an_end_effector_goal(user, tolerance):
    model = load_robot("ur5")
    data = model.createData()
    # where the GP mean (Eq. 18) puts the demonstration's frame at 0.85 T: a pose the model reaches inside the tube
    gp = GPDM.load(user / "learned" / "gpdm.npz")
    pin.framesForwardKinematics(model, data, gp.mean(gp.X[int(round(0.85 * (len(gp.X) - 1)))]))
    target = data.oMf[model.getFrameId("tool0")].translation
    extra = f'[goal]\nframe = "tool0"\nposition = {list(map(float, target))}\ntolerance = {tolerance}\n'
    r = solve(user, f"goal-{tolerance}", extra=extra, gpdm=False)
    tr = r.trajectory
    pin.framesForwardKinematics(model, data, tr["q"][-1])
    miss = np.linalg.norm(data.oMf[model.getFrameId("tool0")].translation - target)
    assert r.success and miss <= tolerance + 1e-6
    assert r.violations["goal_m"] <= 1e-6 and np.allclose(tr["v"][-1], 0.0, atol=1e-10)
    assert np.allclose(tr["q"][0], r.gpdm.mean(r.gpdm.X[0]), atol=1e-9)  # the start is still the demonstration's
