"""Shared fixtures."""
import pytest


@pytest.fixture(scope="session")
def jump_setup():
    """The broad jump's default set-up (training jump, GPDM, phases, limits), built once: its
    SymbolicModel and GPDM key the compiled row-block cache, so the NLP builds share the blocks."""
    from latentoc.jump.problem import setup

    return setup()
