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


def test_contact_schedule_follows_the_training_heel_and_ball():
    """The heel and ball carry force only while the training motion has them on the ground:
    checked against their heights recomputed from the frames with numeric Pinocchio."""
    import pinocchio as pin

    from latentoc.jump.contact import FootGeometry, foot_points
    from latentoc.jump.phases import CONTACT_HEIGHT

    model, _ = jump_model()
    tr = training_jumps()[0]
    geom = FootGeometry.from_standing(model, tr.Q[0])
    ph = training_phases(model, tr, geom=geom)
    d = model.createData()
    H = np.array([foot_points(model, d, geom)[2] for q in tr.Q if pin.framesForwardKinematics(model, d, q) is None])
    H -= H[0]
    assert 0 < ph.heel_off < ph.ball_off <= ph.takeoff < ph.touchdown <= ph.ball_strike < ph.heel_strike < ph.duration
    for k, (off, strike) in enumerate(((ph.heel_off, ph.heel_strike), (ph.ball_off, ph.ball_strike))):
        stance = tr.t <= off + 1e-9
        assert np.all(H[stance, k] <= CONTACT_HEIGHT)  # on the ground until it leaves
        i_up = int(np.argmax(tr.t > off + 1e-9))
        assert H[i_up, k] > CONTACT_HEIGHT  # and the next frame it is up
        assert np.all(H[(tr.t >= strike - 1e-9) & (tr.t <= strike + 0.05), k] <= CONTACT_HEIGHT)
        assert H[int(np.argmax(tr.t >= strike - 1e-9)) - 1, k] > CONTACT_HEIGHT or strike == ph.touchdown
    t = np.array([0.0, ph.heel_off + 0.01, ph.takeoff, ph.heel_strike])
    assert ph.loaded("heel", t).tolist() == [True, False, False, True]
    assert ph.loaded("toe", t).tolist() == [False, True, True, False]  # the toe point off the flat foot
    no_schedule = training_phases(model, tr)  # no geometry, no schedule: every point always, one contact mode
    assert all(no_schedule.loaded(p, t).all() for p in ("heel", "ball", "toe", "pad"))
    assert not no_schedule.flat(t).any() and not no_schedule.pivot(t).any()
    assert len(no_schedule.switches()) == len(no_schedule.roll_switches()) == len(no_schedule.pivot_windows()) == 0


def test_contact_modes_of_the_paper_jump():
    """The contact modes on the paper's jump, every time a 120 Hz frame of the training data (heel
    off 0.192 s, ball off 0.258 s, takeoff 0.308 s, touchdown 0.692 s, ball strike 0.708 s, heel
    strike 0.775 s): the foot flat while the heel is loaded (ends included), the toes rolling on the
    toe point after the ball rises up to the takeoff and from the touchdown until the ball strikes
    (at the ball's switches the toes still lie flat), the points loaded by mode (the toe point off the
    flat foot, the pad on the flat toes only), the anchor's switches at the heel's and the roll's at
    the ball's."""
    from latentoc.jump.contact import FootGeometry

    model, _ = jump_model()
    tr = training_jumps()[0]
    ph = training_phases(model, tr, geom=FootGeometry.from_standing(model, tr.Q[0]))
    frames = {"heel_off": 23, "ball_off": 31, "takeoff": 37, "touchdown": 83, "ball_strike": 85, "heel_strike": 93}
    for name, i in frames.items():
        assert getattr(ph, name) == tr.t[i] and np.isclose(tr.t[i], i / 120.0), name
    ho, bo, to, td, bs, hs = (getattr(ph, k) for k in frames)
    e = 1e-4  # just inside or outside a switch
    t = np.array([0.0, ho - e, ho, ho + e, bo - e, bo, bo + e, to - e, to,
                  td, td + e, bs - e, bs, bs + e, hs - e, hs, hs + e, ph.duration])
    mode = np.where(ph.flat(t), "foot", np.where(ph.pivot(t), "rolling", "toes"))
    np.testing.assert_array_equal(mode, ["foot", "foot", "foot", "toes", "toes", "toes", "rolling", "rolling", "rolling",
                                         "rolling", "rolling", "rolling", "toes", "toes", "toes", "foot", "foot", "foot"])
    loaded = {p: ph.loaded(p, t) for p in ("heel", "ball", "toe", "pad")}
    np.testing.assert_array_equal(loaded["heel"], mode == "foot")
    np.testing.assert_array_equal(loaded["toe"], mode != "foot")
    np.testing.assert_array_equal(loaded["pad"], mode == "toes")
    np.testing.assert_array_equal(loaded["ball"], (t <= bo) | (t >= bs))  # flat foot and flat toes: here always on
    np.testing.assert_array_equal(loaded["ball"], mode != "rolling")
    np.testing.assert_array_equal(ph.switches(), [ho, hs])
    np.testing.assert_array_equal(ph.roll_switches(), [bo, bs])
    assert ph.pivot_windows() == [(bo, to), (td, bs)]


def test_a_schedule_without_rolling_has_no_rolling_window():
    """A ball that rises at the takeoff and strikes at the touchdown: the toes never roll (no
    window, no roll switch, no rolling time), the pad is loaded wherever the toe point is."""
    from latentoc.jump.phases import Phases

    ph = Phases(0.3, 0.7, 0.75, 1.3, heel_off=0.2, ball_off=0.3, ball_strike=0.7, heel_strike=0.8)
    t = np.linspace(0.0, 1.3, 131)
    contact = (t <= 0.3 + 1e-9) | (t >= 0.7 - 1e-9)
    assert ph.pivot_windows() == [] and len(ph.roll_switches()) == 0 and not ph.pivot(t).any()
    np.testing.assert_array_equal(ph.loaded("pad", t[contact]), ph.loaded("toe", t[contact]))
    np.testing.assert_array_equal(ph.loaded("toe", t), ~ph.flat(t))
    np.testing.assert_array_equal(ph.switches(), [0.2, 0.8])
