"""New start poses (Sect. 4.1.4): boundary points on the tube, distances of Eq. 31-32."""

import numpy as np
import pinocchio as pin
import pytest

from latentoc.problem.toml_files import load_problem
from latentoc.robots import load_robot
from latentoc.min_torque.training import problem_gpdm
from latentoc.min_torque.start_poses import radial_direction, start_pose_distances, tube_boundary_point


@pytest.fixture(scope="module")
def gp():
    return problem_gpdm(load_problem("arm-raise-small"))[0]


def test_boundary_point_has_sigma2_delta(gp):
    x0 = gp.X[0]
    u = radial_direction(gp)
    assert np.isclose(np.linalg.norm(u), 1.0)
    tangent = gp.X[1] - gp.X[0]
    assert abs(u @ tangent) / np.linalg.norm(tangent) < 1e-9  # k = len // 20 = 1 for 30 frames
    for delta in gp.variance(x0) * np.array([1.5, 3.0, 10.0]):  # sigma^2 <= 1 + noise (beta_1 = 1)
        x, r = tube_boundary_point(gp, x0, u, delta)
        assert r > 0 and np.isclose(gp.variance(x), delta, rtol=1e-6)


def test_distances_grow_with_tube_and_match_fk(gp):
    model = load_robot("human-arm")
    deltas = list(gp.variance(gp.X[0]) * np.array([1.2, 2.0, 5.0, 20.0]))
    rows = start_pose_distances(gp, model, "lhand_end", deltas)
    trans = [r["translational_distance"] for r in rows]
    assert all(b > a for a, b in zip(trans, trans[1:]))
    data, fid = model.createData(), model.getFrameId("lhand_end")
    pin.framesForwardKinematics(model, data, gp.mean(gp.X[0]))
    M0 = data.oMf[fid].copy()
    pin.framesForwardKinematics(model, data, np.array(rows[-1]["q"]))
    M = data.oMf[fid]
    assert np.isclose(rows[-1]["translational_distance"], np.linalg.norm(M.translation - M0.translation))
    rot = np.linalg.norm(pin.log3(M0.rotation.T @ M.rotation))
    assert np.isclose(rows[-1]["pose_distance"], rot + rows[-1]["translational_distance"])


def test_unknown_frame(gp):
    with pytest.raises(ValueError, match="no frame"):
        start_pose_distances(gp, load_robot("human-arm"), "nose", [0.01])
