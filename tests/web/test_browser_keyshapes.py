"""The Key-shapes panel driven in Chromium as a user would: a generated cartoon (sample_cartoons) sent
as footage, its key outlines given on their frames, the model built, the footage captured and the
result retargeted onto the sample character's key poses and played in the Timeline; every output
checked against the same library calls made directly.

Without Chromium these tests skip, except under CI=true (tests/web/conftest.py).
"""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from PIL import Image

from toonmotion import api
from toonmotion.io.frames import load_frames
from toonmotion.io.keyshape_json import load_keymotion
from toonmotion.io.motion_json import load_motion
from toonmotion.io.pose_json import load_keyframes
from toonmotion.sample_cartoons import morphing_character

KEY_POSES = (0, 5, 9)  # the Timeline's keys, one per key-shape


@pytest.fixture(scope="module")
def cartoon():
    return morphing_character(frames=24, hold=1)


@pytest.fixture(scope="module")
def files(cartoon, tmp_path_factory):
    """The cartoon as a GIF and its outlines on the key frames as a contours file."""
    folder = tmp_path_factory.mktemp("cartoon")
    pictures = [Image.fromarray(f) for f in cartoon.frames]
    pictures[0].save(folder / "hop.gif", save_all=True, append_images=pictures[1:], duration=42, loop=0)
    keys = cartoon.contours[list(cartoon.key_frames)]
    (folder / "keys.json").write_text(json.dumps({"format": "toonmotion.contours", "version": 1, "fps": 24,
                                                  "closed": True, "contours": keys.tolist()}))
    return folder


def _status(page, text, timeout=30_000):
    page.wait_for_function("(t) => document.getElementById('status').textContent.startsWith(t)", arg=text,
                           timeout=timeout)


def _key_the_poses(page, folder):
    character = api.load_project(folder)
    poses = [character.skeleton.positions, api.rotate_joint(character, "right_elbow", -1.0).positions,
             api.rotate_joint(character, "left_knee", 0.7).positions]
    page.locator("#panels button[data-panel=timeline]").click()
    for frame, pose in zip(KEY_POSES, poses, strict=True):
        page.evaluate("""async ([frame, positions]) => {
            const c = window.toonmotion;
            const reply = await c.live.request({type: "set_key", frame, positions, edits: []});
            c.project.keys = reply.keys;
        }""", [frame, pose.tolist()])
    return character


def test_a_cartoon_is_captured_from_footage_retargeted_and_played_in_the_timeline(
        page, editor, cartoon, files):
    folder = editor[1]
    character = _key_the_poses(page, folder)
    page.locator("#panels button[data-panel=keyshapes]").click()
    _status(page, "give the key outlines")
    page.set_input_files("#ks-footage-file", str(files / "hop.gif"))
    _status(page, "pick the layer")
    page.uncheck("#ks-resample")  # the outlines are in correspondence already
    page.set_input_files("#ks-outlines-file", str(files / "keys.json"))
    _status(page, "3 outlines read")
    for i, frame in enumerate(cartoon.key_frames):  # the frames they are drawn on
        page.locator("#ks-keys li input").nth(i).fill(str(frame))
        page.locator("#ks-keys li input").nth(i).dispatch_event("change")
    page.click("#ks-build")
    _status(page, "model built")
    page.wait_for_function("document.getElementById('ks-sheet').naturalWidth > 0")
    keys = cartoon.contours[list(cartoon.key_frames)]
    sheet = api.keyshape_sheet(api.keyshape_space(keys))
    shown = page.evaluate("[document.getElementById('ks-sheet').naturalWidth, "
                          "document.getElementById('ks-sheet').naturalHeight]")
    assert shown == [sheet.shape[1], sheet.shape[0]]

    page.click("#ks-capture-video")
    _status(page, "captured")
    state = page.evaluate("window.toonmotion.keyshapes.state()")
    frames, _ = load_frames(folder / "footage" / "clip.gif")  # the footage as the server read it
    video = api.capture_video(frames, keys, key_frames=list(cartoon.key_frames))
    found = api.capture_contours(video.shapes, keys)
    assert np.allclose(state["capture"]["weights"], found.weights, atol=1e-5)
    assert np.allclose(state["capture"]["shapes"], video.shapes, atol=0.01)
    saved, fps, _ = load_keymotion(folder / "keyshapes" / "motion.json")
    assert np.array_equal(saved.weights, found.weights)
    # The captured outline lies on the drawn character (within a pixel on average).
    assert np.hypot(*(video.shapes - cartoon.contours).T).mean() < 1.5
    page.locator("#ks-scrub").fill("12")
    page.wait_for_function("document.getElementById('ks-frame').textContent === '12'")
    legend = page.locator("#ks-legend").text_content()
    assert f"key 1: {found.weights[12][0]:.2f}" in legend

    page.click("#ks-retarget")
    page.wait_for_function("document.getElementById('timeline-source') && "
                           "!document.getElementById('timeline-source').hidden")
    keyed = load_keyframes(folder / "keys.json", character.skeleton)  # the Timeline's keys, in order
    poses = None
    for i, key in enumerate(keyed.keys):
        poses = api.set_key(character.skeleton, poses, i, key.pose, fps=fps)
    expected = api.retarget_keyposes(found, keys, character.skeleton, poses, fps=fps,
                                     reference=character.mesh.V[character.mesh.boundary[0]])
    motion = load_motion(folder / "keyshapes" / "retargeted.json")
    assert np.allclose(motion.positions, expected.positions, atol=1e-6)
    # Played in the Timeline: each frame shown is the retargeted motion's.
    page.click("#timeline-play")
    page.wait_for_function("window.toonmotion.frame >= 6", timeout=20_000)
    page.click("#timeline-play")
    page.wait_for_timeout(300)  # the frame asked for last has come back
    at, pose = page.evaluate("[window.toonmotion.frame, window.toonmotion.pose]")
    assert np.allclose(pose, expected.positions[at], atol=1e-6)
    assert page.errors == [] and page.locator("#error").is_hidden()
    page.click("#timeline-source button")  # back to the key-frames
    assert page.locator("#timeline-source").is_hidden()


def test_an_outline_drawn_on_the_stage_is_resampled_by_the_server_and_errors_are_one_line(page):
    page.locator("#panels button[data-panel=keyshapes]").click()
    _status(page, "captured")  # the last test's work, read back from the project on mount
    assert page.locator("#ks-keys li").count() == 3
    page.locator("#ks-keys .remove").nth(2).click()
    page.locator("#ks-keys .remove").nth(1).click()
    assert page.locator("#ks-keys li").count() == 1
    page.click("#ks-draw")
    centre = np.array([120.0, 100.0])
    ring = [centre + 30 * np.array([np.cos(a), np.sin(a)]) for a in np.linspace(0, 2 * np.pi, 41)]
    points = [page.evaluate("(p) => window.toonmotion.keyshapes.screen(p)", p.tolist()) for p in ring]
    page.mouse.move(*points[0])
    page.mouse.down()
    for p in points[1:]:
        page.mouse.move(*p)
    page.mouse.up()
    outlines = page.evaluate("window.toonmotion.keyshapes.outlines()")
    assert len(outlines) == 2 and len(outlines[1]["points"]) >= 30
    drawn = np.asarray(outlines[1]["points"])
    assert np.allclose(np.hypot(*(drawn - centre).T), 30, atol=1.5)
    page.uncheck("#ks-resample")  # 96 points and a drawn curve of another count: refused in one line
    page.click("#ks-build")
    page.wait_for_function("!document.getElementById('error').hidden")
    error = page.locator("#error").text_content()
    assert error.startswith("the key outlines must be lists of [x, y] points with the same count")
    page.check("#ks-resample")
    page.fill("#ks-points", "40")
    page.click("#ks-build")
    _status(page, "model built")
    state = page.evaluate("window.toonmotion.keyshapes.state()")
    assert [len(k) for k in state["model"]["keys"]] == [40, 40] and state["capture"] is None
    assert page.locator("#error").is_hidden()
    picture = np.asarray(Image.open(io.BytesIO(page.locator("#ks-sheet").screenshot())).convert("RGB"))
    assert (picture < 200).any()  # the sheet shows outlines
