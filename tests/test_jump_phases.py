"""Phase timing of the symmetric training jump (Sect. 4.2: 1.3 s, takeoff after 0.35 s)."""
import numpy as np

from latentoc.jump.phases import training_phases
from latentoc.jump.training import jump_model, training_jumps


def test_phases_and_grid():
    model, smap = jump_model()
    tr = training_jumps()[0]
    ph = training_phases(model, tr)
    assert np.isclose(ph.duration, 1.3) and np.isclose(ph.takeoff, 0.35, atol=0.02)
    assert 0.25 < ph.touchdown - ph.takeoff < 0.45 and ph.touchdown < ph.settle < ph.duration
    g = ph.grid(5, 4, 6)
    assert g["stance"][-1] == g["flight"][0] and g["flight"][-1] == g["land"][0]
    assert smap.n_learned == 37 and tr.Y.shape == (157, 37)
