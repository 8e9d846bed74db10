"""Tests for toonmotion.animate.timeline: key-frames, easing and interpolated poses."""

import numpy as np
import pytest

from toonmotion import limits
from toonmotion.animate.timeline import (
    EASES,
    Keyframe,
    Timeline,
    ease,
    interpolate_pose,
    make_timeline,
    pose_at,
    segment_at,
)
from toonmotion.errors import KeyframeError, LimitError, PoseError
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import Pose, descendants, rest_pose, rotate_about
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _key(skeleton, frame, positions=None):
    pose = rest_pose(skeleton) if positions is None else Pose(np.array(positions, dtype=float))
    return Keyframe(frame, pose)


def _bone(skeleton, name):
    return skeleton.bone_names.index(name)


def _angle(skeleton, positions, bone):
    angle, _ = bone_angles(skeleton, positions)
    return angle[_bone(skeleton, bone)]


def _turn_degrees(skeleton, a, b, bone):
    """How far ``bone`` turned from positions ``a`` to ``b``, in degrees, in [-180, 180)."""
    d = np.degrees(_angle(skeleton, b, bone) - _angle(skeleton, a, bone))
    return float((d + 180) % 360 - 180)


# --- make_timeline -------------------------------------------------------------------------------


def test_keys_are_sorted_and_frames_counted(skeleton):
    bent = rotate_about(skeleton, skeleton.positions, "right_elbow", 0.5)
    keys = [_key(skeleton, 12, bent), _key(skeleton, 0), _key(skeleton, np.int64(5), bent)]
    timeline = make_timeline(skeleton, keys, fps=12, ease="in-out")
    assert [k.frame for k in timeline.keys] == [0, 5, 12]
    assert all(type(k.frame) is int for k in timeline.keys)
    assert timeline.keys[0].pose is keys[1].pose  # poses are kept, not copied
    assert timeline.frame_count == 13
    assert timeline.fps == 12.0 and isinstance(timeline.fps, float)
    assert timeline.duration == pytest.approx(1.0)
    assert timeline.ease == "in-out"
    one = make_timeline(skeleton, [_key(skeleton, 7)])
    assert one.frame_count == 8 and one.fps == 24.0 and one.ease == "linear"


@pytest.mark.parametrize(
    ("keys", "options", "message"),
    [
        ([], {}, r"there are no key-frames; give at least one key pose"),
        ([0, 4, 4, 9, 9], {}, r"frame 4 has two key poses; give each frame at most one"),
        ([0, -1], {}, r"key-frame numbers must be whole numbers >= 0, got -1"),
        ([0, 2.0], {}, r"key-frame numbers must be whole numbers >= 0, got 2.0"),
        ([0, "3"], {}, r"key-frame numbers must be whole numbers >= 0, got '3'"),
        ([0, True], {}, r"key-frame numbers must be whole numbers >= 0, got True"),
        ([0], {"fps": 0}, r"fps must be a finite number > 0, got 0"),
        ([0], {"fps": -24}, r"fps must be a finite number > 0, got -24"),
        ([0], {"fps": float("nan")}, r"fps must be a finite number > 0, got nan"),
        ([0], {"fps": float("inf")}, r"fps must be a finite number > 0, got inf"),
        ([0], {"fps": "fast"}, r"fps must be a finite number > 0, got 'fast'"),
        ([0], {"fps": None}, r"fps must be a finite number > 0, got None"),
        ([0], {"fps": 0.001}, r"fps must be between 0.01 and 1000 frames per second, got 0.001"),
        ([0], {"fps": 1e6}, r"fps must be between 0.01 and 1000 frames per second, got 1e\+06"),
        ([0], {"ease": "bounce"}, r"ease must be one of linear, in-out, in, out, got 'bounce'"),
    ],
)
def test_make_timeline_refuses_bad_keys_and_options(skeleton, keys, options, message):
    with pytest.raises(KeyframeError, match=message):
        make_timeline(skeleton, [_key(skeleton, f) for f in keys], **options)


def test_a_key_beyond_the_frames_limit_is_refused_until_the_limit_is_raised(skeleton):
    keys = [_key(skeleton, 0), _key(skeleton, 100_000)]
    with pytest.raises(LimitError, match=r"number, 100000, plus one is over the limit frames=100,000"):
        make_timeline(skeleton, keys)
    with limits.using(frames=100_001):
        assert make_timeline(skeleton, keys).frame_count == 100_001


def test_make_timeline_checks_every_key_pose(skeleton):
    with pytest.raises(PoseError, match=r"key-frame 6: has 16 joint positions but the skeleton has 17"):
        make_timeline(skeleton, [_key(skeleton, 0), _key(skeleton, 6, skeleton.positions[:-1])])


# --- segments and easing ----------------------------------------------------------------------------


@pytest.mark.parametrize("kind", EASES)
def test_ease_is_monotone_with_exact_endpoints(kind):
    t = np.linspace(0, 1, 1001)
    e = np.array([ease(x, kind) for x in t])
    assert ease(0.0, kind) == 0.0 and ease(1.0, kind) == 1.0
    assert np.all(np.diff(e) > 0)
    assert np.all((e >= 0) & (e <= 1))


def test_ease_shapes():
    t = np.linspace(0, 1, 101)
    inout = np.array([ease(x, "in-out") for x in t])
    np.testing.assert_allclose(inout + inout[::-1], 1.0, atol=1e-15)  # symmetric about (1/2, 1/2)
    assert ease(0.5, "in-out") == 0.5
    # "in" is slow leaving a key, "out" slow arriving; each is the other turned about (1/2, 1/2).
    ins = np.array([ease(x, "in") for x in t])
    outs = np.array([ease(x, "out") for x in t])
    np.testing.assert_allclose(outs, 1 - ins[::-1], atol=1e-15)
    inner = slice(1, -1)
    assert np.all(ins[inner] < t[inner]) and np.all(outs[inner] > t[inner])
    # Slow at a key: the slope at the ends is 0 where the ease is slow there.
    h = 1e-6
    assert ease(h, "in-out") / h < 1e-5 and (1 - ease(1 - h, "in-out")) / h < 1e-5
    assert ease(h, "in") / h < 1e-5 and (1 - ease(1 - h, "out")) / h < 1e-5
    np.testing.assert_array_equal([ease(x, "linear") for x in t], t)


@pytest.mark.parametrize("kind", EASES)
def test_segment_at_walks_the_keys(skeleton, kind):
    timeline = make_timeline(skeleton, [_key(skeleton, f) for f in (3, 7, 15)], ease=kind)
    assert segment_at(timeline, 0) == (0, 0.0)  # before the first key: hold it
    assert segment_at(timeline, 3) == (0, 0.0)
    assert segment_at(timeline, 7) == (1, 0.0)  # exactly at a key: that key, t = 0
    assert segment_at(timeline, 15) == (2, 0.0)
    assert segment_at(timeline, 40) == (2, 0.0)  # after the last: hold it
    for frame in range(4, 7):
        assert segment_at(timeline, frame) == (0, ease((frame - 3) / 4, kind))
    ts = [segment_at(timeline, f)[1] for f in range(8, 15)]
    assert [segment_at(timeline, f)[0] for f in range(8, 15)] == [1] * 7
    assert all(0 < t < 1 for t in ts) and ts == sorted(ts)


# --- interpolated poses -----------------------------------------------------------------------------


def test_interpolate_pose_endpoints_are_the_keys(skeleton):
    a = rest_pose(skeleton)
    b = Pose(rotate_about(skeleton, skeleton.positions, "left_shoulder", 1.0))
    assert interpolate_pose(skeleton, a, b, 0) is a
    assert interpolate_pose(skeleton, a, b, 1) is b
    np.testing.assert_allclose(interpolate_pose(skeleton, a, b, 1 - 1e-12).positions, b.positions, atol=1e-9)


@pytest.mark.parametrize("t", [0.1, 0.5, 0.77])
def test_interpolate_pose_keeps_bone_lengths_that_both_keys_share(skeleton, t):
    P = skeleton.positions
    b = rotate_about(skeleton, P, "right_shoulder", 2.0)
    b = rotate_about(skeleton, b, "right_elbow", -1.2)
    b = rotate_about(skeleton, b, "left_hip", 0.8)
    b = rotate_about(skeleton, b, "root", -0.4) + (31.0, -12.0)
    mid = interpolate_pose(skeleton, rest_pose(skeleton), Pose(b), t).positions
    np.testing.assert_allclose(bone_angles(skeleton, mid)[1], skeleton.bone_lengths, rtol=1e-12, atol=1e-12)
    # Roots move in a straight line.
    root = skeleton.index("root")
    np.testing.assert_allclose(mid[root], (1 - t) * P[root] + t * b[root], atol=1e-12)


@pytest.mark.parametrize("t", [0.25, 0.5, 0.9])
def test_interpolate_pose_lerps_lengths_that_change(skeleton, t):
    P = skeleton.positions
    b = np.array(P)
    knee = skeleton.index("right_knee")
    below = np.concatenate([[knee], descendants(skeleton, knee)])
    b[below] += 0.5 * (P[knee] - P[skeleton.index("right_hip")])  # the thigh 1.5x as long
    b = rotate_about(skeleton, b, "right_hip", 0.6)
    mid = interpolate_pose(skeleton, rest_pose(skeleton), Pose(b), t).positions
    angle, length = bone_angles(skeleton, mid)
    rest_angle, rest_length = bone_angles(skeleton, P)
    expected = np.array(rest_length)
    thigh = _bone(skeleton, "right_knee")
    expected[thigh] *= 1 + 0.5 * t
    np.testing.assert_allclose(length, expected, rtol=1e-12, atol=1e-12)
    assert angle[thigh] == pytest.approx(rest_angle[thigh] + 0.6 * t, abs=1e-12)


@pytest.mark.parametrize(("turn", "halfway"), [(170, 85), (-170, -85), (190, -85), (-190, 85)])
def test_a_bone_turns_the_short_way(skeleton, turn, halfway):
    P = skeleton.positions
    b = rotate_about(skeleton, P, "right_elbow", np.radians(turn))
    mid = interpolate_pose(skeleton, rest_pose(skeleton), Pose(b), 0.5).positions
    assert _turn_degrees(skeleton, P, mid, "right_hand") == pytest.approx(halfway, abs=1e-9)
    # The hand swings along the arc: it stays a forearm's length from the elbow all the way.
    elbow, hand = skeleton.index("right_elbow"), skeleton.index("right_hand")
    for t in np.linspace(0, 1, 11):
        Q = interpolate_pose(skeleton, rest_pose(skeleton), Pose(b), t).positions
        np.testing.assert_allclose(np.linalg.norm(Q[hand] - Q[elbow]), np.linalg.norm(P[hand] - P[elbow]))
        np.testing.assert_array_equal(Q[elbow], P[elbow])


def test_interpolate_pose_moves_a_zero_length_bone_by_its_offset(skeleton):
    # The sample's root -> hip bone has no length at rest; give it one in the second key.
    b = np.array(skeleton.positions)
    hip = skeleton.index("hip")
    below = np.concatenate([[hip], descendants(skeleton, hip)])
    b[below] += (0.0, -20.0)
    mid = interpolate_pose(skeleton, rest_pose(skeleton), Pose(b), 0.25).positions
    np.testing.assert_allclose(mid[below], skeleton.positions[below] + (0.0, -5.0), atol=1e-12)


def test_pose_at_follows_the_timeline(skeleton):
    a = rest_pose(skeleton)
    b = Pose(rotate_about(skeleton, skeleton.positions, "left_elbow", -1.0))
    timeline = Timeline(keys=(Keyframe(2, a), Keyframe(10, b)), fps=24.0, ease="in-out")
    assert pose_at(skeleton, timeline, 0) is a and pose_at(skeleton, timeline, 2) is a
    assert pose_at(skeleton, timeline, 10) is b and pose_at(skeleton, timeline, 11) is b
    mid = pose_at(skeleton, timeline, 6).positions  # halfway, and in-out is symmetric
    turn = _turn_degrees(skeleton, skeleton.positions, mid, "left_hand")
    assert turn == pytest.approx(np.degrees(-0.5), abs=1e-9)
    early = pose_at(skeleton, timeline, 3).positions
    assert _turn_degrees(skeleton, skeleton.positions, early, "left_hand") == pytest.approx(
        np.degrees(-ease(1 / 8, "in-out")), abs=1e-9)
