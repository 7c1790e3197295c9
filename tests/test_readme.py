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
    from latentoc.problem.toml_files import problem_names

    readme = (ROOT / "README.md").read_text()
    main_job = _code_blocks(readme)[1][0]
    match = re.match(r"python -m latentoc solve (\S+)", main_job)
    assert match, main_job
    assert match.group(1) in problem_names()


def _reproduction_gains(section: str) -> dict[str, str]:
    """tube -> our gain % in one table of docs/reproduction.md (written by `latentoc reproduce`)."""
    text = (ROOT / "docs" / "reproduction.md").read_text()
    body = text.split(section, 1)[1].split("\n## ", 1)[0]
    head, rows = None, {}
    for line in body.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if "ours: tube" in cells:
            head = cells
        elif head and len(cells) == len(head) and cells[head.index("ours: tube")] and not set(line) <= set("|- "):
            rows[cells[head.index("ours: tube")]] = cells[head.index("ours: gain %")]
    return rows


def test_readme_arm_table_is_the_reproductions():
    """The README's arm-raise gains are docs/reproduction.md's (Table 2, d = 3), digit for digit."""
    readme = (ROOT / "README.md").read_text()
    lines = readme.splitlines()
    tubes = next(line for line in lines if line.startswith("| tube | 1.5x"))
    gains = next(line for line in lines if line.startswith("| gain % (cost"))
    def cells(line: str) -> list[str]:
        return [c.strip() for c in line.strip().strip("|").split("|")][1:]

    ours = _reproduction_gains("## Table 2")
    assert dict(zip(cells(tubes), cells(gains))) == ours


def test_readme_images_are_made_by_the_current_code():
    """Every image the README shows is one `python -m latentoc reproduce --figures` writes, the very file
    it wrote, from the code and data of this checkout (docs/images/figures.json, latentoc.reproduce.provenance)."""
    from latentoc.reproduce.figures import COMMAND, IMAGES, image_problems

    readme = (ROOT / "README.md").read_text()
    shown = set(re.findall(r"\]\(docs/images/([^)]+)\)", readme))
    assert shown and shown <= set(IMAGES), f"README images not made by {COMMAND}: {sorted(shown - set(IMAGES))}"
    problems = image_problems()
    assert not problems, f"docs/images is stale: {'; '.join(problems)}. Remake it: {COMMAND}"


def test_readme_shows_the_view_and_the_convergence():
    readme = (ROOT / "README.md").read_text()
    for text in ("docs/images/panda_view.png", "docs/images/arm_convergence.png", "python -m latentoc view ",
                 "python -m latentoc plot ", "python -m latentoc list --robots", "python -m latentoc notebooks"):
        assert text in readme, text
