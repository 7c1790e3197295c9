"""AMC frames -> humanoid configurations: exact angles, root pose, no IK."""
import numpy as np
import pinocchio as pin

from latentoc.robots.human_models import build_cmu_humanoid, cmu_configurations, cmu_motion, cmu_skeleton
from latentoc.mocap.skeleton_model import joint_q_index


def test_every_joint_is_the_amc_value_in_radians():
    m = build_cmu_humanoid()
    skel, mo = cmu_skeleton(), cmu_motion()
    frames = np.arange(0, 2751, 97)
    Q = cmu_configurations(m, frames)
    assert Q.shape == (len(frames), m.nq) == (len(frames), 63)
    jq = joint_q_index(m)
    assert len(jq) == 56
    for bn, b in skel.bones.items():
        for k, d in enumerate(b.dof):
            assert np.array_equal(Q[:, jq[f"{bn}_{d}"]], np.deg2rad(mo[bn][frames, k]))


def test_root_pose():
    m = build_cmu_humanoid()
    mo = cmu_motion()
    q = cmu_configurations(m, [0])[0]
    tx, ty, tz, rx, ry, rz = mo["root"][0]
    u = 0.0254 / 0.45
    assert np.allclose(q[:3], np.array([tz, tx, ty]) * u)  # world = (asf z, asf x, asf y)
    R = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
    # world-axes rotations: asf X -> world y, asf Y -> world z, asf Z -> world x
    Rref = pin.utils.rotate("x", np.radians(rz)) @ pin.utils.rotate("z", np.radians(ry)) \
        @ pin.utils.rotate("y", np.radians(rx))
    assert np.allclose(R, Rref)
    # upright: the subject's up axis stays close to world z while standing
    assert R[2, 2] > 0.95
