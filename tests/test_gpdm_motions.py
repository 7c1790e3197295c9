"""The motions `bench gpdm` times learning on (issue 52): the data each builds, and the minima the learner
reaches on them against the values recorded with the saddle-free learner (MINIMA)."""

import numpy as np
import pytest

from latentoc.benchmarks.gpdm_motions import MINIMA, MOTIONS, benchmark_motion, same_minimum
from latentoc.gpdm import GPDMSettings, learn_gpdm


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_each_motion_is_350_by_37_and_the_same_every_time(name):
    Y = benchmark_motion(name)
    assert Y.shape == (350, 37) and np.all(np.isfinite(Y))
    np.testing.assert_array_equal(Y, benchmark_motion(name))  # fixed seeds, no state between calls


def test_the_same_minimum_is_within_ftol_of_its_value():
    ref = MINIMA["jump"]
    tol = 1e-10 * abs(ref)
    assert same_minimum(ref + 0.9 * tol, ref) and same_minimum(ref - 0.9 * tol, ref)
    assert not same_minimum(ref - 1.1 * tol, ref)
    assert set(MINIMA) == set(MOTIONS)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["loops", "synthetic"])
def test_learning_ends_in_the_recorded_minimum(name):
    """The two quickest motions (2-4 s each) learned again end where the saddle-free learner did."""
    model = learn_gpdm(benchmark_motion(name), GPDMSettings())
    assert model.learning.converged
    assert same_minimum(model.objective_value, MINIMA[name]), (model.objective_value, MINIMA[name])
