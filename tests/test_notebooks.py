"""The notebooks are committed with the outputs of the current code (latentoc.reproduce.notebooks): each one
records the command that remakes it, its code cells' hash and the fingerprints of the checkout's
files it ran and read (latentoc.reproduce.provenance); a change to those, not to unrelated modules, makes it
stale. The recording itself: a called function's module counts, an imported one alone does not;
comments and docstrings do not change a fingerprint. Progress bars work in a Jupyter kernel."""
from __future__ import annotations

import pytest

from latentoc.reproduce import provenance
from latentoc.reproduce.notebooks import check, notebook_paths


@pytest.mark.parametrize("notebook", notebook_paths(), ids=lambda p: p.stem)
def test_committed_outputs_are_the_current_codes(notebook):
    problems = check(notebook)
    assert not problems, (f"{notebook.name} is stale: {'; '.join(problems)}. Remake it with "
                          f"`python -m latentoc notebooks {notebook.stem}` (or `--stale` for every stale one)")


def test_fingerprints_see_code_not_comments(tmp_path):
    a, b, c = tmp_path / "a.py", tmp_path / "b.py", tmp_path / "c.py"
    a.write_text('"""Doc."""\nx = 1  # one\n\n\ndef f():\n    """What f does."""\n    return x\n')
    b.write_text('"""Another doc."""\nx = 1  # a comment\n\ndef f():\n    return x\n')
    c.write_text('"""Doc."""\nx = 2\n\ndef f():\n    return x\n')
    assert provenance.fingerprint(a) == provenance.fingerprint(b) != provenance.fingerprint(c)
    (tmp_path / "d.toml").write_text("x = 1\n")
    assert len(provenance.fingerprint(tmp_path / "d.toml")) == 64


def test_recorder_notes_what_ran_and_what_was_read(tmp_path):
    import latentoc.min_torque.start_poses  # imported, none of its functions called below
    from latentoc.latent.spline import BSpline

    with provenance.Recorder() as rec:
        BSpline(7, 2.0, 3).basis([0.5], 0)
        (provenance.ROOT / "problems" / "arm-raise.toml").read_text()
        (tmp_path / "out.txt").write_text("written, not read")
    assert "latentoc/latent/spline.py" in rec.inputs and "problems/arm-raise.toml" in rec.inputs
    assert "latentoc/min_torque/start_poses.py" not in rec.inputs and latentoc.min_torque.start_poses
    assert all(not k.startswith(("/", "..")) for k in rec.inputs)
    assert provenance.stale(rec.inputs) == [] and provenance.stale({"latentoc/latent/spline.py": "0" * 64}) == ["latentoc/latent/spline.py"]
    assert set(provenance.uncommitted(rec.inputs)) <= set(rec.inputs)
    assert provenance.module_files("%matplotlib inline\nfrom latentoc.reproduce.paper import PAPER") == \
        {str(provenance.ROOT / "latentoc" / "reproduce" / "paper.py")}


@pytest.mark.slow  # starts a Jupyter kernel
def test_progress_bar_in_jupyter():
    """latentoc's bars in a kernel: a text bar on stderr, no "IProgress not found" (tqdm.auto's widget)."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("from latentoc.runtime.progress import bar, set_quiet\nset_quiet(False)\n"
                                          "for _ in bar(range(3), desc='steps', leave=True):\n    pass")]
    NotebookClient(nb, kernel_name="python3", timeout=120).execute()
    text = "".join(o.get("text", "") for o in nb.cells[0].outputs)
    assert "IProgress" not in text and "steps: 100%" in text and "3/3" in text
    assert all(o.output_type == "stream" and o.name == "stderr" for o in nb.cells[0].outputs)
