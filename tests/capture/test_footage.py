"""Tests for toonmotion.capture.footage: suggest, track and correct a motion from frames."""

import numpy as np
import pytest

from toonmotion.animate.motion import Motion
from toonmotion.capture.footage import (
    capture_motion,
    correct_motion,
    first_figure,
    suggest_joints,
    tracking_from_motion,
)
from toonmotion.errors import MotionError, SettingsError, TrackingError
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character, sample_character_on


def _sliding_square(T=12, step=2.0, seed=5):
    """A textured 24 px square sliding right over a flat grey ground; ``(frames, true centres)``."""
    rng = np.random.default_rng(seed)
    texture = rng.integers(0, 255, (24, 24, 3), dtype=np.uint8)
    frames = np.full((T, 80, 120, 3), 128, dtype=np.uint8)
    centres = []
    for t in range(T):
        x0 = 20 + int(round(step * t))
        frames[t, 28:52, x0 : x0 + 24] = texture
        centres.append((x0 + 11.5, 39.5))
    return frames, np.array(centres)


def _one_joint(x, y):
    return Skeleton.from_joints([("box", None, (x, y))])


def test_a_sliding_square_is_captured_with_its_frame_rate_and_confidence():
    frames, truth = _sliding_square()
    capture = capture_motion(frames, _one_joint(*truth[0]), np.array([[16.0, 16.0]]), fps=10.0)
    assert capture.first == 0 and capture.motion.fps == 10.0
    assert capture.motion.frame_count == len(frames)
    assert np.abs(capture.motion.positions[:, 0] - truth).max() < 0.5
    assert capture.motion.confidence.shape == (len(frames), 1)
    assert capture.angles.shape == (len(frames), 1)


def test_a_motion_tracked_from_a_later_frame_starts_there():
    frames, truth = _sliding_square()
    capture = capture_motion(frames, _one_joint(*truth[4]), np.array([[16.0, 16.0]]), fps=10.0, start=4)
    assert capture.first == 4 and capture.motion.frame_count == len(frames) - 4
    assert np.abs(capture.motion.positions[:, 0] - truth[4:]).max() < 0.5


def test_a_start_frame_outside_the_footage_is_a_one_line_error():
    frames, truth = _sliding_square()
    with pytest.raises(SettingsError, match="given at frame 40 but the footage has 12 frames"):
        capture_motion(frames, _one_joint(*truth[0]), np.array([[16.0, 16.0]]), fps=10.0, start=40)


def test_a_correction_puts_the_joint_right_and_keeps_the_frames_before():
    frames, truth = _sliding_square()
    sizes = np.array([[16.0, 16.0]])
    first = capture_motion(frames, _one_joint(*truth[0]), sizes, fps=10.0)
    wrong = first.motion.positions.copy()
    wrong[6:] += 9.0  # as if the tracker had slipped at frame 6
    earlier = Motion(
        skeleton=first.motion.skeleton, positions=wrong, fps=10.0, confidence=first.motion.confidence
    )
    fixed = correct_motion(
        earlier, frames, _one_joint(*truth[0]), sizes, 6, {"box": tuple(truth[6])}, fps=10.0
    )
    np.testing.assert_array_equal(fixed.motion.positions[:6], wrong[:6])
    assert np.abs(fixed.motion.positions[6:, 0] - truth[6:]).max() < 0.5


def test_tracking_from_a_motion_lays_it_on_the_footage_in_the_skeleton_s_order():
    skeleton = Skeleton.from_joints([("a", None, (0, 0)), ("b", "a", (5, 0))])
    reordered = Skeleton.from_joints([("a", None, (0, 0)), ("b", "a", (5, 0))])
    positions = np.arange(3 * 2 * 2, dtype=float).reshape(3, 2, 2)
    motion = Motion(skeleton=reordered, positions=positions, fps=12, confidence=np.full((3, 2), 0.75))
    tracking = tracking_from_motion(motion, skeleton, count=6, start=2)
    assert tracking.tracked.tolist() == [False, False, True, True, True, False]
    np.testing.assert_array_equal(tracking.positions[2:5], positions)
    assert (tracking.confidence[2:5] == 0.75).all() and not tracking.confidence[[0, 1, 5]].any()


def test_tracking_from_a_motion_longer_than_the_footage_is_refused():
    skeleton = Skeleton.from_joints([("a", None, (0, 0))])
    motion = Motion(skeleton=skeleton, positions=np.zeros((5, 1, 2)), fps=12)
    with pytest.raises(SettingsError, match="5 frames from frame 3, more than the footage's 6"):
        tracking_from_motion(motion, skeleton, count=6, start=3)


def test_tracking_from_a_motion_missing_a_joint_names_it():
    motion = Motion(
        skeleton=Skeleton.from_joints([("a", None, (0, 0))]), positions=np.zeros((2, 1, 2)), fps=12
    )
    skeleton = Skeleton.from_joints([("a", None, (0, 0)), ("hat", None, (9, 9))])
    with pytest.raises(MotionError, match="'hat'"):
        tracking_from_motion(motion, skeleton, count=4, start=0)


def test_joints_are_suggested_on_a_flat_background_read_off_the_border():
    frames = np.full((2, 120, 90, 3), 240, dtype=np.uint8)
    frames[:, 20:100, 35:55] = (40, 80, 160)  # a standing bar
    frames[:, 40:50, 15:75] = (40, 80, 160)  # arms
    skeleton, sizes = suggest_joints(frames)
    assert len(skeleton) >= 2 and sizes.shape == (len(skeleton), 2)
    inside = [(15 <= x <= 75) and (20 <= y <= 100) for x, y in skeleton.positions]
    assert all(inside)


def test_a_frame_drawn_round_the_picture_is_not_the_figure():
    """A panel border round the picture differs from the paper as the figure does; no joint is
    suggested on it. A figure cut by all four edges of a close-up is still the figure."""
    picture, _ = sample_character_on("white", scale=0.5)
    unframed = np.pad(picture, ((20, 20), (20, 20), (0, 0)), constant_values=255)
    truth = np.pad(sample_character(scale=0.5)[0][..., 3] > 127, 20)
    framed = unframed.copy()
    framed[:4] = framed[-4:] = framed[:, :4] = framed[:, -4:] = 30
    found = first_figure(framed[None], colour=(255, 255, 255))
    # The very figure found without the frame: the frame's dark border pixels are not paper, so
    # they do not raise the threshold of what differs from it either.
    assert (found == first_figure(unframed[None], colour=(255, 255, 255))).all()
    assert (found & truth).sum() / (found | truth).sum() >= 0.95
    skeleton, _ = suggest_joints(framed[None], colour=(255, 255, 255))
    rows, cols = np.nonzero(truth)
    assert all(cols.min() <= x <= cols.max() and rows.min() <= y <= rows.max() for x, y in skeleton.positions)
    close_up = np.full((60, 60, 3), 255, np.uint8)
    close_up[:, 25:35] = close_up[25:35, :] = (200, 40, 40)  # a cross cut by every edge
    assert first_figure(close_up[None], colour=(255, 255, 255)).sum() == 60 * 10 * 2 - 100


@pytest.mark.parametrize("background", ["white", "paper"])
def test_the_first_figure_keeps_fills_near_the_papers_colour(background):
    # Skin and cream stripes on white paper, and the same on photographed paper whose colour
    # drifts by tens of levels: the figure found is the drawing's own (Otsu's split kept only
    # the outlines of the light fills on white: 0.73 of it).
    picture, _ = sample_character_on(background, scale=0.5)
    truth = sample_character(scale=0.5)[0][..., 3] > 127
    found = first_figure(picture[None])
    assert (found & truth).sum() / (found | truth).sum() >= 0.95


@pytest.mark.parametrize("frames, said", [
    (np.zeros((40, 30, 3), np.uint8), "frames have shape (40, 30, 3); give a (T, h, w, 3) array"),
    ([], "there are no frames to track"),
    ([np.zeros((40, 30), np.uint8)], "frame 0 is a uint8 array of shape (40, 30); give (h, w, 3) uint8 RGB"),
])
def test_suggesting_joints_on_something_that_is_no_footage_is_refused_in_one_line(frames, said):
    """One frame alone (an (H, W, 3) picture) used to end in a TypeError deep in the mask code."""
    with pytest.raises(TrackingError) as refused:
        suggest_joints(frames)
    assert said in str(refused.value) and "\n" not in str(refused.value)
