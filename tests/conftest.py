"""Shared fixtures."""
from types import SimpleNamespace

import pytest


@pytest.fixture(scope="session")
def jump_setup():
    """The broad jump's default set-up (training jump, GPDM, phases, limits), built once."""
    from latentoc.jump.problem import setup

    return setup()


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
    """A broad-jump NLP with few nodes (phase 2: distance, wrench samples every 50 ms) and its
    training start (:func:`latentoc.jump.start.initial_point`)."""
    from latentoc.jump.nlp import build_nlp
    from latentoc.jump.settings import JumpSettings
    from latentoc.jump.start import initial_point

    p = jump_parts
    js = p.js
    settings = JumpSettings(n_stance=6, n_flight=6, n_land=6, wrench_spacing=0.05)
    nlp = build_nlp(p.robot, p.layer, p.blocks, js.phases, settings, js.init["P"], "distance")
    x0 = initial_point(p.robot, p.layer, nlp, js.init["P"], js.init["t"], js.init["base"], js.init["x_L"],
                       js.phases.takeoff, js.phases.touchdown)
    return SimpleNamespace(**vars(p), settings=settings, nlp=nlp, x0=x0)


@pytest.fixture(scope="session")
def small_export(small_jump):
    """The 1 kHz export (:func:`latentoc.jump.export.trajectory`) of the small NLP's training start."""
    from latentoc.jump.export import trajectory
    from latentoc.jump.solve import JumpSolution

    sj = small_jump
    return trajectory(sj.robot, sj.layer, sj.js.phases, JumpSolution(sj.nlp, sj.x0, None, None, {}))
