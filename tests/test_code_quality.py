"""The linter (ruff) and the type checker (mypy), as configured in pyproject.toml, pass on the code."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(*cmd: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", *cmd], cwd=ROOT, capture_output=True, text=True, timeout=600)


def test_ruff():
    pytest.importorskip("ruff")
    p = _run("ruff", "check", "latentoc", "tests", "conftest.py")
    assert p.returncode == 0, p.stdout + p.stderr


@pytest.mark.slow
def test_mypy():
    pytest.importorskip("mypy")
    p = _run("mypy")  # files and settings: [tool.mypy]
    assert p.returncode == 0, p.stdout + p.stderr
