"""The notebooks' committed outputs: ``python -m latentoc notebooks [NAME ...] [--stale]`` runs them in
place (in ``notebooks/`` of the source checkout) and records what their outputs were made from.

Each notebook runs top to bottom in a fresh Jupyter kernel with progress bars off
(``LATENTOC_QUIET=1``: the committed outputs hold figures and numbers, not bar updates); a
:class:`~latentoc.reproduce.provenance.Recorder` in the kernel notes the checkout's files whose code ran or
that were read, and the modules the cells import by name are added. The
notebook's metadata ``latentoc`` then holds the command that remakes it, the SHA-256 of its code
cells and those inputs' fingerprints; :func:`check` (``tests/test_notebooks.py``) reports a notebook
whose cells or inputs changed since, so the committed outputs are those of the current code.
"""
from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from latentoc.errors import LatentocError
from latentoc.reproduce.provenance import ROOT, fingerprints, module_files, stale

__all__ = ["NOTEBOOKS", "notebook_paths", "cells_hash", "run_notebook", "check", "COMMAND"]

NOTEBOOKS = ROOT / "notebooks"
COMMAND = "python -m latentoc notebooks"
_START = "import latentoc.reproduce.provenance\nlatentoc.reproduce.provenance.start()"
_STOP = "import json\nimport latentoc.reproduce.provenance\nprint(json.dumps(latentoc.reproduce.provenance.stop()))"


def notebook_paths(names: list[str] | None = None) -> list[Path]:
    """The notebooks by name or number prefix (``03``, ``03_arm_raising``); all without names."""
    if not NOTEBOOKS.is_dir():
        raise LatentocError(f"no notebooks at {NOTEBOOKS}: they are in latentoc's source checkout")
    every = sorted(NOTEBOOKS.glob("*.ipynb"))
    if not names:
        return every
    out = []
    for name in names:
        found = [p for p in every if p.stem == name or p.stem.startswith(name) or p.name == name]
        if len(found) != 1:
            raise LatentocError(f"notebook {name!r}: {'no' if not found else 'more than one'} notebook of that name in "
                                f"{NOTEBOOKS} ({', '.join(p.stem for p in every)})")
        out.append(found[0])
    return out


def cells_hash(nb: Any) -> str:
    """SHA-256 of the notebook's code cells' sources, in order."""
    return hashlib.sha256(json.dumps([c.source for c in nb.cells if c.cell_type == "code"]).encode()).hexdigest()


def run_notebook(path: Path, timeout: int = 3600) -> dict[str, Any]:
    """Execute the notebook at ``path`` in place (module doc); returns its ``latentoc`` metadata."""
    import nbformat
    from nbclient import NotebookClient

    nb = nbformat.read(path, as_version=4)
    start, stop = nbformat.v4.new_code_cell(_START), nbformat.v4.new_code_cell(_STOP)
    nb.cells = [start, *nb.cells, stop]
    # the kernel inherits the environment: quiet progress, and committed outputs are never a quick test run
    saved = {k: os.environ.get(k) for k in ("LATENTOC_QUIET", "LATENTOC_NOTEBOOK_QUICK")}
    os.environ["LATENTOC_QUIET"] = "1"
    os.environ.pop("LATENTOC_NOTEBOOK_QUICK", None)
    try:
        NotebookClient(nb, timeout=timeout, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}).execute()
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    inputs = json.loads("".join(o.get("text", "") for o in stop.outputs if o.output_type == "stream"))
    nb.cells = nb.cells[1:-1]
    imported = set().union(*(module_files(c.source) for c in nb.cells if c.cell_type == "code"))
    inputs = dict(sorted({**inputs, **fingerprints(imported)}.items()))
    for cell in nb.cells:  # the hidden first cell took execution count 1
        if cell.cell_type == "code" and cell.execution_count:
            cell.execution_count -= 1
            for out in cell.outputs:
                if out.get("execution_count"):
                    out.execution_count -= 1
    meta = {"regenerate": f"{COMMAND} {path.stem}", "cells_sha256": cells_hash(nb), "inputs": inputs}
    nb.metadata["latentoc"] = meta
    nbformat.write(nb, path)
    return meta


def check(path: Path) -> list[str]:
    """Why the committed outputs of the notebook at ``path`` are not those of the current code and
    cells (empty: current)."""
    import nbformat

    nb = nbformat.read(path, as_version=4)
    meta = nb.metadata.get("latentoc")
    if not meta:
        return [f"{path.name} has no record of its run: {COMMAND} {path.stem}"]
    problems = []
    if meta.get("cells_sha256") != cells_hash(nb):
        problems.append("its code cells changed since it was run")
    changed = stale(meta.get("inputs", {}))
    if changed:
        problems.append("the code or data it ran changed: " + ", ".join(changed))
    for k, cell in enumerate(nb.cells):
        if cell.cell_type != "code":
            continue
        if cell.execution_count is None:
            problems.append(f"cell {k} has not been run")
        if any(o.output_type == "error" for o in cell.outputs):
            problems.append(f"cell {k} ended with an error")
    return problems
