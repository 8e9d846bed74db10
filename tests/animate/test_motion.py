"""Tests for toonmotion.animate.motion: motions as (frames, joints, 2) arrays."""

import numpy as np
import pytest

from toonmotion.animate.motion import Motion, motion_for, motion_from_timeline
from toonmotion.animate.timeline import pose_at
from toonmotion.errors import MotionError
from toonmotion.rig.skeleton import Skeleton
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def test_a_timeline_sampled_has_a_pose_per_frame_and_hits_the_keys(skeleton):
    timeline = sample_keyframes(skeleton)
    motion = motion_from_timeline(skeleton, timeline)
    assert motion.positions.shape == (timeline.frame_count, len(skeleton), 2)
    assert motion.fps == timeline.fps
    for key in timeline.keys:
        np.testing.assert_array_equal(motion.positions[key.frame], key.pose.positions)
    np.testing.assert_array_equal(motion.pose(5).positions, pose_at(skeleton, timeline, 5).positions)
    assert not motion.positions.flags.writeable


def test_motion_for_reorders_columns_by_name():
    a = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 5)), ("toe", "knee", (2, 9))])
    b = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 5))])
    positions = np.arange(2 * 3 * 2, dtype=float).reshape(2, 3, 2)
    out = motion_for(b, Motion(a, positions, fps=10))
    np.testing.assert_array_equal(out, positions[:, :2])
    with pytest.raises(MotionError, match="has no joint 'toe'"):
        motion_for(a, Motion(b, positions[:, :2], fps=10))


@pytest.mark.parametrize(
    ("positions", "fps", "message"),
    [
        (np.zeros((0, 17, 2)), 12, r"shape \(frames, 17, 2\)"),
        (np.zeros((3, 16, 2)), 12, r"shape \(frames, 17, 2\)"),
        (np.full((3, 17, 2), np.nan), 12, "frame 0 of the motion has a non-finite"),
        (np.zeros((3, 17, 2)), 0, "fps must be a finite number > 0"),
        (np.zeros((3, 17, 2)), float("inf"), "fps must be a finite number > 0"),
        (np.zeros((3, 17, 2)), True, "fps must be a finite number > 0"),
    ],
)
def test_malformed_motions(skeleton, positions, fps, message):
    with pytest.raises(MotionError, match=message):
        Motion(skeleton, positions, fps=fps)
