"""Tests for toonmotion.capture.track_figure and the tracker's use of the figure's mask: every joint
lies on the figure, shown or hidden behind it."""

import math

import cv2
import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require
from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.foreground import FlatBackgroundMasks, flat_figure_masks, flat_threshold
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.track_figure import FigureMasks, figure_cells, on_figure, onto_figure
from toonmotion.capture.track_settings import TrackSettings, TrackSetup
from toonmotion.capture.tracker import track
from toonmotion.errors import TrackingError
from toonmotion.rig.skeleton import Skeleton
from toonmotion.testing.mocap_tracking import render_bvh_clip

FRAMES = 40


def _disc(shape=(60, 80)):
    near = np.zeros(shape, np.uint8)
    cv2.circle(near, (50, 30), 12, 255, -1)
    return near


def test_figure_cells_lay_out_a_turned_window_as_the_tracker_does():
    """Cell (i, j) of a window round c turned by a, cells s px apart, is c + s R(a) (j - R, i - R)."""
    near = _disc()
    centre, angle, R, step = np.array([47.3, 28.6]), 0.7, 6, 2.0
    cells = figure_cells(near, centre, angle, R, step)
    i, j = np.mgrid[-R:R + 1, -R:R + 1]
    c, s = math.cos(angle), math.sin(angle)
    points = np.stack([centre[0] + step * (c * j - s * i), centre[1] + step * (s * j + c * i)], axis=-1)
    assert (cells == on_figure(near, points.reshape(-1, 2)).reshape(cells.shape)).all()
    assert cells.any() and not cells.all()


def test_a_point_off_the_figure_goes_to_its_nearest_pixel_within_reach_and_toward_it_beyond():
    near = _disc()
    inside, outside = np.array([50.0, 30.0]), np.array([50.0, 50.0])  # 20 px below the centre
    assert onto_figure(near, inside, 5.0) is inside
    moved = onto_figure(near, outside, 10.0)
    assert on_figure(near, moved[None])[0] and np.hypot(*(moved - outside)) == pytest.approx(8.0, abs=1.0)
    # About 8 px off: a reach of 5 takes it 5 px toward the figure, straight up; one of 1.5 (the
    # figure beyond ClipTuning.pull_reach reaches) leaves it where it was.
    np.testing.assert_allclose(onto_figure(near, outside, 5.0), [50.0, 45.0])
    assert (onto_figure(near, outside, 1.5) == outside).all()


def test_masks_hold_points_within_the_slack_of_the_figure():
    mask = np.zeros((1, 60, 80), bool)
    mask[0, 20:40, 20:40] = True
    figure = FigureMasks(mask, 1, (60, 80, 3))
    edge = 40 - 1 + ClipTuning().figure_slack  # the last figure column is 39
    assert figure.holds(0, np.array([[edge, 30.0], [edge + 1.5, 30.0]])).tolist() == [True, False]
    with pytest.raises(TrackingError, match="one a frame"):
        FigureMasks(mask, 2, (60, 80, 3))
    with pytest.raises(TrackingError, match="frames' size"):
        FigureMasks(mask, 1, (61, 80, 3)).near(0)


@pytest.fixture(scope="module")
def flat_walk():
    clip = _require(SHARED_DATA / "mocap") / "cmu_07_01_walk.bvh"
    return render_bvh_clip(clip, frames=FRAMES, style="flat")


def test_a_cartoon_on_plain_paper_has_every_joint_on_its_masks(flat_walk):
    """Light fills near the paper's colour (skin on cream) are the figure too: a threshold from
    Otsu's split would keep only their outlines."""
    masks = flat_figure_masks(flat_walk.images)
    assert isinstance(masks, FlatBackgroundMasks) and len(masks) == FRAMES
    figure = FigureMasks(masks, FRAMES, flat_walk.images.shape[1:])
    assert all(figure.holds(t, flat_walk.truth[t]).all() for t in range(FRAMES))
    paper = np.all(flat_walk.images == flat_walk.images[0, 0, 0], axis=-1)
    assert not (masks[0] & paper[0]).any() and (masks[0] | paper[0]).mean() > 0.999


def test_each_mask_is_its_own_array_though_the_work_is_done_in_kept_ones(flat_walk):
    """The masks are made in arrays kept from frame to frame; those handed out are not overwritten
    by the next: each is the summed channel difference from the paper above the threshold, for
    frames of any type."""
    masks = flat_figure_masks(flat_walk.images)
    kept = list(masks)
    paper = np.asarray(flat_walk.images[0, 0, 0], dtype=int)
    threshold = flat_threshold(flat_walk.images[0], paper)
    for frame, mask in zip(flat_walk.images, kept, strict=True):
        difference = np.minimum(np.abs(frame.astype(int) - paper).sum(axis=-1), 255)
        np.testing.assert_array_equal(mask, difference > threshold)
    assert len({id(mask) for mask in kept}) == FRAMES
    floats = flat_figure_masks(flat_walk.images[:3].astype(np.float32))  # split into arrays of their own
    assert all(np.array_equal(floats[t], kept[t]) for t in range(3))


def test_a_textured_background_gives_no_masks():
    """A background estimated from the footage is wrong where the figure holds still: none is offered."""
    clip = _require(SHARED_DATA / "mocap") / "fair_wave_hello.bvh"
    assert flat_figure_masks(render_bvh_clip(clip, frames=4).images) is None


def test_tracked_joints_of_a_cartoon_never_leave_the_figure():
    """The invariant the masks give: every joint, found or hidden, lies on the figure. Without
    them, joints carried while hidden float on the paper beside the limbs (the flat run: 46
    joint-frames off the figure in these 40 frames)."""
    clip = _require(SHARED_DATA / "mocap") / "cmu_02_03_run.bvh"
    run = render_bvh_clip(clip, frames=FRAMES, style="flat")
    masks = flat_figure_masks(run.images)
    setup = TrackSetup(run.skeleton, np.full((len(run.skeleton), 2), run.side))
    figure = FigureMasks(masks, FRAMES, run.images.shape[1:])
    held = track(run.images, setup, masks=masks)
    assert all(figure.holds(t, held.positions[t]).all() for t in range(FRAMES))
    free = track(run.images, setup)
    assert not all(figure.holds(t, free.positions[t]).all() for t in range(FRAMES))


def test_a_joint_off_its_mask_where_tracking_starts_is_left_free():
    """A mask that misses part of the figure does not drag a joint marked off it."""
    rng = np.random.default_rng(3)
    frames = np.full((4, 60, 90, 3), 240, np.uint8)
    frames[:, 20:40, 10:30] = rng.integers(0, 255, (20, 20, 3))  # the figure, on a flat colour
    frames[:, 20:40, 60:80] = frames[0, 20:40, 10:30]
    masks = np.zeros((4, 60, 90), bool)
    masks[:, 20:40, 10:30] = True  # the mask misses the second square
    skeleton = Skeleton.from_joints([("a", None, (19.5, 29.5)), ("b", None, (69.5, 29.5))])
    tracking = track(frames, TrackSetup(skeleton, np.full((2, 2), 12.0)), masks=masks)
    assert np.abs(tracking.positions - [[19.5, 29.5], [69.5, 29.5]]).max() < 0.2
    assert (tracking.confidence >= MatchTuning().visible_confidence).all()


def test_capture_holds_joints_to_a_flat_figure_unless_told_not_to(flat_walk):
    from toonmotion.capture.footage import _masks

    assert _masks(flat_walk.images, None, None) is not None
    assert _masks(flat_walk.images, TrackSettings(figure=False), None) is None
    with pytest.raises(TrackingError, match="figure must be True or False"):
        TrackSettings(figure="yes")  # type: ignore[arg-type]


def test_a_corrected_tracking_keeps_its_joints_on_the_figure(flat_walk):
    """``retrack`` with the masks: the frames before the correction kept, the corrected joint where
    it was put, and every joint of every frame after it on the figure."""
    from toonmotion.capture.tracker import retrack

    masks = flat_figure_masks(flat_walk.images)
    setup = TrackSetup(flat_walk.skeleton, np.full((len(flat_walk.skeleton), 2), flat_walk.side))
    figure = FigureMasks(masks, FRAMES, flat_walk.images.shape[1:])
    first = track(flat_walk.images, setup, masks=masks)
    name = flat_walk.skeleton.names[5]
    fixed = retrack(first, flat_walk.images, setup, 20, {name: flat_walk.truth[20, 5]}, masks=masks)
    np.testing.assert_array_equal(fixed.positions[:20], first.positions[:20])
    np.testing.assert_allclose(fixed.positions[20, 5], flat_walk.truth[20, 5])
    assert all(figure.holds(t, fixed.positions[t]).all() for t in range(20, FRAMES))
