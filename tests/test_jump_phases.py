"""Phase timing of the symmetric training jump (Sect. 4.2: 1.3 s), checked against the data."""
import numpy as np

from latentoc.jump.phases import toe_heights, training_phases
from latentoc.mocap.jumps import detect_jumps
from latentoc.jump.training import jump_model, training_jumps


def test_phases_and_grid():
    model, smap = jump_model()
    tr = training_jumps()[0]
    ph = training_phases(model, tr)
    assert np.isclose(ph.duration, 1.3)
    # toe-off: the toe tip's lowest point just before the feet leave (detected 0.350 s), after
    # which it only rises; touchdown: the toe tip back at its standing height
    j = detect_jumps(model, tr.Q)[0]
    z = toe_heights(model, tr.Q)
    i0, i1 = int(np.argmin(np.abs(tr.t - ph.takeoff))), int(np.argmin(np.abs(tr.t - ph.touchdown)))
    assert tr.t[j.takeoff] - 0.1 <= ph.takeoff < tr.t[j.takeoff] and 0.29 < ph.takeoff < 0.33
    assert np.all(np.diff(z[i0:j.takeoff + 1]) > 0) and z[i0] <= z[i0 - 1]
    assert z[i1] <= z[0] < z[i1 - 1] and i1 >= j.touchdown
    assert 0.25 < ph.touchdown - ph.takeoff < 0.45 and ph.touchdown < ph.settle < ph.duration
    g = ph.grid(5, 4, 6)
    assert g["stance"][-1] == g["flight"][0] and g["flight"][-1] == g["land"][0]
    assert smap.n_learned == 37 and tr.Y.shape == (157, 37)
