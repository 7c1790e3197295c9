"""Shared fixtures."""
import signal
from types import SimpleNamespace

import pytest


@pytest.fixture
def sigint_default():
    """Ctrl-C as in a user's process: Python's own SIGINT handler in this process and SIG_DFL in the
    processes it starts (pytest-xdist's workers ignore SIGINT, and children inherit the ignoring)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.fixture(scope="session")
def jump_setup():
    """The packaged broad jump's set-up (planted training jump, GPDM, phases, limits), built once."""
    from latentoc.jump.problem import problem_setup
    from latentoc.problem.toml_files import load_problem

    return problem_setup(load_problem("broad-jump"))


@pytest.fixture(scope="session")
def jump_parts(jump_setup):
    """The default set-up's robot (mu = 0.4), GP layer and row blocks: the blocks are built (and,
    with LATENTOC_JIT on, compiled or found in the disk cache) once per test session."""
    from latentoc.latent.gp_layer import GPLayer

    js = jump_setup
    robot = js.robot(0.4)
    return SimpleNamespace(js=js, robot=robot, layer=GPLayer(js.gpdm), blocks=js.blocks(robot))


@pytest.fixture(scope="session")
def small_jump(jump_parts):
    """A broad-jump NLP with few nodes and every row family (phase 2: distance; every node row,
    contact samples every 50 ms and flight samples every 50 ms with every torque row, the tube) and
    its training start (:func:`latentoc.jump.solve.initial_point.initial_point`)."""
    import numpy as np

    from latentoc.jump.schedule.phases import contact_sample_grid
    from latentoc.jump.transcription.nlp import build_nlp, tube_times
    from latentoc.jump.transcription.selection import Selection
    from latentoc.jump.settings import JumpSettings
    from latentoc.jump.solve.initial_point import initial_point

    p = jump_parts
    js = p.js
    settings = JumpSettings(n_stance=6, n_flight=6, n_land=6, sample_spacing=0.05)
    ph, nk = js.phases, p.robot.unmirrored.size
    tc = contact_sample_grid(settings, ph)
    tf = np.round(np.arange(ph.takeoff + 0.02, ph.touchdown - 0.01, 0.05), 3)
    selection = Selection(np.ones((12, nk)), np.ones((12, 8)), tc, np.ones((len(tc), nk)), np.ones((len(tc), 8)),
                          tf, np.ones((len(tf), nk)), tube_times(ph, p.layer))
    nlp = build_nlp(p.robot, p.layer, p.blocks, ph, settings, js.init["P"], "distance", selection)
    x0 = initial_point(p.robot, p.layer, nlp, ph, js.init["P"], js.init["x_L"])
    return SimpleNamespace(**vars(p), settings=settings, nlp=nlp, x0=x0)


@pytest.fixture(scope="session")
def small_export(small_jump):
    """The 1 kHz export (:func:`latentoc.jump.check.export.trajectory`) of the small NLP's training start."""
    from latentoc.jump.check.export import trajectory

    sj = small_jump
    return trajectory(sj.robot, sj.layer, sj.js.phases, sj.nlp, sj.x0)
