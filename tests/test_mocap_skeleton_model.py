"""Pinocchio model built from the CMU ASF against an independent Acclaim FK in numpy."""
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from latentoc.mocap import read_amc, read_asf
from latentoc.mocap.configurations import motion_to_q
from latentoc.mocap.skeleton_model import body_frame_names, build_model

DATA = Path(__file__).resolve().parents[1] / "robots" / "cmu"
INCH = 0.0254


@pytest.fixture(scope="module")
def skel():
    return read_asf(DATA / "01.asf")


@pytest.fixture(scope="module")
def motion(skel):
    return read_amc(DATA / "01_01.amc", skel)


def _rot(axis, a):
    c, s = np.cos(a), np.sin(a)
    return {"X": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "Y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "Z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis.upper()]


def _euler(vals_deg, letters):
    """Compose rotations, first letter applied first (column vectors)."""
    R = np.eye(3)
    for v, l in zip(vals_deg, letters):
        R = _rot(l, np.radians(v)) @ R
    return R


def acclaim_fk(skel, motion, i):
    """Bone end positions in ASF axes (metres), straight from the Acclaim definitions."""
    u = INCH / skel.length_unit
    root = dict(zip(skel.root.order, motion["root"][i]))
    Cr = _euler([skel.root.orientation["XYZ".index(c)] for c in skel.root.axis], skel.root.axis)
    Mr = _euler([root["R" + c] for c in skel.root.axis], skel.root.axis)
    G = {"root": Cr @ Mr @ Cr.T}
    end = {"root": (skel.root.position + np.array([root["TX"], root["TY"], root["TZ"]])) * u}
    todo = list(skel.hierarchy["root"])
    while todo:
        bn = todo.pop(0)
        b = skel.bones[bn]
        C = _euler([b.axis["XYZ".index(c)] for c in b.axis_order], b.axis_order)
        M = _euler(list(motion[bn][i]), [d[1] for d in b.dof])
        G[bn] = G[b.parent] @ C @ M @ C.T
        end[bn] = end[b.parent] + G[bn] @ b.direction * b.length * u
        todo += skel.hierarchy.get(bn, [])
    return end


def test_sizes(skel):
    m = build_model(skel)
    assert len(body_frame_names(m)) == 31  # root + 30 bones
    n_rev = sum(1 for j in m.joints[1:] if j.nq == 1)
    assert n_rev == 56  # 62 ASF DOF = 6 root + 56 revolute
    assert m.joints[1].shortname() == "JointModelFreeFlyer"
    assert (m.nq, m.nv) == (63, 62)
    assert np.allclose(m.gravity.linear, [0, 0, -9.81])
    for bn in skel.bones:
        assert m.existFrame(bn) and m.existFrame(bn + "_end")


def test_limits_are_asf_limits_in_radians(skel):
    m = build_model(skel)
    j = m.getJointId("lfemur_rx")
    assert np.isclose(m.lowerPositionLimit[m.joints[j].idx_q], np.radians(-160))
    assert np.isclose(m.upperPositionLimit[m.joints[j].idx_q], np.radians(20))


def test_fk_matches_acclaim(skel, motion):
    m = build_model(skel)
    d = m.createData()
    P = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]])
    frames = np.linspace(0, motion.n_frames - 1, 50).astype(int)
    Q = motion_to_q(m, skel, motion, frames)
    worst = 0.0
    for q, i in zip(Q, frames):
        ref = acclaim_fk(skel, motion, i)
        pin.framesForwardKinematics(m, d, q)
        for bn in skel.bones:
            p = d.oMf[m.getFrameId(bn + "_end")].translation
            worst = max(worst, np.abs(p - P @ ref[bn]).max())
        assert np.allclose(d.oMf[m.getFrameId("root", pin.FrameType.BODY)].translation, P @ ref["root"], atol=1e-12)
    assert worst < 1e-9


def test_q_equals_amc_values(skel, motion):
    m = build_model(skel)
    Q = motion_to_q(m, skel, motion, slice(0, 5))
    j = m.getJointId("ltibia_rx")
    assert np.allclose(Q[:, m.joints[j].idx_q], np.radians(motion["ltibia"][:5, 0]), rtol=0, atol=0)
    j = m.getJointId("lhumerus_ry")
    assert np.allclose(Q[:, m.joints[j].idx_q], np.radians(motion["lhumerus"][:5, 1]), rtol=0, atol=0)
    assert np.allclose(np.linalg.norm(Q[:, 3:7], axis=1), 1.0)


def test_joint_limit_violations_in_data(skel, motion):
    """Report (not hide) how far the take leaves the ASF limits."""
    report = []
    for bn, b in skel.bones.items():
        for k, (d, (lo, hi)) in enumerate(zip(b.dof, b.limits)):
            v = motion[bn][:, k]
            over = max(0.0, v.max() - hi, lo - v.min())
            if over > 1e-6:
                n = int(np.sum((v > hi) | (v < lo)))
                report.append((f"{bn}_{d}", round(over, 2), n))
    print("\nASF limit violations in 01_01 (joint, worst excess deg, frames):")
    for r in sorted(report, key=lambda r: -r[1]):
        print("  ", r)
    # Found in 01_01: the wrists (lwrist_ry positive in almost every frame, up to 31 deg;
    # rwrist_ry up to 39 deg), rthumb_rz (20 deg), toes, feet, neck, head, lhumerus rx/rz
    # leave their ASF limits.  Legs' main joints and the back stay inside.
    names = {r[0] for r in report}
    assert all(r[1] < 45.0 for r in report), report
    for j in ("lfemur_rx", "rfemur_rx", "ltibia_rx", "rtibia_rx", "lowerback_rx", "thorax_rx"):
        assert j not in names
    assert names <= {"lwrist_ry", "rwrist_ry", "rthumb_rz", "lthumb_rz", "lthumb_rx", "rthumb_rx",
                     "ltoes_rx", "rtoes_rx", "lfoot_rz", "rfoot_rz", "lfoot_rx", "rfoot_rx",
                     "upperneck_rx", "upperneck_ry", "upperneck_rz", "lowerneck_rx", "lowerneck_ry",
                     "lowerneck_rz", "head_rx", "head_ry", "head_rz", "lhumerus_rx", "lhumerus_rz",
                     "rhumerus_rx", "rhumerus_rz", "lhand_rx", "rhand_rx", "lhand_rz", "rhand_rz"}, names
