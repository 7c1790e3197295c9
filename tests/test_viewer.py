"""The 3-D view: the robot's parts where forward kinematics puts them (the Panda's URDF meshes on a
reduced model, the skeleton's capsules along its bones), a page that needs nothing but itself, and
in a real headless browser (chromium): the page loads from the file, draws the robot (against the same
page without it) and its animation advances."""
from __future__ import annotations

import json
import re

import numpy as np
import pinocchio as pin
import pytest
from browser import chromium, dom, screenshot
from result_factory import make_result

from latentoc.cli import main
from latentoc.plots import skeleton_segments
from latentoc.robots import example_robot_data_dir, load_robot, robot_urdf
from latentoc.viewer import build_scene, page_html, part_poses, robot_parts, write_html
from latentoc.viewer.scene import b64, contact_points, sample_indices

FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]
CONTACT_FRAMES = np.array(["lfoot", "lfoot_end", "ltoes_end", "rfoot", "rfoot_end", "rtoes_end"])


def moving(model: pin.Model, n: int, duration: float = 2.0, phase: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A smooth motion within the joint limits (t, Q)."""
    t = np.linspace(0.0, duration, n)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    mid, amp = 0.5 * (lo + hi), 0.3 * np.minimum(hi - lo, 2.0)
    return t, mid + amp * np.sin(2 * np.pi * t[:, None] / duration + phase + np.arange(model.nq))


@pytest.fixture(scope="module")
def panda_reduced():
    """The Panda with its fingers locked, as a CSV demonstration of the arm joints makes it."""
    full = load_robot("panda")
    q_ref = pin.neutral(full)
    for name in FINGERS:
        q_ref[full.joints[full.getJointId(name)].idx_q] = 0.02
    return full, pin.buildReducedModel(full, [full.getJointId(n) for n in FINGERS], q_ref), q_ref


def test_panda_meshes_sit_where_the_urdf_puts_them(panda_reduced):
    """Each visual mesh of the URDF, posed on the reduced model, is where Pinocchio's geometry
    placement puts it on the full model (fingers at their locked value)."""
    full, reduced, q_ref = panda_reduced
    parts, what = robot_parts(reduced, "panda")
    assert what == "meshes" and len(parts) == 11 and all(p.kind == "mesh" for p in parts)
    urdf = robot_urdf("panda")
    geom = pin.buildGeomFromUrdf(full, str(urdf), pin.GeometryType.VISUAL, package_dirs=[str(example_robot_data_dir().parents[1])])
    assert [p.name for p in parts] == [g.name for g in geom.geometryObjects]
    _, Q = moving(reduced, 3)
    poses = part_poses(reduced, parts, Q)
    data, gdata = full.createData(), pin.GeometryData(geom)
    for i, q in enumerate(Q):
        q_full = q_ref.copy()
        arm = [full.joints[full.getJointId(reduced.names[j])].idx_q for j in range(1, reduced.njoints)]
        q_full[arm] = q
        pin.updateGeometryPlacements(full, data, geom, gdata, q_full)
        for k, part in enumerate(parts):
            M = gdata.oMg[k]
            assert np.allclose(poses[i, k, :3], M.translation, atol=1e-9)
            assert np.allclose(pin.Quaternion(poses[i, k, 3:]).matrix(), M.rotation, atol=1e-9)
    for part, go in zip(parts, geom.geometryObjects):  # the mesh itself: coal's vertices, untouched
        assert part.vertices.shape == (go.geometry.num_vertices, 3) and part.triangles.shape == (go.geometry.num_tris, 3)


def test_skeleton_capsules_lie_on_the_bones():
    model = load_robot("human-arm")
    parts, what = robot_parts(model, "human-arm")
    assert what == "capsules" and all(p.kind == "capsule" for p in parts)
    _, Q = moving(model, 4)
    poses = part_poses(model, parts, Q)
    for i, q in enumerate(Q):
        S, names = skeleton_segments(model, q, return_names=True)
        assert [p.name for p in parts] == [f"bone_{n}" for n in names]
        for k, (a, b) in enumerate(S):
            assert np.allclose(poses[i, k, :3], 0.5 * (a + b))
            z = pin.Quaternion(poses[i, k, 3:]).matrix()[:, 2]
            assert np.allclose(z, (b - a) / np.linalg.norm(b - a))
            assert np.isclose(parts[k].size[1], np.linalg.norm(b - a))  # the capsule's length is the bone's


def test_contact_points_and_samples():
    from latentoc.robots.human_models import broad_jump_training_motion, build_cmu_humanoid

    model = build_cmu_humanoid()
    _, Q = broad_jump_training_motion()
    traj = {"contact_frames": CONTACT_FRAMES, "heel_offset": np.array([-0.05, 0.01, -0.03])}
    P = contact_points(model, traj, Q[:2])
    data = model.createData()
    pin.framesForwardKinematics(model, data, Q[1])
    assert np.allclose(P[1, 2], data.oMf[model.getFrameId("ltoes_end")].translation)
    M = data.oMf[model.getFrameId("rfoot")]
    assert np.allclose(P[1, 3], M.translation + M.rotation @ traj["heel_offset"])
    t = np.arange(0, 1.3005, 0.001)
    idx = sample_indices(t, 50)
    assert idx[0] == 0 and idx[-1] == len(t) - 1 and np.allclose(np.diff(t[idx])[:-1], 0.02)
    assert np.frombuffer(__import__("base64").b64decode(b64(np.array([1.5, -2.0]))), "<f4").tolist() == [1.5, -2.0]


def test_page_is_self_contained(tmp_path):
    """No external resource: no src/href to a file or the network; three.js's licence notice is in; the
    scene data parses back, and no '</script>' hides in it."""
    model = load_robot("human-arm")
    t, Q = moving(model, 101)
    r = make_result(model, 101, trajectory={"t": t, "q": Q, "q_initial": Q[::-1].copy()})
    r.settings["robot"] = "human-arm"
    r.problem = "a </script> problem"
    page = page_html(build_scene(r))
    assert not re.search(r"""<(script|link|img|iframe|object|embed)\b[^>]*\b(src|href|data)\s*=""", page, flags=re.I)
    assert page.count("<script") == 3  # the scene's JSON, three.js, the page's script: all inline
    assert "three.js authors" in page and "The MIT License" in page
    data = re.search(r'<script type="application/json" id="latentoc-scene">(.*?)</script>', page, flags=re.S).group(1)
    scene = json.loads(data)
    assert scene["title"].startswith("a </script>") and scene["frames"] == 101 and set(scene["motions"]) == {"optimised",
                                                                                                             "initial"}


@pytest.fixture(scope="module")
def pages(tmp_path_factory, panda_reduced):
    """Pages of two results, each with a twin page without the robot (the same camera, ground and
    controls): the Panda (meshes, the initial motion's ghost) and a jump on the ground (capsules, contacts)."""
    from latentoc.robots.human_models import broad_jump_training_motion, build_cmu_humanoid

    d = tmp_path_factory.mktemp("view")
    out = {}
    _, panda, _ = panda_reduced
    t, Q = moving(panda, 201)
    out["panda"] = make_result(panda, 201, trajectory={"t": t, "q": Q, "q_initial": moving(panda, 201, phase=1.0)[1]})
    human = build_cmu_humanoid()
    tj, Qj = broad_jump_training_motion()
    n = len(tj)
    W = np.zeros((n, 6))
    W[:, 0], W[:, 2] = 60.0, 300.0
    out["jump"] = make_result(human, n, tube=None, trajectory={
        "t": tj - tj[0], "q": Qj, "tau": np.zeros((n, human.nv - 6)), "wrench": W, "contact": np.ones(n, np.int8),
        "touchdown": 0.0, "settle": 0.0, "heel_offset": np.array([-0.05, 0.0, 0.0]), "contact_frames": CONTACT_FRAMES,
        "friction": 0.4})
    pages = {}
    for name, r in out.items():
        r.settings["robot"] = "panda" if name == "panda" else None
        scene = build_scene(r)
        page = d / f"{name}.html"
        page.write_text(page_html(scene))
        empty = {k: v for k, v in scene.items() if k != "contacts"}
        empty.update(parts=[], meshes=[], motions={"optimised": ""})
        (d / f"{name}-empty.html").write_text(page_html(empty))
        pages[name] = (page, d / f"{name}-empty.html")
    return pages


def view_of(pixels: np.ndarray) -> np.ndarray:
    """The 3-D view below the title lines and above the control bar."""
    return pixels[70:-60]


def changed(a: np.ndarray, b: np.ndarray) -> int:
    return int(np.sum(np.abs(view_of(a) - view_of(b)).max(axis=2) > 30))


@pytest.mark.slow  # starts a browser four times per page (about 5 s each)
@pytest.mark.parametrize("name", ["panda", "jump"])  # meshes; capsules with contacts
def test_the_page_draws_the_robot_and_animates_in_a_browser(pages, name, tmp_path):
    if chromium() is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    page, empty = pages[name]
    # playing: the clock has moved on. Virtual time is not exact and the motion loops back to t = 0,
    # so the played time, which never wraps, is checked
    html = dom(page, 1300)
    assert "data-error" not in html, "the script failed"
    assert re.search(r'<div id="status"></div>', html)  # "loading..." cleared at the end of the script
    assert int(re.search(r'data-ticks="([0-9]+)"', html).group(1)) >= 2, "only one frame was drawn"
    assert float(re.search(r'data-played="([0-9.]+)"', html).group(1)) > 0, "the animation did not advance"
    # stills at two times (#t= pauses there): the pose drawn is the motion's at that time
    early = screenshot(page, tmp_path / "early.png", 300, url_suffix="#t=0.2")
    blank = screenshot(empty, tmp_path / "blank.png", 300, url_suffix="#t=0.2")
    late = screenshot(page, tmp_path / "late.png", 300, url_suffix="#t=1.2")
    assert changed(early, blank) > 2000, "the robot is not drawn"
    assert changed(early, late) > 300, "the pose does not follow the motion's time"
    if name == "jump":  # the friction cones are the only green in the scene
        r, g, b = (view_of(early)[..., k] for k in range(3))
        assert np.sum((g > r + 30) & (g > b + 10)) > 50


def test_cli_view_writes_the_page(tmp_path, capsys):
    model = load_robot("human-arm")
    t, Q = moving(model, 51)
    make_result(model, 51, trajectory={"t": t, "q": Q}).save(tmp_path / "r")
    assert main(["view", str(tmp_path / "r"), "--rate", "25"]) == 0
    assert (tmp_path / "r" / "view.html").is_file() and "view.html" in capsys.readouterr().out
    assert main(["view", str(tmp_path / "r"), "--html", str(tmp_path / "v" / "a.html")]) == 0
    assert (tmp_path / "v" / "a.html").read_text().startswith("<!doctype html>")
    assert write_html(tmp_path / "r").name == "view.html"
    assert main(["view", str(tmp_path / "nothing")]) == 2
