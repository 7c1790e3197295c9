"""The exchange's choice of samples (latentoc.jump.solve.exchange) and the selection it grows
(latentoc.jump.transcription.selection), on analytic slack series."""
import numpy as np
import pytest

from latentoc.jump.solve.exchange import TOLERANCE, violated
from latentoc.nlp.exchange_rounds import worst_times
from latentoc.jump.transcription.selection import Selection


def test_a_stretch_near_its_bound_gets_its_least_slack_and_a_sample_every_spacing():
    """A slack dipping below the margin over 1 kHz samples 106-139: the least slack (at 123) and
    every 5th sample of the grid in the stretch; a two-sample dip also its neighbours 2 ms away."""
    t = np.arange(300)
    slack = np.where((t >= 100) & (t < 140), 0.5 * ((t - 123) / 20.0) ** 2, 1.0)
    slack[250], slack[251] = 0.0, -0.01
    picked = worst_times(slack, slack < 0.4, spacing=5, neighbours=2)
    assert 123 in picked and 251 in picked and 249 in picked and 253 in picked
    inside = picked[(picked >= 100) & (picked < 140)]
    stretch = np.flatnonzero((slack < 0.4) & (t >= 100) & (t < 140))
    assert stretch[0] == 106 and stretch[-1] == 139
    np.testing.assert_array_equal(inside, sorted({123, *range(110, 140, 5)}))
    assert set(picked) <= set(range(100, 140)) | {249, 250, 251, 253}


def test_no_stretch_no_sample():
    assert worst_times(np.ones(50), np.zeros(50, bool), 5, 2).size == 0


@pytest.mark.parametrize("kind, unit", [("torque", TOLERANCE.torque), ("cop", TOLERANCE.cop),
                                        ("zmp", TOLERANCE.polygon), ("tube", TOLERANCE.tube),
                                        ("clearance", TOLERANCE.clearance), ("dynamics", TOLERANCE.dynamics)])
def test_violated_beyond_the_tolerance_only(kind, unit):
    held = {k: 0.0 for k in ("torque", "normal", "friction", "point_cone", "cop", "zmp", "com", "tube", "clearance", "dynamics")}
    assert not violated({**held, kind: 0.9 * unit}) and violated({**held, kind: 1.1 * unit})


def test_selections_merge_by_time_and_row():
    """Samples at the same time (to 1 ns) merge with their rows or-ed; node rows or-ed; the tube
    united; merging what is there already adds nothing."""
    a = Selection(np.zeros((2, 3)), np.zeros((2, 8)), [0.1, 0.2], [[1, 0, 0], [0, 0, 0]], np.zeros((2, 8)),
                  [0.5], [[0, 1, 0]], [0.1])
    b = Selection(np.eye(2, 3), np.zeros((2, 8)), [0.2 + 1e-12, 0.3], [[0, 0, 1], [0, 1, 0]], np.zeros((2, 8)),
                  [], np.zeros((0, 3)), [0.1, 0.2])
    m = a.merged(b)
    np.testing.assert_allclose(m.contact, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(m.contact_torque, [[1, 0, 0], [0, 0, 1], [0, 1, 0]])
    np.testing.assert_array_equal(m.node_torque, np.eye(2, 3))
    np.testing.assert_allclose(m.tube, [0.1, 0.2])
    assert m.rows() == a.rows() + b.rows() - 1  # the tube point at 0.1 is in both
    assert m.merged(a).rows() == m.rows() and len(m.merged(b).contact) == 3
    with pytest.raises(ValueError, match="2 rows for 1 contact samples"):
        Selection(np.zeros((2, 3)), np.zeros((2, 8)), [0.1], np.zeros((2, 3)), np.zeros((1, 8)), [], np.zeros((0, 3)), [])


def test_clearance_on_the_1khz_grid_is_the_height_rows_slack(small_jump):
    """The 1 kHz clearance (latentoc.jump.solve.exchange.clearance, numeric Pinocchio on the export) equals,
    at every contact sample, the slack of that sample's height rows in the NLP (CasADi), point by
    point; it is NaN in flight and for the loaded points, whose placement the closure holds: on the
    export they stay at their standing height to 1e-9 m."""
    from latentoc.jump.robot.feet import POINTS
    from latentoc.jump.solve.exchange import clearance
    from latentoc.jump.check.export import trajectory
    from latentoc.jump.check.verify import series

    sj = small_jump
    jn, ph, x = sj.nlp, sj.js.phases, np.asarray(sj.x0, float)
    traj = trajectory(sj.robot, sj.layer, ph, jn, x)
    sr = series(sj.js.model, traj, sj.robot.mu)
    slack = clearance(sr, traj, sj.robot, ph)
    t = np.asarray(traj["t"])
    contact = np.asarray(traj["contact"]).astype(bool)
    assert np.isnan(slack[~contact]).all()
    fp = sj.robot.geom.footprint
    for k, p in enumerate(POINTS):
        on = ph.loaded(p, t) & contact
        assert np.isnan(slack[on, k]).all()
        if p in ("toe", "pad"):  # on the planted toes
            np.testing.assert_allclose(sr["points"][on, k, 2], fp[2, k], atol=1e-9)
    g = jn.nlp.constraints(x)
    names, times, comps = jn.row_names, jn.row_times, jn.row_components
    checked = 0
    for tk in jn.selection.contact:
        i = int(np.argmin(np.abs(t - tk)))
        assert abs(t[i] - tk) < 1e-9
        rows = np.flatnonzero(np.isclose(times, tk, atol=1e-12) & (names == "height"))
        np.testing.assert_allclose(slack[i, comps[rows]], g[rows], atol=1e-9)
        assert np.isnan(np.delete(slack[i], comps[rows])).all()
        checked += len(rows)
    assert checked > 0
