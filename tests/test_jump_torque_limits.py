"""Training inverse dynamics: NNLS contact forces reproduce the base wrench where they can."""
import numpy as np
from latentoc.jump.robot.robot_declaration import CMU_HUMANOID

from latentoc.jump.schedule.phases import training_phases
from latentoc.jump.robot.torque_limits import estimate_training_dynamics
from latentoc.jump.demonstration.training import training_jumps
from latentoc.robots.cmu_humanoid import symmetric_model


def test_training_forces_and_limits():
    model, smap = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    ph = training_phases(model, tr, geom, schedule=False)
    contact = (tr.t <= ph.takeoff) | (tr.t >= ph.touchdown)
    td = estimate_training_dynamics(model, smap, tr, geom, contact, margin=0.0)
    W = 63.86 * 9.81
    # forces are unilateral and in the cone by construction
    assert np.all(td.forces[..., 1] >= -1e-9)
    assert np.all(np.abs(td.forces[..., 0]) <= 0.4 * td.forces[..., 1] + 1e-9)
    # the vertical force balance is reproduced well in stance (frames standing still)
    still = np.where(tr.t < 0.15)[0]
    assert np.max(np.abs(td.base_residual[still][:, 2])) < 0.1 * W
    # the vertical force is what the captured motion needs (centroidal dP_z + m g), not just m g
    fz = 2 * td.forces[still, :, 1].sum(axis=1)
    assert np.all(fz > 0.5 * W)
    # lateral rows vanish by symmetry; limits enclose the training torques
    assert np.max(np.abs(td.base_residual[:, [1, 3, 5]])) < 1e-6 * W
    assert np.all(td.tau_min <= td.tau.min(0) + 1e-9) and np.all(td.tau_max >= td.tau.max(0) - 1e-9)
    # the margin: max(margin * peak, floor) on each side of every loaded joint, 0 on the others
    wide = estimate_training_dynamics(model, smap, tr, geom, contact, margin=0.1, floor=5.0)
    peak = np.max(np.abs(td.tau), axis=0)
    pad = np.where(peak > 1e-9, np.maximum(0.1 * peak, 5.0), 0.0)
    assert np.allclose(wide.tau_max - td.tau_max, pad) and np.allclose(td.tau_min - wide.tau_min, pad)
    assert np.any((peak > 1e-9) & (0.1 * peak < 5.0)) and np.any(0.1 * peak > 5.0)


def test_schedule_unloads_the_heel_after_heel_off():
    """With the contact schedule the heel carries no force after heel-off (and the ball none
    after ball-off); the toe alone must then balance what it can."""
    model, smap = symmetric_model()
    tr = training_jumps()[0]
    geom = CMU_HUMANOID.geometry(model, tr.Q[0])
    ph = training_phases(model, tr, geom)
    contact = (tr.t <= ph.takeoff) | (tr.t >= ph.touchdown)
    loaded = np.column_stack([ph.loaded(k, tr.t) for k in ("heel", "ball", "toe", "pad")])
    td = estimate_training_dynamics(model, smap, tr, geom, contact, loaded=loaded)
    off = contact & ~loaded[:, 0]
    assert off.sum() > 5 and np.all(td.forces[off, 0, :] == 0)
    assert np.all(td.forces[contact & ~loaded[:, 1], 1, :] == 0)
    assert np.any(td.forces[contact & loaded[:, 0], 0, 1] > 0)
