"""Tests for toonmotion.capture.synthetic: the textured limb figure used to measure tracking."""

import numpy as np
import pytest

from toonmotion.capture.synthetic import limb_figure_frames
from toonmotion.errors import TrackingError

PARENTS = np.array([-1, 0, 1])


def _arm(frames=4):
    P = np.array([[100.0, 100.0], [160.0, 100.0], [220.0, 100.0]])
    return np.repeat(P[None], frames, axis=0)


def test_frames_have_the_size_and_the_figure_is_drawn():
    points = _arm()
    frames, radius = limb_figure_frames(points, PARENTS, size=(320, 200), width=12, seed=1)
    assert frames.shape == (4, 200, 320, 3) and frames.dtype == np.uint8
    assert radius == pytest.approx(9.0)
    # A still figure renders the same picture every frame.
    assert (frames == frames[0]).all()
    # Pixels along the limb differ from those away from the figure's texture statistics.
    assert not np.array_equal(frames[0, 100, 90:230], frames[0, 20, 90:230])


def test_the_nearer_part_hides_the_farther():
    points = _arm(2)
    points[:, 2] = (100.0, 100.0)  # the hand folds back onto the shoulder
    near_hand = np.array([[5.0, 5.0, 0.0]] * 2)
    near_shoulder = np.array([[0.0, 5.0, 5.0]] * 2)
    a, _ = limb_figure_frames(points, PARENTS, depth=near_hand, size=(320, 200), width=12, seed=3)
    b, _ = limb_figure_frames(points, PARENTS, depth=near_shoulder, size=(320, 200), width=12, seed=3)
    assert not np.array_equal(a[0, 95:106, 95:106], b[0, 95:106, 95:106])


def test_bad_points_are_refused():
    with pytest.raises(TrackingError, match=r"points must be \(frames, 3, 2\)"):
        limb_figure_frames(np.zeros((4, 2, 2)), PARENTS)


def test_the_flat_style_is_flat_colours_and_outlines_over_plain_paper():
    frames, radius = limb_figure_frames(_arm(2), PARENTS, size=(320, 200), width=12, seed=1, style="flat")
    frame = frames[0]
    assert radius == pytest.approx(9.0) and (frames == frame).all()
    paper = frame[5, 5]
    assert (frame[:60] == paper).all() and (frame[140:] == paper).all()  # nothing above or below the arm
    # Inside a band the colour is one flat fill; across it, fill, then a dark outline, then paper.
    assert len(np.unique(frame[100, 104:148], axis=0)) == 1
    column = frame[85:116, 125].astype(int).sum(axis=1)
    assert column.min() < 150 < frame[100, 125].astype(int).sum()  # the ink is darker than the fill
    # Anti-aliased edges aside, the picture holds paper, ink and at most two fills.
    _, counts = np.unique(frame.reshape(-1, 3), axis=0, return_counts=True)
    assert np.sort(counts)[::-1][:4].sum() >= 0.98 * counts.sum()


def test_an_unknown_style_is_refused():
    with pytest.raises(TrackingError, match=r"the figure's style must be one of textured, flat, got 'oil'"):
        limb_figure_frames(_arm(), PARENTS, style="oil")
