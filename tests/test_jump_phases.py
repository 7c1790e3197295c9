"""Phase timing of the symmetric training jump (Sect. 4.2: 1.3 s), checked against the data."""
import numpy as np

from latentoc.jump.robot.robot_declaration import CMU_HUMANOID
from latentoc.jump.schedule.phases import toe_heights, training_phases
from latentoc.mocap.jumps import detect_jumps
from latentoc.jump.demonstration.training import training_jumps
from latentoc.robots.cmu_humanoid import symmetric_model


def test_phases_and_grid():
    model, smap = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    ph = training_phases(model, tr, geom, schedule=False)
    assert np.isclose(ph.duration, 1.3)
    # toe-off: the toe tip's lowest point just before the feet leave (detected 0.350 s), after
    # which it only rises; touchdown: the toe tip back at its standing height
    j = detect_jumps(model, tr.Q)[0]
    z = toe_heights(model, tr.Q, geom)
    i0, i1 = int(np.argmin(np.abs(tr.t - ph.takeoff))), int(np.argmin(np.abs(tr.t - ph.touchdown)))
    assert tr.t[j.takeoff] - 0.1 <= ph.takeoff < tr.t[j.takeoff] and 0.29 < ph.takeoff < 0.33
    assert np.all(np.diff(z[i0:j.takeoff + 1]) > 0) and z[i0] <= z[i0 - 1]
    assert z[i1] <= z[0] < z[i1 - 1] and i1 >= j.touchdown
    assert 0.25 < ph.touchdown - ph.takeoff < 0.45 and ph.touchdown < ph.settle < ph.duration
    assert smap.n_learned == 37 and tr.Y.shape == (157, 37)


def test_contact_schedule_follows_the_training_heel_and_ball():
    """The heel and ball carry force only while the training motion has them on the ground:
    checked against their heights recomputed from the frames with numeric Pinocchio."""
    import pinocchio as pin

    from latentoc.jump.robot.feet import foot_points
    from latentoc.jump.schedule.phases import CONTACT_HEIGHT

    model, _ = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    ph = training_phases(model, tr, geom)
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
    assert ph.loaded("toe", t).all()
    assert training_phases(model, tr, geom, schedule=False).loaded("heel", t).all()  # no schedule
