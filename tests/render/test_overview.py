"""Tests for toonmotion.render.overview."""

import colorsys

import numpy as np
import pytest
from PIL import Image

from toonmotion.geometry.segments import closest_points_on_segments
from toonmotion.render.overview import bone_colours, render_overview
from toonmotion.rig.character import RigSettings
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.skeleton import Skeleton

W, H = 40, 50


@pytest.fixture(scope="module")
def character():
    """A grey rectangle (neutral, so it does not shift hues) with a two-bone spine."""
    mask = np.zeros((H, W), dtype=bool)
    mask[5:45, 8:32] = True
    rgba = np.zeros((H, W, 4), dtype=np.uint8)
    rgba[mask] = (200, 200, 200, 255)
    skeleton = Skeleton.from_joints(
        [("hip", None, (20.0, 25.0)), ("chest", "hip", (20.0, 8.0)), ("feet", "hip", (20.0, 42.0))]
    )
    return rig_drawing(rgba, skeleton=skeleton, settings=RigSettings(spacing=5.0))


def _hue(rgb):
    return colorsys.rgb_to_hsv(*(np.asarray(rgb, dtype=float) / 255))[0]


def _hue_distance(a, b):
    d = abs(a - b) % 1.0
    return min(d, 1.0 - d)


@pytest.mark.parametrize("height", [100, 333, 400])
def test_overview_is_rgb_and_sized_by_the_height(character, height):
    image = render_overview(character, height=height)
    assert isinstance(image, Image.Image)
    assert image.mode == "RGB"
    # Each panel's drawing area is `height` tall, under a title strip.
    assert height < image.height <= height + max(28, height // 22) + 12
    panel_width = W * height / H
    assert abs(image.width - (2 * panel_width + 30)) <= 2


def test_right_panel_colours_interior_triangles_by_bone(character):
    height = 400
    scale = height / H
    image = np.asarray(render_overview(character, height=height))
    title = max(28, height // 22)
    left_width = round(W * scale * 2) // 2
    x0, y0 = 20 + left_width, title  # where the right panel's drawing area starts

    mesh, binding, skeleton = character.mesh, character.binding, character.skeleton
    colours = bone_colours(len(skeleton.bones))
    bones = skeleton.bones
    A, B = skeleton.positions[bones[:, 0]], skeleton.positions[bones[:, 1]]
    centroids = mesh.V[mesh.F].mean(axis=1)
    _, distance = closest_points_on_segments(centroids, A, B)
    joint_distance = np.linalg.norm(centroids[:, None] - skeleton.positions[None], axis=2)
    # Interior triangles well clear of the bone lines and joint dots drawn on top.
    clear = (~binding.joint_triangle) & (distance.min(axis=1) > 1.5) & (joint_distance.min(axis=1) > 1.5)
    assert clear.sum() >= 10
    seen = set()
    for t in np.flatnonzero(clear):
        bone = binding.bone[mesh.F[t, 0]]
        x, y = centroids[t]
        pixel = image[int(round(y0 + y * scale)), int(round(x0 + x * scale))]
        r, g, b = pixel / 255
        assert colorsys.rgb_to_hsv(r, g, b)[1] > 0.15, f"triangle {t} is not coloured: {pixel}"
        assert _hue_distance(_hue(pixel), _hue(colours[bone])) < 0.03, (t, pixel, colours[bone])
        seen.add(int(bone))
    assert seen == {skeleton.bone_names.index("chest"), skeleton.bone_names.index("feet")}
    # Outside the figure the right panel is (nearly) white.
    corner = image[int(y0 + 1 * scale), int(x0 + 2 * scale)]
    assert np.all(corner >= 245)


def test_overview_draws_fallback_vertices_without_error(character):
    # A skeleton partly off the figure still renders; its fallback vertices (the thesis's rule) are
    # marked.
    skeleton = Skeleton.from_joints([("a", None, (36.0, 44.0)), ("b", "a", (36.0, 6.0))])
    ch = rig_drawing(character.texture, skeleton=skeleton,
                     settings=RigSettings(spacing=5.0, decomposition="straight"))
    assert ch.binding.fallback.any()
    image = np.asarray(render_overview(ch, height=200))
    assert image.shape[2] == 3
    # Some pixels carry the red fallback marker.
    red = (image[..., 0] > 200) & (image[..., 1] < 60) & (image[..., 2] < 60)
    assert red.any()


@pytest.mark.parametrize("count", [0, 1, 5, 16, 40])
def test_bone_colours_are_distinct(count):
    colours = bone_colours(count)
    assert colours.shape == (count, 3)
    assert colours.dtype == np.uint8
    assert len({tuple(c) for c in colours}) == count
    hues = [_hue(c) for c in colours]
    for i in range(count):
        for j in range(i + 1, min(count, i + 6)):  # neighbours in bone order differ clearly
            assert _hue_distance(hues[i], hues[j]) > 0.05
    if count:
        assert colours.astype(int).max(axis=1).min() > 150  # bright enough to read


def test_bone_colours_are_stable():
    np.testing.assert_array_equal(bone_colours(7), bone_colours(7))
    np.testing.assert_array_equal(bone_colours(7)[:3], bone_colours(3))
