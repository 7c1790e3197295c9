"""The README's figures, made by one command: ``python -m latentoc reproduce --figures``.

It solves the README's main problem (``arm-raise``) and the worked example
(``examples/panda-reach``) and writes into ``docs/images``:

* ``arm_latent_tube.png``: the optimised path in its variance tube (Fig. 3), the README's headline;
* ``arm_convergence.png``: Ipopt's convergence over the exchange's rounds;
* ``panda_view.png``: a still of the 3-D view (``python -m latentoc view``) of the Panda reach, taken
  by headless Chromium;
* ``figures.json``: each image's SHA-256 and the fingerprints of the checkout's files the command
  ran and read (:mod:`latentoc.reproduce.provenance`), so ``tests/test_readme.py`` fails when an image is
  older than the code that makes it.
"""
from __future__ import annotations

import hashlib
import json
import tempfile
from pathlib import Path
from typing import Any

from latentoc.reproduce.provenance import ROOT, Recorder

__all__ = ["IMAGES", "MANIFEST", "COMMAND", "make_figures", "image_problems"]

COMMAND = "python -m latentoc reproduce --figures"
IMAGES = ("arm_latent_tube.png", "arm_convergence.png", "panda_view.png")
MANIFEST = "figures.json"
VIEW_TIME = 1.4  # s into the 2.5 s reach: the arm on its way, the initial motion's ghost beside it


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def make_figures(out: str | Path = ROOT / "docs" / "images") -> list[Path]:
    """Solve, draw and write the images and their manifest into ``out`` (module doc); the paths."""
    import latentoc

    from matplotlib.figure import Figure

    from latentoc.plots import DPI, plot_convergence, plot_latent_tube, save
    from latentoc.viewer import write_html
    from latentoc.viewer.still import still

    out = Path(out)
    with Recorder() as rec, tempfile.TemporaryDirectory(prefix="latentoc-figures-") as tmp:
        arm = latentoc.solve(latentoc.load_problem("arm-raise"))
        traj = arm.trajectory
        assert arm.gpdm is not None and arm.tube is not None
        tube = Figure(figsize=(9.0, 4.8), dpi=DPI)  # wide: the tube is long and thin at one scale on every axis
        ax = tube.add_subplot(projection="3d")
        plot_latent_tube(arm.gpdm, arm.tube.delta, paths={"initial": traj["x_initial"], "optimised": traj["x"]},
                         control_points={"initial control points": traj["P_initial"],
                                         "optimised control points": traj["P"]},
                         title=f"arm-raise: the optimised path in the tube $\\delta$ = {arm.tube.delta:.3g}", axes=ax)
        ax.set_box_aspect(tuple(ax.get_box_aspect()), zoom=1.15)
        tube.subplots_adjust(left=0.0, right=1.0, bottom=0.0, top=0.95)
        written = [save(tube, out / IMAGES[0]),
                   save(plot_convergence(arm.convergence, title="arm-raise: Ipopt's convergence, round by round"),
                        out / IMAGES[1])]
        panda = latentoc.solve(latentoc.load_problem(str(ROOT / "examples" / "panda-reach" / "panda-reach.toml")))
        page = write_html(panda, Path(tmp) / "view.html")
        written.append(still(page, out / IMAGES[2], VIEW_TIME))
    manifest: dict[str, Any] = {"command": COMMAND, "images": {p.name: _sha256(p) for p in written},
                                "inputs": rec.inputs}
    (out / MANIFEST).write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return written + [out / MANIFEST]


def image_problems(folder: str | Path = ROOT / "docs" / "images") -> list[str]:
    """Why the images in ``folder`` are not what the command makes from the current code (empty: current)."""
    from latentoc.reproduce.provenance import stale

    folder = Path(folder)
    if not (folder / MANIFEST).is_file():
        return [f"no {MANIFEST} in {folder}"]
    manifest = json.loads((folder / MANIFEST).read_text())
    problems = [f"{name} is not the image the command wrote" for name, sha in manifest["images"].items()
                if not (folder / name).is_file() or _sha256(folder / name) != sha]
    missing = sorted(set(IMAGES) - set(manifest["images"]))
    if missing:
        problems.append(f"the manifest lacks {', '.join(missing)}")
    changed = stale(manifest["inputs"])
    if changed:
        problems.append("the code or data that made them changed: " + ", ".join(changed))
    return problems
