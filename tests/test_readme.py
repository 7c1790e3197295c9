"""The README's set-up commands are what CI runs, and its main command names a real problem."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _code_blocks(text: str) -> list[list[str]]:
    blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)
    return [[line.strip() for line in b.splitlines() if line.strip() and not line.startswith("#")] for b in blocks]


def test_first_two_commands_are_what_ci_runs():
    readme = (ROOT / "README.md").read_text()
    first = _code_blocks(readme)[0]
    assert len(first) == 2, "the README starts with exactly two commands: install, test"
    ci_lines = [line.strip() for line in (ROOT / ".ci" / "run").read_text().splitlines()]
    positions = [ci_lines.index(cmd) for cmd in first]  # ValueError if CI does not run it verbatim
    assert positions == sorted(positions)


def test_main_job_command_follows_and_names_a_known_problem():
    from latentoc.problem import problem_names

    readme = (ROOT / "README.md").read_text()
    main_job = _code_blocks(readme)[1][0]
    match = re.match(r"python -m latentoc solve (\S+)", main_job)
    assert match, main_job
    assert match.group(1) in problem_names()
