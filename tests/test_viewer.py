"""The 3-D view: the robot's parts where forward kinematics puts them (the Panda's URDF meshes on a
reduced model, the skeleton's capsules along its bones), the broad jump's contact points where the
jump's own Pinocchio code puts them (all four per foot, with their forces), a page that needs nothing
but itself, and in a real headless browser (chromium): the page loads from the file, draws the robot
(against the same page without it), every contact point's force and cone and the initial motion's
ghost where they are, and its animation advances."""
from __future__ import annotations

import base64
import html
import json
import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from browser import chromium, dom, screenshot
from result_factory import jump_trajectory, make_jump_result, make_result

from latentoc.cli.parser import main
from latentoc.jump.robot.feet import MIRROR, FootGeometry, foot_points
from latentoc.plots import skeleton_segments
from latentoc.robots import example_robot_data_dir, load_robot, robot_urdf
from latentoc.viewer import build_scene, page_html, part_poses, robot_parts, write_html
from latentoc.viewer.scene import FORCE_SCALE, b64, contact_points, sample_indices

FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]


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


def jumps_own_points(model: pin.Model, traj: dict, Q: np.ndarray) -> np.ndarray:
    """(n, 8, 3): the left foot's heel, ball, toe, pad by the jump's own code
    (:func:`latentoc.jump.robot.feet.foot_points`), then their mirror images (the right foot)."""
    geom = FootGeometry.from_result(traj)
    data = model.createData()
    out = []
    for q in Q:
        pin.framesForwardKinematics(model, data, q)
        left = foot_points(model, data, geom).T
        out.append(np.vstack([left, left @ MIRROR]))
    return np.array(out)


def f32(text: str, *shape: int) -> np.ndarray:
    return np.frombuffer(base64.b64decode(text), "<f4").reshape(shape)


def test_contact_points_are_the_jumps_own():
    """Four points per foot named by the trajectory, where the jump's Pinocchio code puts them (the
    right foot: the left one's mirror image, not the offsets' y negated in the right frames); an older
    result (no contact_points, no toe_offset: heel, ball and toe tip); one frame per point (another
    robot's sole corners)."""
    model, traj = jump_trajectory()
    Q = traj["q"][::10]
    P = contact_points(model, traj, Q)
    assert P.shape == (len(Q), 8, 3)
    assert np.allclose(P, jumps_own_points(model, traj, Q), atol=1e-12)
    assert np.all(np.abs(P[0, :, 2]) < 0.01)  # standing: every point on the ground
    old = {k: v for k, v in traj.items() if k not in ("contact_points", "toe_offset")}
    heel_ball_toe = jumps_own_points(model, old, Q)[:, [0, 1, 2, 4, 5, 6]]
    assert np.allclose(contact_points(model, old, Q), heel_ball_toe, atol=1e-12)
    corners = {f"c{j}_offset": np.array([0.1 * (j % 2) - 0.05, 0.03 * (j // 2), -0.04]) for j in range(4)}
    sole = {"contact_frames": np.array(["lfoot"] * 4 + ["rfoot"] * 4),
            "contact_points": np.array(["c0", "c1", "c2", "c3"]), **corners}
    P = contact_points(model, sole, Q)
    data = model.createData()
    for i, q in enumerate(Q):
        pin.framesForwardKinematics(model, data, q)
        left = np.array([data.oMf[model.getFrameId("lfoot")].act(corners[f"c{j}_offset"]) for j in range(4)])
        assert np.allclose(P[i, :4], left) and np.allclose(P[i, 4:], left @ MIRROR)  # the motion is symmetric
    with pytest.raises(ValueError, match="cannot be placed"):
        contact_points(model, {**traj, "contact_points": np.array(["heel", "knee"])}, Q)


def test_samples_and_b64():
    t = np.arange(0, 1.3005, 0.001)
    idx = sample_indices(t, 50)
    assert idx[0] == 0 and idx[-1] == len(t) - 1 and np.allclose(np.diff(t[idx])[:-1], 0.02)
    assert np.frombuffer(base64.b64decode(b64(np.array([1.5, -2.0]))), "<f4").tolist() == [1.5, -2.0]


def test_jump_scene_has_every_contact_point_and_the_ghost():
    """The scene of a broad jump in the export's format: 8 points at the jump's own positions, each
    with its own force (mirrored on the right foot) while loaded; the support polygon of heels and toe
    points; the training motion (q_initial) as the ghost of a floating-base robot. A result with no
    point forces has each foot's wrench at its toe point."""
    r = make_jump_result()
    traj = r.trajectory
    model = pin.Model()
    model.loadFromString(str(traj["model"]))
    scene = build_scene(r)
    C = scene["contacts"]
    idx = sample_indices(traj["t"], 50)
    n = len(idx)
    assert C["names"] == [f"{s} {p}" for s in ("left", "right") for p in ("heel", "ball", "toe", "pad")]
    own = jumps_own_points(model, traj, traj["q"][idx])
    assert np.allclose(f32(C["points"], n, 8, 3), own, atol=1e-5)
    weight = sum(i.mass for i in model.inertias) * 9.81
    F = traj["point_forces"][idx]
    left = np.stack([F[..., 0], np.zeros_like(F[..., 0]), F[..., 1]], axis=-1)
    forces = f32(C["forces"], n, 8, 3) * weight / FORCE_SCALE
    assert np.allclose(forces, np.concatenate([left, left @ MIRROR], axis=1), rtol=1e-5, atol=1e-3)
    assert len(np.unique(np.round(F[0, :, 1]))) == 4  # the points' forces differ: an order mix-up would show
    active = np.frombuffer(base64.b64decode(C["active"]), np.uint8).reshape(n, 8).astype(bool)
    loaded = traj["loaded"][idx].astype(bool) & traj["contact"][idx, None].astype(bool)
    assert np.array_equal(active, np.tile(loaded, (1, 2))) and active[0].all() and not active[n // 2].any()
    assert C["corners"] == 4
    poly = f32(C["polygon"], n, 4, 2)
    ends = own[:, [0, 2, 4, 6], :2]  # heels and toe points, the solver's polygon
    far = np.linalg.norm(poly[:, :, None] - ends[:, None], axis=3).min(axis=2)  # each corner to the nearest end
    assert far.max() < 1e-5 and all(len(np.unique(np.round(c, 4), axis=0)) == 4 for c in poly)
    # the ghost: the training motion, posed like the optimised one; apart from it in the flight only
    parts, _ = robot_parts(model)
    ghost = f32(scene["motions"]["initial"], n, len(parts), 7)
    optimised = f32(scene["motions"]["optimised"], n, len(parts), 7)
    assert np.allclose(ghost, part_poses(model, parts, traj["q_initial"][idx]), atol=1e-5)
    gap = np.abs(ghost[..., 0] - optimised[..., 0]).max(axis=1)
    assert gap[0] < 1e-6 and gap[-1] == pytest.approx(0.3, abs=1e-5)
    older = make_jump_result(point_forces=None, loaded=None, contact_points=None, toe_offset=None)
    old = build_scene(older)["contacts"]
    assert old["names"] == [f"{s} {p}" for s in ("left", "right") for p in ("heel", "ball", "toe")]
    forces = f32(old["forces"], n, 6, 3) * weight / FORCE_SCALE
    W = traj["wrench"][idx]
    assert np.allclose(forces[:, 2], W[:, :3], atol=1e-3) and np.allclose(forces[:, 5], W[:, :3] @ MIRROR, atol=1e-3)
    assert np.allclose(forces[:, [0, 1, 3, 4]], 0.0)


def _replayed(traj, shift: float = 0.5) -> dict[str, np.ndarray]:
    """A replay in simulation.npz's format (times from 0, at its own 2 ms rate) of the result's motion
    moved ``shift`` m along x."""
    t = np.asarray(traj["t"], float)
    ts = np.arange(0.0, t[-1] - t[0] + 1e-9, 0.002)
    Q = np.asarray(traj["q"], float)[np.abs(t[None, :] - t[0] - ts[:, None]).argmin(axis=1)].copy()
    Q[:, 0] += shift
    return {"t": ts, "q": Q}


def test_the_simulated_motion_is_shown_beside_the_plan(tmp_path):
    """A result folder with simulate's replay (simulation.npz): the view's scene has it as a third
    motion, posed like the others at the replay's nearest time; a folder without one, or with an
    unreadable one, has none."""
    r = make_jump_result()
    traj = r.trajectory
    model = pin.Model()
    model.loadFromString(str(traj["model"]))
    sim = _replayed(traj)
    idx = sample_indices(traj["t"], 50)
    parts, _ = robot_parts(model)
    scene = build_scene(r, simulated=sim)
    n = len(idx)
    shown = f32(scene["motions"]["simulated"], n, len(parts), 7)
    t = np.asarray(traj["t"])[idx] - traj["t"][0]
    near = np.abs(sim["t"][None, :] - t[:, None]).argmin(axis=1)
    assert np.allclose(shown, part_poses(model, parts, sim["q"][near]), atol=1e-5)
    optimised = f32(scene["motions"]["optimised"], n, len(parts), 7)
    assert np.allclose(shown[..., 0] - optimised[..., 0], 0.5, atol=1e-5)  # 0.5 m ahead, as replayed
    folder = tmp_path / "jump"
    r.save(folder)

    def motions_in(page: Path) -> set[str]:
        data = re.search(r'<script type="application/json" id="latentoc-scene">(.*?)</script>', page.read_text(), flags=re.S)
        return set(json.loads(data.group(1))["motions"])

    assert motions_in(write_html(folder)) == {"optimised", "initial"}
    np.savez(folder / "simulation.npz", **sim)
    assert motions_in(write_html(folder)) == {"optimised", "initial", "simulated"}
    (folder / "simulation.npz").write_bytes(b"not an npz")
    assert motions_in(write_html(folder)) == {"optimised", "initial"}


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
    controls): the Panda (meshes, the initial motion's ghost) and a broad jump in the export's format
    (capsules, four contact points per foot, the training jump's ghost); for the jump also twins with
    no forces and with no ghost."""
    d = tmp_path_factory.mktemp("view")
    _, panda, _ = panda_reduced
    t, Q = moving(panda, 201)
    out = {"panda": make_result(panda, 201, trajectory={"t": t, "q": Q, "q_initial": moving(panda, 201, phase=1.0)[1]}),
           "jump": make_jump_result()}
    pages = {}
    for name, r in out.items():
        r.settings["robot"] = "panda" if name == "panda" else None
        scene = build_scene(r)
        twins = {"": scene, "-empty": {**{k: v for k, v in scene.items() if k != "contacts"}, "parts": [], "meshes": [],
                                       "motions": {"optimised": ""}}}
        if name == "jump":
            C = scene["contacts"]
            zero = b64(np.zeros(len(base64.b64decode(C["forces"])) // 4))
            twins["-no-forces"] = {**scene, "contacts": {**C, "forces": zero}}
            twins["-no-ghost"] = {**scene, "motions": {"optimised": scene["motions"]["optimised"]}}
            twins["-simulated"] = build_scene(r, simulated=_replayed(r.trajectory))
        for suffix, sc in twins.items():
            (d / f"{name}{suffix}.html").write_text(page_html(sc))
        pages[name] = {suffix: d / f"{name}{suffix}.html" for suffix in twins}
    return pages


def view_of(pixels: np.ndarray) -> np.ndarray:
    """The 3-D view below the title lines and above the control bar."""
    return pixels[70:-60]


def changed(a: np.ndarray, b: np.ndarray) -> int:
    return int(np.sum(np.abs(view_of(a) - view_of(b)).max(axis=2) > 30))


@pytest.mark.slow  # starts a browser four times (about 5 s each); the jump's page: the test below
@pytest.mark.parametrize("name", ["panda"])  # meshes
def test_the_page_draws_the_robot_and_animates_in_a_browser(pages, name, tmp_path):
    if chromium() is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    page, empty = pages[name][""], pages[name]["-empty"]
    # playing: the clock has moved on. Virtual time is not exact and the motion loops back to t = 0,
    # so the played time, which never wraps, is checked
    html = dom(page, 400)
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


def shown_contacts(page, t: float) -> tuple[int, list[dict]]:
    """The frame the page shows paused at time t and what its contact layer draws there."""
    text = dom(page, 300, url_suffix=f"#t={t}")
    assert "data-error" not in text, "the script failed"
    frame = int(re.search(r'data-frame="([0-9]+)"', text).group(1))
    return frame, json.loads(html.unescape(re.search(r'data-contacts="([^"]*)"', text).group(1)))


@pytest.mark.slow  # starts a browser eight times (about 5 s each)
def test_the_jump_page_draws_every_contact_point_in_a_browser(pages, tmp_path):
    """The broad jump in the export's format, in chromium: in the stance all four points of each foot
    have their arrow and cone, where the jump's own code puts the points, each arrow as long as its
    force; in the flight none; the robot, the arrows, the friction cones and the initial motion's
    ghost are drawn (against the same page without them), and the pose follows the time."""
    if chromium() is None:
        pytest.skip("no chromium on this machine (apt-get install chromium; .ci/run installs it)")
    jump = pages["jump"]
    model, traj = jump_trajectory()
    idx = sample_indices(traj["t"], 50)
    weight = sum(i.mass for i in model.inertias) * 9.81
    frame, shown = shown_contacts(jump[""], 0.1)
    i = idx[frame]
    assert traj["t"][i] == pytest.approx(0.1, abs=1e-9)  # the sample at 0.1 s itself (float32 times)
    assert [c["name"] for c in shown] == [f"{s} {p}" for s in ("left", "right") for p in ("heel", "ball", "toe", "pad")]
    assert all(c["arrow"] and c["cone"] for c in shown), "a loaded point's arrow or cone is missing"
    own = jumps_own_points(model, traj, traj["q"][i:i + 1])[0]
    assert np.allclose([c["at"] for c in shown], own, atol=2e-4)
    f = np.hypot(traj["point_forces"][i, :, 0], traj["point_forces"][i, :, 1]) * FORCE_SCALE / weight
    assert np.allclose([c["length"] for c in shown], np.concatenate([f, f]), atol=2e-4)
    frame, shown = shown_contacts(jump[""], 0.5)
    assert not traj["contact"][idx[frame]] and not any(c["arrow"] or c["cone"] for c in shown)
    stance = screenshot(jump[""], tmp_path / "stance.png", 300, url_suffix="#t=0.1")
    bare = screenshot(jump["-no-forces"], tmp_path / "bare.png", 300, url_suffix="#t=0.1")
    assert changed(stance, bare) > 100, "the force arrows are not drawn"
    r, g, b = (view_of(stance)[..., k] for k in range(3))
    assert np.sum((g > r + 30) & (g > b + 10)) > 50, "no friction cone"  # the only green in the scene
    blank = screenshot(jump["-empty"], tmp_path / "blank.png", 300, url_suffix="#t=0.1")
    assert changed(stance, blank) > 2000, "the robot is not drawn"
    flight = screenshot(jump[""], tmp_path / "flight.png", 300, url_suffix="#t=0.6")
    assert changed(stance, flight) > 300, "the pose does not follow the motion's time"
    alone = screenshot(jump["-no-ghost"], tmp_path / "alone.png", 300, url_suffix="#t=0.6")
    assert changed(flight, alone) > 1000, "the initial motion's ghost is not drawn"
    replay = screenshot(jump["-simulated"], tmp_path / "replay.png", 300, url_suffix="#t=0.6")
    assert changed(replay, flight) > 1000, "the simulated motion is not drawn"
    r, g, b = (view_of(replay)[..., k].astype(int) for k in range(3))
    assert np.sum((r > g + 40) & (g > b + 20)) > 200, "the replay is not drawn in orange"  # the only orange


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
