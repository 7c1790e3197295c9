"""The view of a retargeted demonstration (``latentoc retarget``, then ``view`` on its .npz): the
robot's parts where forward kinematics puts them, the source's beside it (its own model and
configurations, moved sideways clear of the robot and down to the ground), bad files refused
naming the file, and in a real headless browser both drawn."""
from __future__ import annotations

import base64
import json
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from browser import chromium, dom, screenshot

from latentoc.cli.parser import main
from latentoc.robots import load_robot
from latentoc.viewer import part_poses, robot_parts, write_html
from latentoc.viewer.retargeted import GAP, retargeted_scene
from latentoc.viewer.scene import sample_indices

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def retargeted(tmp_path_factory) -> Path:
    """Eight frames of the CMU jump's start retargeted to the G1 by the CLI."""
    out = tmp_path_factory.mktemp("retargeted") / "g1.npz"
    assert main(["retarget", str(ROOT / "robots/g1/cmu-retarget.toml"), "--motion", str(ROOT / "robots/cmu/01_01.amc"),
                 "--asf", str(ROOT / "robots/cmu/01.asf"), "--start", "149", "--stop", "157", "--out", str(out)]) == 0
    return out


def f32(text: str, *shape: int) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), "<f4").reshape(shape)


def test_the_robot_and_its_source_are_posed_by_their_own_models(retargeted):
    with np.load(retargeted) as f:
        t, q, qs = f["t"], f["q"], f["q_source"]
    g1, human = load_robot("g1"), load_robot("cmu-humanoid")
    scene = retargeted_scene(retargeted, rate_hz=1000)
    idx = sample_indices(t, 1000)
    parts, _ = robot_parts(g1, "g1")
    src, _ = robot_parts(human, "cmu-humanoid")
    n = len(idx)
    shown = f32(scene["motions"]["optimised"], n, len(parts), 7)
    assert np.allclose(shown, part_poses(g1, parts, q[idx]), atol=1e-5)
    beside = f32(scene["beside"]["poses"], n, len(src), 7)
    own = part_poses(human, src, qs[idx])
    shift = beside[..., :3] - own[..., :3]
    assert np.allclose(shift, shift[0, 0], atol=1e-5) and shift[0, 0, 0] == pytest.approx(0.0, abs=1e-6)
    assert np.allclose(beside[..., 3:], own[..., 3:], atol=1e-6)  # moved, not turned
    assert beside[..., 1].max() <= shown[..., 1].min() - GAP + 1e-5  # clear of the robot, to its right
    d = human.createData()  # the source's lowest frame on the ground at its start
    pin.framesForwardKinematics(human, d, qs[0])
    assert min(m.translation[2] for m in d.oMf) + shift[0, 0, 2] == pytest.approx(0.0, abs=1e-5)


def test_a_file_that_is_not_a_retargeted_motion_is_refused_by_name(tmp_path, capsys):
    bad = tmp_path / "plain.npz"
    np.savez(bad, t=np.linspace(0, 1, 5), q=np.zeros((5, 36)))
    assert main(["view", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and "q_source" in err and "Traceback" not in err
    assert not bad.with_suffix(".html").exists()


@pytest.mark.slow  # starts a browser three times (about 5 s each)
def test_both_are_drawn_in_a_browser(retargeted, tmp_path):
    if chromium() is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    page = write_html(retargeted, tmp_path / "view.html")
    text = dom(page, 300, url_suffix="#t=0.02")
    assert "data-error" not in text, "the script failed"
    n_src = len(robot_parts(load_robot("cmu-humanoid"), "cmu-humanoid")[0])
    assert re.search(r'data-beside="([^"]*)"', text).group(1) == f"{n_src} shown"
    # the same page without the source, and without anything: each drawn part changes the pixels
    data = re.search(r'(<script type="application/json" id="latentoc-scene">)(.*?)(</script>)', page.read_text(), re.S)
    scene = json.loads(data.group(2))

    def variant(name: str, change) -> Path:
        s = json.loads(json.dumps(scene))
        change(s)
        out = tmp_path / f"{name}.html"
        out.write_text(page.read_text().replace(data.group(2), json.dumps(s).replace("</", "<\\/")))
        return out

    alone = variant("alone", lambda s: s.pop("beside"))
    both = screenshot(page, tmp_path / "both.png", 300, url_suffix="#t=0.02")
    robot = screenshot(alone, tmp_path / "robot.png", 300, url_suffix="#t=0.02")
    view = slice(70, -60)  # below the title lines (their text differs), above the control bar
    assert int(np.sum(np.abs(both[view] - robot[view]).max(axis=2) > 30)) > 1000, "the source is not drawn"
