"""The 3-D view as one self-contained HTML file: three.js (MIT licence, embedded with its notice),
latentoc's page script and the scene's data, all inline, so it opens from disk in any browser
without a server or a network connection."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from latentoc.runtime.files import NPZ_ERRORS
from latentoc.results import Result, result_and_output
from latentoc.viewer.retargeted import retargeted_scene
from latentoc.viewer.scene import build_scene

SIM_NPZ = "simulation.npz"  # latentoc simulate's replay in a result folder

__all__ = ["write_html", "page_html", "THREE_VERSION"]

JS = Path(__file__).with_name("js")
THREE_VERSION = "0.159.0"  # js/three.min.js, from the npm package three@0.159.0

PAGE = """<!doctype html>
<html lang="en">
<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="latentoc view">
<title>{title}</title>
<style>
  html, body {{ margin: 0; height: 100%; overflow: hidden; font: 13px system-ui, sans-serif; color: #222; }}
  #view {{ position: absolute; inset: 0; }}
  #panel {{ position: absolute; left: 10px; top: 8px; right: 10px; pointer-events: none; }}
  #panel h1 {{ font-size: 15px; margin: 0 0 2px 0; }}
  #summary {{ color: #555; }}
  #bar {{ position: absolute; left: 10px; right: 10px; bottom: 10px; display: flex; gap: 10px; align-items: center;
          background: rgba(255, 255, 255, 0.85); padding: 6px 10px; border-radius: 6px; }}
  #time {{ flex: 1; }}
  #clock {{ font-variant-numeric: tabular-nums; min-width: 6em; }}
</style>
</head>
<body>
<div id="view"></div>
<div id="panel"><h1 id="title"></h1><div id="summary"></div><div id="status">loading...</div></div>
<div id="bar">
  <button id="play">pause</button>
  <span id="clock">t = 0.00 s</span>
  <input id="time" type="range" min="0" max="1" step="0.01" value="0">
  <select id="speed" title="playback speed"><option value="1">1x</option><option value="0.5">0.5x</option>
    <option value="0.25">0.25x</option><option value="0.1">0.1x</option></select>
  <label><input id="ghost" type="checkbox" checked> initial motion</label>
  <label><input id="simulated" type="checkbox" checked> simulated (MuJoCo)</label>
  <label><input id="beside" type="checkbox" checked> <span id="beside-label">beside</span></label>
  <label><input id="forces" type="checkbox" checked> forces</label>
  <label><input id="cones" type="checkbox" checked> friction cones</label>
  <label><input id="polygon" type="checkbox" checked> support polygon, COM, ZMP</label>
</div>
<script type="application/json" id="latentoc-scene">{scene}</script>
<script>
/* three.js {three_version}, https://threejs.org, licence: */
/*
{three_licence}
*/
{three}
</script>
<script>
{page}
</script>
</body>
</html>
"""


def page_html(scene: dict) -> str:
    """The page of a :func:`~latentoc.viewer.scene.build_scene` scene."""
    data = json.dumps(scene, separators=(",", ":")).replace("</", "<\\/")  # no "</script>" inside the JSON
    title = scene["title"].replace("&", "&amp;").replace("<", "&lt;")
    return PAGE.format(title=title, scene=data, three_version=THREE_VERSION,
                       three_licence=(JS / "three.LICENSE").read_text().replace("*/", "* /"),
                       three=(JS / "three.min.js").read_text(), page=(JS / "page.js").read_text())


def write_html(result: Result | str | Path, path: str | Path | None = None, rate_hz: float = 50.0) -> Path:
    """Write the 3-D view of a result (or of the result folder a path names) to ``path`` (default:
    the folder's ``view.html``); returns the path. A folder's ``simulation.npz`` (``latentoc
    simulate``) is shown beside the planned motion. A path to ``latentoc retarget``'s .npz: the
    robot's motion with the source's beside it (:mod:`.retargeted`; default page: beside the file,
    its name with ``.html``)."""
    if not isinstance(result, Result) and Path(result).suffix == ".npz" and Path(result).is_file():
        out = Path(result).with_suffix(".html") if path is None else Path(path)
        scene = retargeted_scene(result, rate_hz)
    else:
        folder = None if isinstance(result, Result) else Path(result)
        result, out = result_and_output(result, path, "view.html", "write_html")
        scene = build_scene(result, rate_hz, _simulation(folder) if folder is not None else None)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(page_html(scene), encoding="utf-8")
    return out


def _simulation(folder: Path) -> dict[str, np.ndarray] | None:
    """``t`` and ``q`` of the folder's replay, or None (none, or not a readable replay)."""
    path = folder / SIM_NPZ
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as f:
            t, q = np.asarray(f["t"], float), np.asarray(f["q"], float)
    except NPZ_ERRORS + (KeyError,):
        return None
    return {"t": t, "q": q} if t.ndim == 1 and q.ndim == 2 and len(t) == len(q) and len(t) > 0 else None
