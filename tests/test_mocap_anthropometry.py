"""de Leva (1996) anthropometry mapped onto the CMU bones."""
import numpy as np
import pytest

from latentoc.robots.human_models import build_cmu_humanoid, cmu_skeleton
from latentoc.mocap.anthropometry import BONE_MAP, DE_LEVA_MALE, BILATERAL, cmu_inertias, de_leva_segments


def test_table_sums_to_100_percent():
    total = sum(v[0] for v in DE_LEVA_MALE.values()) + sum(DE_LEVA_MALE[k][0] for k in BILATERAL)
    assert np.isclose(total, 100.0)


def test_every_bone_mapped_and_shares_sum_to_one():
    skel = cmu_skeleton()
    assert set(BONE_MAP) == {"root", *skel.bones}
    shares: dict = {}
    for bn, (seg, share) in BONE_MAP.items():
        key = seg if seg not in BILATERAL else (seg, bn[0])
        shares[key] = shares.get(key, 0.0) + share
    assert all(np.isclose(v, 1.0) for v in shares.values()), shares


@pytest.mark.parametrize("mass,height", [(63.86, 1.75), (80.0, 1.9)])
def test_humanoid_mass_and_inertias(mass, height):
    m = build_cmu_humanoid(mass, height)
    assert abs(sum(I.mass for I in m.inertias) - mass) < 1e-12
    for j in range(1, m.njoints):
        I = m.inertias[j]
        if I.mass > 0:
            assert np.all(np.linalg.eigvalsh(I.inertia) > 0)
    # every bone carries mass: the 56 revolute chains end in massive bodies
    skel = cmu_skeleton()
    root, ins = cmu_inertias(skel, mass, height)
    assert root.mass > 0 and all(I.mass > 0 for I in ins.values())


def test_scaling_with_height_and_mass():
    a, b = de_leva_segments(60, 1.7), de_leva_segments(120, 3.4)
    assert np.isclose(b["thigh"].mass, 2 * a["thigh"].mass)
    assert np.isclose(b["thigh"].length, 2 * a["thigh"].length)
    assert np.isclose(de_leva_segments(100, 1.741)["thigh"].length, 0.4222)


def test_mass_matrix_positive_definite_on_data():
    import pinocchio as pin

    from latentoc.robots.human_models import cmu_configurations
    m = build_cmu_humanoid()
    d = m.createData()
    for q in cmu_configurations(m, slice(0, 2751, 500)):
        M = pin.crba(m, d, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert np.linalg.eigvalsh(M).min() > 0
        assert np.isclose(M[0, 0], 63.86)  # base translational block = total mass
