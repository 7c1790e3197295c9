"""Animation: the GIF's frames, size and timing (frame k starts at k/fps), the initial motion's ghost;
the live 3-D view names its missing optional package."""

from __future__ import annotations

import importlib.util

import numpy as np
import pinocchio as pin
import pytest
from PIL import Image
from gif_pixels import colour_pixels

from latentoc.plots import animation
from latentoc.robots.human_arm import arm_trial, build_human_arm
from latentoc.plots import DPI


def test_frame_times_cover_the_motion():
    t = np.arange(0, 1001) / 1000.0  # 1 kHz, 1 s
    idx = animation.frame_times(t, 30)
    assert len(idx) == 31 and idx[0] == 0 and idx[-1] == 1000
    assert np.allclose(t[idx], np.arange(31) / 30, atol=5e-4)


def test_animate_writes_gif(tmp_path):
    t, Q = arm_trial()
    model = build_human_arm()
    t, Q = t[:121], Q[:121]  # 1 s
    p = animation.animate(model, t, Q, tmp_path / "arm.gif", fps=8, plane="yz", title="arm")
    with Image.open(p) as im:
        assert im.format == "GIF"
        assert im.n_frames == len(animation.frame_times(t, 8)) == 9
        w, h = animation.ANIMATION_SIZE
        assert im.size == (int(w * DPI), int(h * DPI))


@pytest.mark.parametrize("fps", [25, 15, 30])
def test_gif_plays_at_the_motions_speed(tmp_path, fps):
    """GIF delays are whole centiseconds: each frame k starts within 5 ms of k/fps, and the loop lasts
    the frames' share of motion time (15 fps with a fixed 6 cs delay played 10 % fast)."""
    delays = animation.frame_delays_cs(50, fps)
    starts = np.concatenate([[0], np.cumsum(delays)]) / 100.0
    assert np.allclose(starts, np.arange(51) / fps, atol=0.005)
    t, Q = arm_trial()
    model = build_human_arm()
    p = animation.animate(model, t[:61], Q[:61], tmp_path / "arm.gif", fps=fps, plane="yz")
    with Image.open(p) as im:
        got = []
        for k in range(im.n_frames):
            im.seek(k)
            got.append(im.info["duration"])
    assert got == [10 * d for d in animation.frame_delays_cs(len(got), fps)]
    assert abs(sum(got) / 1000.0 - len(got) / fps) <= 0.005


def test_gif_shows_the_initial_motion(tmp_path):
    """With the initial motion, its ghost's grey is drawn in every frame: hundreds of pixels more of it
    than without (where only anti-aliased edges come near that grey)."""
    t, Q = arm_trial()
    model = build_human_arm()
    t, Q = t[:61], Q[:61]
    grey = np.array([0xb3, 0xb3, 0xb3])


    with_ghost = animation.animate(model, t, Q, tmp_path / "a.gif", fps=10, plane="yz", initial=Q[::-1].copy())
    without = animation.animate(model, t, Q, tmp_path / "b.gif", fps=10, plane="yz")
    assert min(colour_pixels(with_ghost, grey)) > max(colour_pixels(without, grey)) + 300


def test_animate_checks_lengths(tmp_path):
    model = build_human_arm()
    with pytest.raises(ValueError, match="samples"):
        animation.animate(model, np.arange(3.0), np.zeros((2, model.nq)), tmp_path / "x.gif")


def test_stick_geometry_has_a_capsule_per_bone():
    model = build_human_arm()
    geom = animation.stick_geometry(model)
    assert geom.ngeoms == 7  # 3 segments between joints + 4 bone ends of non-zero length
    data, gdata = model.createData(), pin.GeometryData(geom)
    q = pin.neutral(model)
    pin.updateGeometryPlacements(model, data, geom, gdata, q)
    # the hand capsule is centred halfway along the hand bone
    pin.framesForwardKinematics(model, data, q)
    k = geom.getGeometryId("bone_lhand_end")
    f = model.frames[model.getFrameId("lhand_end")]
    mid = 0.5 * (data.oMi[f.parentJoint].translation + data.oMf[model.getFrameId("lhand_end")].translation)
    assert np.allclose(gdata.oMg[k].translation, mid)


@pytest.mark.parametrize("backend", ["meshcat", "viser"])
def test_view_without_extra_names_package(backend):
    if importlib.util.find_spec(backend) is not None:
        pytest.skip(f"{backend} is installed")
    with pytest.raises(animation.VisualizerNotInstalledError, match=f"pip install {backend}"):
        animation.view(build_human_arm(), np.zeros(7), backend=backend)


def test_view_rejects_unknown_backend():
    with pytest.raises(ValueError, match="backend"):
        animation.view(build_human_arm(), np.zeros(7), backend="gepetto")
