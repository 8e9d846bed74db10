"""Tests for toonmotion.capture.track_path: the tracker's whole-sequence pass (Viterbi over the
places each joint's searches found)."""

import numpy as np
import pytest

from toonmotion.animate.motion import motion_for
from toonmotion.capture.footage import capture_motion, first_figure
from toonmotion.capture.setup import rectangle_sizes
from toonmotion.capture.track_path import best_paths
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.io.frames import load_frames
from toonmotion.io.motion_json import load_motion
from toonmotion.rig.skeleton import Skeleton
from toonmotion.testing.mocap_tracking import tracking_scores

from ..conftest import run_cli


def _options(T, k, n=2):
    return np.full((T, k, n, 3), np.nan)


def test_a_look_alike_taken_on_one_frame_is_swapped_for_the_place_on_the_path():
    T = 8
    P = np.zeros((T, 1, 2))
    P[:, 0, 0] = 4.0 * np.arange(T)  # a root moving 4 px a frame
    C = np.full((T, 1), 0.95)
    options = _options(T, 1)
    options[3, 0, 0] = (*P[3, 0], 0.7)  # the search saw it where it was, a little less alike
    P[3, 0] += (0.0, 9.0)  # but took a look-alike 9 px off
    found, confidence = best_paths(P, C, options, np.array([-1]), np.arange(T), np.array([8.0]))
    assert np.allclose(found[:, 0, 0], 4.0 * np.arange(T)) and np.allclose(found[:, 0, 1], 0.0)
    assert confidence[3, 0] == pytest.approx(0.7) and np.allclose(np.delete(confidence, 3), 0.95)


def test_a_child_goes_with_its_parent_not_with_a_look_alike_left_behind():
    T = 8
    parents = np.array([-1, 0])
    P = np.zeros((T, 2, 2))
    P[:, 0, 0] = 6.0 * np.arange(T)  # the parent moves 6 px a frame
    P[:, 1] = P[:, 0] + (0.0, 20.0)  # its child hangs 20 px below it
    C = np.full((T, 2), 0.9)
    options = _options(T, 2)
    for t in (4, 5):  # the child's match stayed behind where it was at frame 3, as good a match
        options[t, 1, 0] = (*P[t, 1], 0.85)
        P[t, 1] = P[3, 1]
    found, _ = best_paths(P, C, options, parents, np.arange(T), np.array([8.0, 8.0]))
    assert np.allclose(found[:, 1], found[:, 0] + (0.0, 20.0))


def test_places_are_only_swapped_for_ones_offered_and_fixed_frames_are_kept():
    rng = np.random.default_rng(3)
    T, k = 12, 3
    parents = np.array([-1, 0, 1])
    P = rng.uniform(0, 100, (T, k, 2))
    C = rng.uniform(0.1, 1.0, (T, k))
    options = _options(T, k, 3)
    options[..., :2] = rng.uniform(0, 100, (T, k, 3, 2))
    options[..., 2] = rng.uniform(0.25, 1.0, (T, k, 3))
    options[rng.random((T, k, 3)) < 0.3] = np.nan
    drawings = np.array([1, 2, 4, 5, 6, 9, 10, 11])  # frames 0, 3, 7 and 8 are not chosen on
    found, confidence = best_paths(P, C, options, parents, drawings, np.full(k, 10.0))
    for t in range(T):
        for m in range(k):
            if t not in drawings[1:]:
                assert (found[t, m] == P[t, m]).all() and confidence[t, m] == C[t, m]
            elif (found[t, m] != P[t, m]).any():
                row = np.flatnonzero((options[t, m, :, :2] == found[t, m]).all(axis=1))
                assert len(row) and confidence[t, m] == pytest.approx(options[t, m, row[0], 2])
    assert (found != P).any()  # the random places do get swapped


def test_no_step_is_longer_than_the_widest_search_but_the_trackers_own():
    T = 8
    P = np.zeros((T, 1, 2))
    C = np.full((T, 1), 0.3)  # a joint matched poorly all along
    options = _options(T, 1)
    options[1:, 0, 0] = (30.0, 0.0, 1.0)  # a perfect look-alike a step of 30 px away
    options[1:, 0, 1] = (0.0, 20.0, 1.0)  # and one 20 px away
    P[5:, 0] = (40.0, 0.0)  # the tracker found it again 40 px off
    radius = np.array([8.0])  # the widest search reaches 3 x 8 = 24 px a frame
    found, _ = best_paths(P, C, options, np.array([-1]), np.arange(T), radius)
    steps = np.hypot(*np.diff(found[:, 0], axis=0).T)
    own = np.hypot(*np.diff(P[:, 0], axis=0).T)
    assert ((steps <= 24.0) | (steps == own)).all()
    assert (found[1:, 0] == (0.0, 20.0)).all(axis=1).any()  # the near look-alike is taken
    assert not (found[:, 0] == (30.0, 0.0)).all(axis=1).any()  # the far one never


def test_fewer_than_three_drawings_are_left_as_they_are():
    P, C = np.zeros((2, 1, 2)), np.ones((2, 1))
    options = _options(2, 1)
    options[1, 0, 0] = (5.0, 5.0, 1.0)
    found, confidence = best_paths(P, C, options, np.array([-1]), np.arange(2), np.array([8.0]))
    assert (found == P).all() and (confidence == C).all()


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """The package's own ``demo/demo.mp4``, made as ``make demo`` makes it, with its true joints."""
    folder = tmp_path_factory.mktemp("demo")
    steps = [
        ["sample", "-o", folder / "hero.png", "--skeleton", folder / "hero.json", "--keys",
         folder / "keys.json"],
        ["rig", folder / "hero.png", "--skeleton", folder / "hero.json", "-o", folder / "hero"],
        ["depth", folder / "hero", "right_elbow=1", "right_hand=1"],
        ["animate", folder / "hero", folder / "keys.json", "-o", folder / "demo.mp4", "--save-frame-motion",
         folder / "motion.json"],
    ]
    for step in steps:
        assert run_cli(*step) == 0
    frames, fps = load_frames(folder / "demo.mp4")
    truth = load_motion(folder / "motion.json")
    positions = motion_for(truth.skeleton, truth, where="the true motion")
    count = min(len(frames), len(positions))
    frames, positions = frames[:count], positions[:count]
    placed = Skeleton.from_joints([(n, p, tuple(xy)) for (n, p, _), xy in
                                   zip(truth.skeleton.joints(), positions[0], strict=True)])
    sizes = rectangle_sizes(first_figure(frames), positions[0])

    def error(settings):
        found = capture_motion(frames, placed, sizes, fps=fps, settings=settings).motion.positions
        return tracking_scores(found, positions)["mean_px"]

    return {"with": error(TrackSettings()), "without": error(TrackSettings(best_path=False))}


def test_the_whole_sequence_pass_brings_the_demo_closer_to_its_true_joints(demo):
    # Measured: 2.09 px without the pass, 1.84 with it; 3.23 and 3.04 before stage two held the
    # drawing at its joints (DeformSettings.joint_anchor), when the demo's drawn knees lay up to
    # 24 px from the skeleton's. (4.01 and 3.74 before a joint's anchor found as it was cut took
    # precedence over its prediction: that now takes the knees back to their places when the legs
    # straighten again, which the pass used to do; the bound was 0.2.)
    assert demo["with"] <= demo["without"] - 0.15


def test_the_demo_is_tracked_within_3_px_of_its_true_joints(demo):
    # Measured: 1.84 px. It was 3.04 (a strict xfail) while stage two let the drawing's knees and
    # elbows settle 10-24 px from the skeleton's, which the tracker, following the drawing, could
    # not find; against where the drawing carried its joints the tracker was within 1.56 px then.
    assert demo["with"] <= 3.0
