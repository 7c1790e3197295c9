"""The motions `bench gpdm` times learning on (issue 52): the data each builds, and the minima the learner
reaches on them against the values recorded with the saddle-free learner (MINIMA)."""

import numpy as np
import pytest

from latentoc.benchmarks.gpdm_motions import MINIMA, MOTIONS, SAME_RTOL, benchmark_motion, same_minimum
from latentoc.gpdm import GPDMSettings, learn_gpdm


@pytest.mark.parametrize("name", sorted(MOTIONS))
def test_each_motion_is_350_by_37_and_the_same_every_time(name):
    Y = benchmark_motion(name)
    assert Y.shape == (350, 37) and np.all(np.isfinite(Y))
    np.testing.assert_array_equal(Y, benchmark_motion(name))  # fixed seeds, no state between calls


def test_the_same_minimum_tells_the_learners_scatter_from_another_minimum():
    # the saddle-free learner from starts perturbed by 1e-10: the walk within 7.8e-5 of its recorded value;
    # the jump's nearest other minimum measured, -185786.005653 (docs/gpdm.md)
    assert same_minimum(MINIMA["walk"] - 7.8e-5, MINIMA["walk"]) and same_minimum(MINIMA["walk"] + 7.8e-5, MINIMA["walk"])
    assert not same_minimum(-185786.005653, MINIMA["jump"])
    assert not same_minimum(-75505.35, -75504.441749048)  # the broad jump's set: its two closest minima
    ref = MINIMA["jump"]
    assert same_minimum(ref + 0.9 * SAME_RTOL * abs(ref), ref) and not same_minimum(ref + 1.1 * SAME_RTOL * abs(ref), ref)
    assert set(MINIMA) == set(MOTIONS)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["loops", "synthetic"])
def test_learning_ends_in_the_recorded_minimum(name):
    """The two quickest motions (2-4 s each) learned again end where the saddle-free learner did."""
    model = learn_gpdm(benchmark_motion(name), GPDMSettings())
    assert model.learning.converged
    assert same_minimum(model.objective_value, MINIMA[name]), (model.objective_value, MINIMA[name])
