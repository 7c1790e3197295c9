"""Retargeting a demonstration to another robot (latentoc.motions.retargeting, `latentoc retarget`)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from latentoc.motions.readers import read_npz
from latentoc.motions.retarget_map import load_retarget_map
from latentoc.motions.retargeting import Keypoint, RetargetError, _Frame, frame_id, retarget
from latentoc.robots.catalog import load_robot

ROOT = Path(__file__).resolve().parents[1]
G1_MAP = ROOT / "robots" / "g1" / "cmu-retarget.toml"


def _g1_motion(n: int = 15) -> tuple[pin.Model, np.ndarray, np.ndarray]:
    """A smooth G1 motion inside its joint limits, its base moving and turning."""
    g = load_robot("g1")
    rng = np.random.default_rng(3)
    lo, hi = g.lowerPositionLimit[7:], g.upperPositionLimit[7:]
    ph = rng.uniform(0, 2 * np.pi, len(lo))
    t = np.linspace(0.0, 1.0, n)
    Q = np.zeros((n, g.nq))
    for i, s in enumerate(t):
        Q[i] = pin.neutral(g)
        Q[i, 7:] = (lo + hi) / 2 + 0.3 * (hi - lo) / 2 * np.sin(2 * np.pi * s + ph)
        Q[i, :3] = [0.3 * s, 0.05 * np.sin(s), 0.75 + 0.05 * s]
        Q[i, 3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(0.1 * s, 0.2 * s, 0.3 * s)).coeffs()
    return g, t, Q


def test_a_robot_retargeted_onto_itself_is_recovered_exactly():
    """Every body frame of the G1 followed by the same frame of the G1 at scale 1: the keypoints can
    match exactly, so the residual is zero and the configurations are the source's."""
    g, t, Q = _g1_motion()
    bodies = [f.name for f in g.frames if f.type == pin.FrameType.BODY]
    kps = [Keypoint(n, n, n, orientation=1.0) for n in bodies]
    r = retarget(g, Q, t, g, kps, rest_source=pin.neutral(g), rest_target=pin.neutral(g))
    assert max(m for _, m in r.residual_mm.values()) < 1e-6
    assert max(m for _, m in r.residual_deg.values()) < 1e-6
    assert max(np.abs(pin.difference(g, a, b)).max() for a, b in zip(Q, r.Q)) < 1e-8
    # played 20 times as fast, some joints pass their URDF velocity limits: the report names exactly those
    fast = retarget(g, Q, t / 20, g, kps, rest_source=pin.neutral(g), rest_target=pin.neutral(g))
    speed = np.abs(np.gradient(Q[:, 7:], t / 20, axis=0)).max(axis=0) / g.velocityLimit[6:]
    names = list(g.names)[2:]
    assert fast.too_fast.keys() == {n for n, s in zip(names, speed) if s > 1} and fast.too_fast
    assert all(np.isclose(fast.too_fast[n], s, rtol=1e-6) for n, s in zip(names, speed) if s > 1)
    assert not r.too_fast


def test_the_frame_jacobian_matches_finite_differences():
    g, t, Q = _g1_motion(2)
    kps = [Keypoint("toe", "left_ankle_roll_link", "left_ankle_roll_link", offset=(0.13, 0.0, -0.035),
                    weight=2.0, orientation=0.5, height=0.0),
           Keypoint("hand", "right_wrist_yaw_link", "right_wrist_yaw_link", orientation=1.0)]
    fids = [frame_id(g, k.target, k.name) for k in kps]
    frame = _Frame(g, kps, fids)
    rng = np.random.default_rng(0)
    R = [pin.rpy.rpyToMatrix(*rng.normal(size=3)) for _ in kps]
    P = rng.normal(size=(2, 3)) * 0.1 + [[0, 0, 0.5], [0, 0, 0.8]]  # the toe's target below: its ground row binds
    frame.set(Q[1], P, R, np.array([2.0, 1.0]), np.array([0.5, 1.0]), 1e-3)
    dv = rng.normal(size=g.nv) * 0.05
    J = frame.jacobian(dv)
    h = 1e-6
    fd = np.column_stack([(frame.residuals(dv + h * e) - frame.residuals(dv - h * e)) / (2 * h) for e in np.eye(g.nv)])
    assert np.allclose(J, fd, atol=1e-5)


def test_cmu_jump_on_the_g1_keeps_limits_ground_and_planted_feet():
    """The stance of the CMU jump on the G1 with the shipped map: every joint inside the URDF's limits,
    no foot point below the ground, the planted toe points still (to the residual) while planted."""
    from latentoc.jump.demonstration.training import training_jumps

    spec = load_retarget_map(G1_MAP)
    source, g = load_robot(spec.source), load_robot(spec.target)
    tr = training_jumps(0)[0]
    sl = slice(0, 40)  # the crouch and push-off
    r = retarget(source, tr.Q[sl], tr.t[sl], g, spec.keypoints, scale=0.8, rise=spec.rise, speed=spec.speed)
    lo, hi = g.lowerPositionLimit[7:], g.upperPositionLimit[7:]
    assert np.all(r.Q[:, 7:] >= lo - 1e-9) and np.all(r.Q[:, 7:] <= hi + 1e-9)
    d = g.createData()
    toe = {}
    for side in ("left", "right"):
        fid = g.getFrameId(f"{side}_ankle_roll_link")
        pts = []
        for q in r.Q:
            pin.framesForwardKinematics(g, d, q)
            pts.append(d.oMf[fid].act(np.array([0.13, 0.0, -0.035])))
        toe[side] = np.array(pts)
        assert toe[side][:, 2].min() > -5e-4
        on = r.planted[f"{side}_toe"]
        assert on.sum() >= 10
        held = toe[side][on]
        assert np.ptp(held[:, :2], axis=0).max() < 0.0015  # still to 1.5 mm while planted (1.0 measured)
    assert r.scale == 0.8


def _write(tmp_path: Path, text: str) -> Path:
    p = tmp_path / "map.toml"
    p.write_text(text)
    return p


GOOD = '''source = "g1"
target = "g1"
scale = 1.0
[keypoints.pelvis]
source = "pelvis"
target = "pelvis"
'''


@pytest.mark.parametrize("text, key", [
    (GOOD.replace('target = "g1"\n', ""), "target: missing"),
    (GOOD + 'parent = "nowhere"\n', "keypoints.pelvis.parent: no keypoint named 'nowhere'"),
    (GOOD + 'offset = [1, 2]\n', "keypoints.pelvis.offset"),
    (GOOD + 'weight = -1\n', "keypoints.pelvis.weight"),
    (GOOD + 'colour = 1\n', "keypoints.pelvis: unknown key 'colour'"),
    (GOOD.replace("scale = 1.0\n", ""), "scale_chain"),
    (GOOD + '[keypoints.a]\nsource = "pelvis"\ntarget = "pelvis"\nparent = "b"\n'
            '[keypoints.b]\nsource = "pelvis"\ntarget = "pelvis"\nparent = "a"\n', "cycle"),
    (GOOD.replace('target = "pelvis"', 'target = "left_wing"'), "keypoints.pelvis"),
])
def test_a_bad_keypoint_map_is_refused_naming_the_key(tmp_path, text, key):
    g, t, Q = _g1_motion(2)
    with pytest.raises(RetargetError, match=key.replace("[", r"\[").replace("(", r"\(")):
        spec = load_retarget_map(_write(tmp_path, text))
        retarget(g, Q, t, g, spec.keypoints, scale=1.0)


@pytest.mark.slow  # a subprocess
def test_cli_writes_a_motion_the_readers_take_and_refuses_bad_input(tmp_path):
    g, t, Q = _g1_motion(4)
    src = tmp_path / "g1.npz"
    np.savez(src, t=t, q=Q)
    good = _write(tmp_path, GOOD)
    out = tmp_path / "out.npz"
    run = [sys.executable, "-m", "latentoc", "retarget", str(good), "--motion", str(src), "--out", str(out)]
    p = subprocess.run(run, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    raw = read_npz(out)
    assert raw.values.shape == (4, g.nq) and raw.names is None
    assert np.allclose(raw.values[:, :3], Q[:, :3], atol=1e-9)  # the pelvis, followed exactly
    bad = tmp_path / "bad.npz"
    p = subprocess.run(run[:4] + [str(_write(tmp_path, GOOD + "parent = 'x'\n")), "--motion", str(src), "--out", str(bad)],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "keypoints.pelvis.parent" in p.stderr and "Traceback" not in p.stderr
    assert not bad.exists()
