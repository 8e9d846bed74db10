"""Tests for toonmotion.render.overlay."""

import numpy as np
import pytest

from toonmotion.errors import SettingsError
from toonmotion.geometry.segments import closest_points_on_segments
from toonmotion.render.overlay import draw_mesh, draw_reference, draw_skeleton

H, W = 60, 80
CANVAS = (-0.5, -0.5, W - 0.5, H - 0.5)


def _frame():
    frame = np.zeros((H, W, 4), np.uint8)
    frame[:, : W // 2] = (250, 240, 230, 255)  # opaque left half, transparent right half
    return frame


def _distance_to_segments(A, B):
    ys, xs = np.mgrid[0:H, 0:W]
    points = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(float)
    return closest_points_on_segments(points, A, B)[1].min(axis=1).reshape(H, W)


def _changed(a, b):
    return np.any(a != b, axis=2)


def test_reference_line_changes_pixels_along_the_bone_and_only_near_it():
    frame = _frame()
    before = frame.copy()
    positions = np.array([[10.0, 10.0], [65.0, 45.0], [20.0, 50.0]])
    bones = np.array([[0, 1], [0, 2]])
    out = draw_reference(frame, positions, bones, view=CANVAS, width=2)
    assert np.array_equal(frame, before)  # input untouched
    assert out.shape == frame.shape and out.dtype == np.uint8
    distance = _distance_to_segments(positions[bones[:, 0]], positions[bones[:, 1]])
    changed = _changed(out, frame)
    assert not changed[distance > 2.5].any()
    # Every pixel centre close to a bone's middle stretch is painted, reddish and opaque.
    along = distance < 0.5
    assert along.sum() > 60
    assert changed[along].all()
    assert np.all(out[along, 0] > 150) and np.all(out[along, 1] < 120) and np.all(out[along, 3] == 255)


def test_skeleton_draws_discs_at_joints():
    frame = _frame()
    positions = np.array([[20.0, 30.0], [60.0, 30.0]])
    out = draw_skeleton(frame, positions, [[0, 1]], view=CANVAS, width=1, joint_radius=5)
    changed = _changed(out, frame)
    # A disc of radius 5 around each joint, not just the 1-pixel line.
    for x, y in positions.astype(int):
        assert changed[y - 4:y + 5, x - 3:x + 4].all()
    assert not changed[30 - 4, 40] and changed[30, 40]
    assert not changed[:22].any() and not changed[39:].any()
    assert tuple(out[30, 60]) == (20, 90, 230, 255)


def test_overlay_is_placed_through_the_view():
    frame = np.zeros((H, W, 4), np.uint8)
    view = (10.0, 10.0, 30.0, 25.0)  # scale 4, offset (-40.5, -40.5): fills the frame
    out = draw_reference(frame, [[12.0, 15.0], [28.0, 15.0]], [[0, 1]], view=view, width=1)
    rows = np.flatnonzero(out[..., 3].any(axis=1))
    cols = np.flatnonzero(out[..., 3].any(axis=0))
    assert rows.min() >= 18 and rows.max() <= 21  # y = 15 * 4 - 40.5 = 19.5
    assert abs(cols.min() - 7.5) <= 1.5 and abs(cols.max() - 71.5) <= 1.5


def test_translucent_colour_blends_over_the_frame():
    frame = _frame()
    out = draw_mesh(frame, np.array([[0.0, 30.0], [79.0, 30.0], [40.0, 59.0]]), [[0, 1, 2]],
                    view=CANVAS, colour=(0, 0, 0, 128), width=1)
    # Over the opaque half: darker but still opaque. Over the transparent half: black, alpha ~128.
    assert np.all(out[30, 5:35, 3] == 255)
    assert np.all(out[30, 5:35, 0] < 200) and np.all(out[30, 5:35, 0] > 100)
    assert np.all((out[30, 45:75, 3] > 100) & (out[30, 45:75, 3] <= 128))
    assert np.all(out[30, 45:75, :3] == 0)


def test_mesh_draws_each_edge():
    frame = np.zeros((H, W, 4), np.uint8)
    U = np.array([[10.0, 10.0], [70.0, 10.0], [70.0, 50.0], [10.0, 50.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    out = draw_mesh(frame, U, F, view=CANVAS, width=1)
    for (ax, ay), (bx, by) in [(U[0], U[1]), (U[1], U[2]), (U[0], U[2]), (U[3], U[0])]:
        mid = np.rint([(ax + bx) / 2, (ay + by) / 2]).astype(int)
        assert out[mid[1], mid[0], 3] > 0
    assert not out[30, 20:30].any()  # inside a triangle, away from edges


def test_empty_inputs_return_an_unchanged_copy():
    frame = _frame()
    out = draw_skeleton(frame, np.zeros((0, 2)), np.zeros((0, 2), int), view=CANVAS)
    assert np.array_equal(out, frame) and out is not frame


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda f: draw_reference(f[..., :3], [[0, 0], [1, 1]], [[0, 1]], view=CANVAS), "frame must be"),
        (lambda f: draw_reference(f, [[0, 0], [np.nan, 1]], [[0, 1]], view=CANVAS), "NaN"),
        (lambda f: draw_reference(f, [[0, 0], [1, 1]], [[0, 2]], view=CANVAS), "bones index"),
        (lambda f: draw_reference(f, [[0, 0], [1, 1]], [[0, 1]], view=CANVAS, width=0), "width"),
        (lambda f: draw_reference(f, [[0, 0], [1, 1]], [[0, 1]], view=CANVAS, colour=(1, 2)), "colour"),
        (lambda f: draw_skeleton(f, [[0, 0], [1, 1]], [[0, 1]], view=CANVAS, joint_radius=-1), "radius"),
        (lambda f: draw_mesh(f, [[0, 0], [1, 1]], [[0, 1, 2]], view=CANVAS), "F index"),
        (lambda f: draw_mesh(f, [[0, 0], [1, 1], [0, 1]], [[0, 1, 2]], view=(0, 0, 0, 0)), "view"),
    ],
)
def test_bad_input_is_a_settings_error(call, match):
    with pytest.raises(SettingsError, match=match):
        call(_frame())
