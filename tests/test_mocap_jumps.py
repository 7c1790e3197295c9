"""Jump phase detection on take 01_01 against the frames listed in the data README."""
import numpy as np
import pytest

from latentoc.robots.human_models import (broad_jump_sequences, broad_jump_training_motion,
                                          build_cmu_humanoid, cmu_configurations)
from latentoc.mocap.jumps import detect_jumps

README_FLIGHT_STARTS = [230, 432, 597, 786, 1289, 1551, 1780, 2218, 2434, 2636]


@pytest.fixture(scope="module")
def jumps():
    m = build_cmu_humanoid()
    return detect_jumps(m, cmu_configurations(m))


def test_every_jump_found(jumps):
    print("\ndetected:", [(j.start_still, j.takeoff, j.touchdown, j.end_still, round(j.distance, 2))
                          for j in jumps])
    assert len(jumps) == 10
    for j, ref in zip(jumps, README_FLIGHT_STARTS):
        assert abs(j.takeoff - ref) <= 5


def test_phases_plausible(jumps):
    for j in jumps:
        assert j.start_still < j.takeoff < j.touchdown < j.end_still
        assert 0.2 < j.flight_time < 0.5
        assert 0.6 < j.distance < 1.3  # README: about 0.7-1.1 m
        assert 1.0 < (j.end_still - j.start_still) / 120 < 1.7  # README: 1.3-1.5 s


def test_training_motion():
    t, Q = broad_jump_training_motion()
    assert Q.shape == (157, 63) and t.shape == (157,)
    assert np.isclose(t[-1], 1.3) and np.allclose(np.diff(t), 1 / 120)
    seqs = broad_jump_sequences()
    assert len(seqs) == 10
    # the body travels forward during the jump (facing roughly along its heading)
    d = Q[-1, :2] - Q[0, :2]
    assert 0.6 < np.linalg.norm(d) < 1.3
    # mid-window the feet are in the air: root is higher than at the start
    assert Q[:, 2].max() > Q[0, 2] + 0.1
