"""Tests for toonmotion.render.sequence: an animation's frames in one view, written to disk."""

import numpy as np
import pytest
from PIL import Image

from toonmotion.animate.animation import animate_timeline
from toonmotion.deform.deformer import Deformer
from toonmotion.render.frame import render_frame
from toonmotion.render.sequence import animation_view, render_animation, write_animation
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def animated():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    return character, animate_timeline(Deformer(character), sample_keyframes(skeleton))


def test_the_view_holds_the_canvas_and_every_frame(animated):
    character, animation = animated
    x0, y0, x1, y1 = animation_view(character, animation)
    w, h = character.size
    assert x0 <= -0.5 and y0 <= -0.5 and x1 >= w - 0.5 and y1 >= h - 0.5
    for _, U in animation.meshes:
        assert (U.min(axis=0) >= (x0, y0)).all() and (U.max(axis=0) <= (x1, y1)).all()


def test_every_frame_is_the_frame_renderer_s_picture_in_the_shared_view(animated):
    character, animation = animated
    view = animation_view(character, animation)
    pictures = list(render_animation(character, animation, size=(60, 80), overlays=("skeleton",)))
    assert len(pictures) == len(animation.meshes)
    for t in (0, len(pictures) // 2, len(pictures) - 1):
        frame, U = animation.meshes[t]
        expected = render_frame(
            character, U, pose=animation.motion.pose(frame), size=(60, 80), view=view, overlays=("skeleton",)
        )
        np.testing.assert_array_equal(pictures[t], expected)


def test_png_frames_are_written_with_progress_and_the_size_reported(animated, tmp_path):
    character, animation = animated
    calls = []
    count, size = write_animation(
        tmp_path / "frames",
        character,
        animation,
        size=(30, 40),
        progress=lambda stage, i, n: calls.append((stage, i, n)),
    )
    assert count == len(animation.meshes) == len(calls) and size == (30, 40)
    assert calls[-1] == ("rendering", count, count)
    files = sorted((tmp_path / "frames").glob("*.png"))
    assert len(files) == count and Image.open(files[0]).size == (30, 40)
    assert Image.open(files[0]).mode == "RGBA"


def test_a_gif_is_composited_over_white_when_the_background_is_transparent(animated, tmp_path):
    character, animation = animated
    count, _ = write_animation(tmp_path / "a.gif", character, animation, size=(30, 40))
    with Image.open(tmp_path / "a.gif") as gif:
        assert gif.n_frames == count
        corner = np.asarray(gif.convert("RGB"))[0, 0]
    assert corner.tolist() == [255, 255, 255]
