"""Tests for toonmotion.capture.setup."""

import cv2
import numpy as np
import pytest

from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.capture.setup import check_setup, rectangle_sizes, suggest_setup
from toonmotion.errors import TrackingError
from toonmotion.rig.skeleton import Skeleton

LOW, HIGH = FigureTuning().size_low, FigureTuning().size_high

SHOULDER, HIP = (60, 50), (60, 95)
HANDS, FEET = [(25, 75), (95, 75)], [(35, 145), (85, 145)]


def _stick_figure(dy=0, height=160):
    """A stick figure 7 px thick with a round head, 120 wide; ``dy`` moves it down."""
    mask = np.zeros((height, 120), np.uint8)

    def at(p):
        return p[0], p[1] + dy

    cv2.circle(mask, at((60, 25)), 12, 1, -1)
    limbs = [((60, 30), HIP)] + [(SHOULDER, h) for h in HANDS] + [(HIP, f) for f in FEET]
    for a, b in limbs:
        cv2.line(mask, at(a), at(b), 1, 7)
    return mask.astype(bool)


def _inside(skeleton, sizes, w, h):
    lo = skeleton.positions - sizes / 2
    hi = skeleton.positions + sizes / 2
    return bool(np.all(lo >= -0.5 - 1e-9) and np.all(hi <= np.array([w, h]) - 0.5 + 1e-9))


def _nearest(skeleton, point):
    return float(np.min(np.linalg.norm(skeleton.positions - np.array(point, float), axis=1)))


def test_suggested_joints_sit_at_both_ends_of_every_limb():
    mask = _stick_figure()
    skeleton, sizes = suggest_setup(mask)
    assert sizes.shape == (len(skeleton), 2)
    for point in [SHOULDER, HIP, *HANDS, *FEET]:
        assert _nearest(skeleton, point) <= 7.0, point
    assert _nearest(skeleton, (60, 25)) <= 12.0  # in the head
    assert _inside(skeleton, sizes, 120, 160)
    check_setup(skeleton, sizes, (120, 160))


def test_rectangles_follow_the_figure_thickness_within_the_range():
    skeleton, sizes = suggest_setup(_stick_figure())
    assert np.all(sizes >= LOW) and np.all(sizes <= HIGH)
    np.testing.assert_array_equal(sizes[:, 0], sizes[:, 1])
    # Limbs are 7 px thick: their joints get small squares; the head is 24 px across.
    hand = np.argmin(np.linalg.norm(skeleton.positions - HANDS[0], axis=1))
    assert sizes[hand, 0] <= 10
    head = np.argmin(np.linalg.norm(skeleton.positions - (60, 25), axis=1))
    assert sizes[head, 0] >= 14


def test_rectangles_at_the_frame_edge_are_shrunk_inside():
    mask = _stick_figure(dy=13, height=160)  # feet at y = 158, a pixel off the bottom edge
    skeleton, sizes = suggest_setup(mask, max_bone=20)
    assert _inside(skeleton, sizes, 120, 160)
    assert np.all(sizes > 0)
    assert sizes.min() < LOW  # the feet's rectangles had to shrink
    check_setup(skeleton, sizes, (120, 160))


def test_suggest_setup_of_an_empty_mask_raises():
    with pytest.raises(TrackingError, match="empty"):
        suggest_setup(np.zeros((20, 20), bool))


def _two_joints():
    return Skeleton.from_joints([("hip", None, (20, 20)), ("knee", "hip", (20, 35))])


@pytest.mark.parametrize("bad", [0.0, -4.0, np.nan, np.inf])
def test_check_setup_rejects_sizes_that_are_not_positive_and_finite(bad):
    sizes = np.array([[8.0, 8.0], [8.0, bad]])
    with pytest.raises(TrackingError, match="joint 'knee' has rectangle size"):
        check_setup(_two_joints(), sizes, (40, 40))


def test_check_setup_rejects_a_rectangle_outside_the_frame():
    sizes = np.array([[8.0, 8.0], [8.0, 12.0]])  # knee's spans y 29 to 41
    check_setup(_two_joints(), sizes, (40, 42))
    message = r"the rectangle of joint 'knee', \(16, 29\) to \(24, 41\), is not inside the 40x40 frame"
    with pytest.raises(TrackingError, match=message):
        check_setup(_two_joints(), sizes, (40, 40))
    with pytest.raises(TrackingError, match="joint 'hip'"):
        check_setup(_two_joints(), sizes, (23, 40))


def test_check_setup_rejects_sizes_of_the_wrong_shape():
    with pytest.raises(TrackingError, match="each of the 2 joints"):
        check_setup(_two_joints(), np.ones((3, 2)), (40, 40))


def test_rectangles_on_a_frame_twice_as_large_are_within_a_range_twice_as_large():
    # A thick body on a frame up to FigureTuning.frame_side gets the range's largest square, and a
    # thin arm its smallest; the same figure on a frame twice the size (twice as thick) gets squares twice as
    # large: the tracker halves that frame, and sees the rectangles of the range again.
    small = np.zeros((500, 800), bool)
    small[100:400, 200:600] = True
    small[249:251, 600:780] = True
    large = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)
    at = np.array([[400.0, 250.0], [700.0, 249.5]])
    assert max(small.shape) <= FigureTuning().frame_side < max(large.shape)
    np.testing.assert_array_equal(rectangle_sizes(small, at), [[HIGH] * 2, [LOW] * 2])
    np.testing.assert_array_equal(rectangle_sizes(large, 2 * at + 0.5),
                                  [[2 * HIGH] * 2, [2 * LOW] * 2])
