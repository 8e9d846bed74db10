"""Tests for toonmotion.render.track_overlay."""

import numpy as np

from toonmotion.render.track_overlay import draw_tracking


def test_rectangles_and_bones_are_drawn_and_the_frame_is_left_alone():
    frame = np.full((60, 80, 3), 200, dtype=np.uint8)
    positions = np.array([[20.0, 30.0], [60.0, 30.0]])
    sizes = np.array([[10.0, 10.0], [12.0, 8.0]])
    out = draw_tracking(frame, positions, sizes, np.array([-1, 0]), confidence=np.array([1.0, 0.0]))
    assert (frame == 200).all()
    assert out.shape == frame.shape and out.dtype == np.uint8
    assert tuple(out[30, 40]) != (200, 200, 200)  # the bone
    assert tuple(out[25, 20]) == (0, 255, 0)  # a sure joint's rectangle edge is green
    assert tuple(out[26, 60]) == (255, 0, 0)  # an unsure one's is red
