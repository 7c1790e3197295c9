"""Test layers (issue 24): ``pytest`` runs everything (CI); ``pytest -m "not slow"`` is the quick loop.

Marked here by rule: every notebook (``notebook`` and ``slow``) and every test that uses the broad
jump's set-up (its GPDM, phases and row blocks take tens of seconds to build). The test modules
mark their own other slow tests (solves, subprocesses, clusters) with ``pytest.mark.slow``.
"""
import os

import pytest

# nbmake's kernels inherit it: the broad-jump notebook stops after a few iterations under test (its
# committed outputs are a full solve, `python -m latentoc notebooks`)
os.environ.setdefault("LATENTOC_NOTEBOOK_QUICK", "1")
# The tests check values, not speed: the NLP Functions are evaluated in CasADi's virtual machine, not
# compiled (gcc takes ~10 min for the broad jump's node Jacobians on a cold machine; the compiled path
# has its own tests, and `python -m latentoc bench` measures it). LATENTOC_JIT=1 compiles.
os.environ.setdefault("LATENTOC_JIT", "0")

SLOW_FIXTURES = {"jump_setup"}  # tests/conftest.py: the broad jump's set-up, shared by the session


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if item.path.suffix == ".ipynb":
            item.add_marker(pytest.mark.notebook)
            item.add_marker(pytest.mark.slow)
        elif SLOW_FIXTURES & set(getattr(item, "fixturenames", ())):
            item.add_marker(pytest.mark.slow)
