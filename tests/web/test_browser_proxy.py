"""The 3D panel driven in Chromium as a user would: the sample character's animation lifted with a
prior from the library, from a view set by dragging the gizmo's camera; a balloon added and the
scene simulated, played in the Timeline, and exported; each output checked against the same
library calls."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from tests.conftest import SHARED_DATA, _require
from toonmotion import api
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.io.bvh import load_bvh
from toonmotion.io.frames import load_frames
from toonmotion.io.image import load_image
from toonmotion.io.pose_json import load_keyframes, save_keyframes
from toonmotion.io.proxy_json import load_proxy
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character
from toonmotion.scene.elements import Balloon
from toonmotion.web.background import serving

PRIOR = "cmu_16_07_jump.bvh"


@pytest.fixture(scope="module")
def editor(tmp_path_factory):
    """The editor on the half-size sample character keyed with the sample key-frames, with the
    shared motion-capture clips as its library of priors: ``(url, project folder)``."""
    library = _require(SHARED_DATA / "mocap")
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("editor3d") / "hero"
    character = rig_drawing(drawing, skeleton=skeleton)
    api.save_project(folder, character)
    save_keyframes(folder / "keys.json", character.skeleton, sample_keyframes(character.skeleton, fps=6.0))
    with serving(folder, library=library) as served:
        yield served.page, folder


def _animation(folder):
    character = api.load_project(folder)
    timeline = load_keyframes(folder / "keys.json", character.skeleton)
    return character, api.animate_character(Deformer(character, DeformSettings(compiled=True)), timeline)


def _wait_status(page, start, timeout=180_000):
    page.wait_for_function(f"document.getElementById('status').textContent.startsWith({start!r})",
                           timeout=timeout)


def test_lift_with_the_gizmo_s_view_add_a_balloon_play_the_scene_and_export_it(page, editor):
    folder = editor[1]
    page.click("nav button[data-panel=proxy]")
    page.wait_for_function("document.querySelectorAll('#proxy-prior option').length > 1")
    assert page.locator("#proxy-3d").is_visible() and page.locator("#proxy-2d").is_visible()
    page.select_option("#proxy-prior", f"library/{PRIOR}")
    # Drag the gizmo's camera 30 px left: the azimuth turns by 30 degrees.
    box = page.locator("#proxy-gizmo").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + 60)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] / 2 - 30, box["y"] + 60, steps=5)
    page.mouse.up()
    page.click("#proxy-lift")
    _wait_status(page, "lifted")
    found = page.locator("#proxy-found").text_content()
    assert found.startswith("view 30°, 0° (given)"), found

    character, animation = _animation(folder)
    expected, _ = api.lift_animation(character, animation, load_bvh(SHARED_DATA / "mocap" / PRIOR),
                                     view=(30.0, 0.0))
    assert np.allclose(load_proxy(folder / "proxy3d" / "proxy.json").points, expected.points, atol=1e-9)
    # The orbit view draws the proxy: its canvas is no longer blank.
    orbit = np.asarray(Image.open(io.BytesIO(page.locator("#proxy-3d").screenshot())).convert("RGB"), float)
    assert (np.abs(orbit - orbit[2, 2]).sum(axis=2) > 60).mean() > 0.01

    page.select_option("#proxy-kind", "balloon")
    page.select_option("#proxy-marker", "right_hand")
    page.click("#proxy-add")
    assert page.locator("#proxy-elements li").count() == 1
    page.click("#proxy-simulate")
    _wait_status(page, "simulated")
    proxy = load_proxy(folder / "proxy3d" / "proxy.json")
    pictures, limbs = api.animation_frames(character, animation, proxy)
    motion = api.simulate_scene(proxy, [Balloon("right_hand")])
    made = list(api.composite_scene(proxy, pictures, motion, background=(255, 255, 255), limbs=limbs))
    for t in (0, len(made) - 1):
        assert np.array_equal(load_image(folder / "proxy3d" / "scene" / f"{t:04d}.png")[..., :3], made[t])

    # The Timeline plays the scene: at frame 12 the stage shows the composited frame's balloon.
    page.click("nav button[data-panel=timeline]")
    page.check("#timeline-scene")
    page.evaluate("""() => { const s = document.getElementById('timeline-scrub'); s.value = '12';
                             s.dispatchEvent(new Event('input')); }""")
    page.wait_for_timeout(600)
    stage = np.asarray(Image.open(io.BytesIO(page.locator("#stage").screenshot())).convert("RGB"), float)
    balloon_red = (stage[..., 0] > 150) & (stage[..., 1] < 80) & (stage[..., 2] < 80)
    scene_red = (made[12][..., 0] > 150) & (made[12][..., 1] < 80) & (made[12][..., 2] < 80)
    assert scene_red.sum() > 50 and balloon_red.sum() > 50

    page.click("nav button[data-panel=proxy]")
    page.wait_for_function("document.getElementById('proxy-scene').textContent.includes('composited')")
    page.select_option("#proxy-format", "mp4")
    page.fill("#proxy-name", "balloon")
    page.click("#proxy-export")
    _wait_status(page, "exported")
    link = page.locator("#proxy-files a")
    assert link.text_content() == "exports/balloon.mp4"
    frames, _ = load_frames(folder / "exports" / "balloon.mp4")
    assert len(frames) == len(made)
    assert page.errors == [] and page.locator("#error").is_hidden()


def test_a_reload_shows_the_proxy_and_the_scene_again_and_errors_are_one_line(page, editor):
    page.reload()
    page.wait_for_function("document.getElementById('status').textContent === 'ready'", timeout=30_000)
    page.click("nav button[data-panel=proxy]")
    page.wait_for_function("document.getElementById('proxy-scene').textContent.includes('composited')")
    assert page.locator("#proxy-found").text_content().startswith("view 30°, 0° (given)")
    assert page.locator("#proxy-elements li").count() == 1
    page.select_option("#proxy-kind", "cape")
    page.select_option("#proxy-marker", "neck")
    page.select_option("#proxy-marker2", "neck")
    page.click("#proxy-add")
    page.click("#proxy-simulate")
    page.wait_for_function("!document.getElementById('error').hidden", timeout=60_000)
    said = page.locator("#error").text_content()
    assert said == "a cape hangs between two markers, got 'neck' twice", said
    assert page.errors == []
