"""Mirroring map for symmetric learning (paper Sect. 4.2), verified by forward kinematics."""
import numpy as np
import pinocchio as pin
import pytest

from latentoc.robots.human_models import build_cmu_humanoid, cmu_configurations, cmu_skeleton
from latentoc.mocap.skeleton_model import build_model
from latentoc.mocap.symmetry import SymmetryMap, mirror_partner, symmetrized_skeleton

S = np.diag([1.0, -1.0, 1.0])  # world sagittal reflection (y is left)


def _random_q(model, rng, n):
    lo = np.where(np.isfinite(model.lowerPositionLimit), model.lowerPositionLimit, -1)
    hi = np.where(np.isfinite(model.upperPositionLimit), model.upperPositionLimit, 1)
    Q = rng.uniform(lo, hi, size=(n, model.nq))
    for q in Q:
        quat = pin.Quaternion(rng.normal(size=4)).normalized()
        q[3:7] = quat.coeffs()
    return Q


def _ends(model, skel, q):
    d = model.createData()
    pin.framesForwardKinematics(model, d, q)
    return {b: d.oMf[model.getFrameId(b + "_end")].translation.copy() for b in skel.bones}


@pytest.fixture(scope="module")
def sym():
    skel = symmetrized_skeleton(cmu_skeleton())
    model = build_model(skel)
    return skel, model, SymmetryMap(model, skel)


def test_learned_dof_count():
    m = build_cmu_humanoid()
    sm = SymmetryMap(m, cmu_skeleton())
    assert sm.n_learned == 37 and len(sm.copied) == 19  # 62 - 19 - 6
    assert all(n.startswith("l") or n.split("_")[0] in
               {"lowerback", "upperback", "thorax", "lowerneck", "upperneck", "head"}
               for n in sm.learned_names)


def test_round_trips():
    m = build_cmu_humanoid()
    sm = SymmetryMap(m, cmu_skeleton())
    Q = cmu_configurations(m, slice(0, 2751, 50))
    Y = sm.to_learned(Q)
    assert Y.shape == (len(Q), 37)
    assert np.array_equal(sm.to_learned(sm.to_full(Y, Q[:, :7])), Y)
    Qs = sm.to_full(Y, Q[:, :7])
    assert np.array_equal(sm.to_full(sm.to_learned(Qs), Qs[:, :7]), Qs)
    assert np.allclose(sm.mirror(sm.mirror(Q)), Q)


def test_mirror_is_reflection_by_fk(sym):
    """FK(mirror(q)) = S * FK(q) with left and right bones swapped (symmetric geometry)."""
    skel, model, sm = sym
    rng = np.random.default_rng(0)
    for q in _random_q(model, rng, 10):
        a, b = _ends(model, skel, q), _ends(model, skel, sm.mirror(q))
        for bone in skel.bones:
            other = mirror_partner(bone, skel) or bone
            assert np.allclose(b[other], S @ a[bone], atol=1e-9), bone


def _symmetric_pose(model, sm, rng):
    q = _random_q(model, rng, 1)[0]
    y = sm.to_learned(q)
    for k, n in enumerate(sm.learned_names):  # centre joints: only the sagittal rx
        if sm.centre_factor.get(n, 1.0) < 0:
            y[k] = 0.0
    base = np.array([0.3, 0.0, 0.9, *pin.Quaternion(pin.utils.rotate("y", 0.2)).coeffs()])
    return sm.to_full(y, base)


def test_symmetric_pose_has_mirror_feet(sym):
    skel, model, sm = sym
    rng = np.random.default_rng(1)
    for _ in range(5):
        e = _ends(model, skel, _symmetric_pose(model, sm, rng))
        for b in ("toes", "foot", "tibia", "hand", "radius"):
            assert np.allclose(S @ e["l" + b], e["r" + b], atol=1e-9)


def test_symmetric_pose_on_real_skeleton_nearly_mirror():
    """The real CMU geometry is slightly asymmetric (bone lengths differ by up to 3 cm)."""
    skel = cmu_skeleton()
    m = build_model(skel)
    sm = SymmetryMap(m, skel)
    rng = np.random.default_rng(2)
    for _ in range(5):
        e = _ends(m, skel, _symmetric_pose(m, sm, rng))
        assert np.linalg.norm(S @ e["ltoes"] - e["rtoes"]) < 0.08
