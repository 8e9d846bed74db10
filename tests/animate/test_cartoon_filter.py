"""Tests for toonmotion.animate.cartoon_filter: the cartoon animation filter over time (thesis 5.1, 5.2.2)."""

import numpy as np
import pytest

from toonmotion.animate.cartoon_filter import (
    MIN_LENGTH_FRACTION,
    FilterSettings,
    cartoon_filter,
    filter_bones,
    filter_trajectories,
    joint_indices,
)
from toonmotion.errors import FilterError
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import descendants, rotate_about
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character

# The thesis' ball (fig. 5.2): still, then SPEED px/frame, then still.
STILL, MOVING, SPEED = 20, 30, 4.0
START = STILL - 1  # the last still frame: x'' = SPEED there
STOP = STILL + MOVING - 1  # the last moving frame, already at the end position: x'' = -SPEED there


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _ball():
    """``(T,)`` positions: STILL frames at 0, MOVING frames at SPEED px/frame, STILL frames at the end."""
    moving = SPEED * np.arange(1, MOVING + 1)
    return np.concatenate([np.zeros(STILL), moving, np.full(STILL, moving[-1])])


def _wiggle(T=80):
    """A smooth, irregular 1D signal: two sines and a drift."""
    t = np.arange(T, dtype=float)
    return 30 * np.sin(2 * np.pi * t / 37 + 0.4) + 12 * np.sin(2 * np.pi * t / 13 + 1.3) + 0.5 * t


def _motion(skeleton, T=40):
    """``(T, k, 2)``: the sample walking right with a stop-start, its right arm swinging faster and faster."""
    P = skeleton.positions
    walk = np.clip(3.0 * (np.arange(T) - 9), 0, 60)  # still, 3 px/frame, still
    frames = []
    for t in range(T):
        Q = rotate_about(skeleton, P, "right_shoulder", 0.002 * t * t)
        frames.append(Q + [walk[t], 0.0])
    return np.array(frames)


# --- the filter on a signal: the thesis' ball -----------------------------------------------------


def test_the_ball_dips_back_before_it_starts_and_overshoots_where_it_stops():
    x = _ball()
    dips, overshoots = [], []
    for A in (0.5, 1.0, 2.0):
        y = cartoon_filter(x, FilterSettings(strength=A))
        assert y.shape == x.shape and y is not x
        dip = -y[:STILL].min()  # the start position is 0
        overshoot = y[STOP:].max() - x[-1]
        assert dip > 0 and overshoot > 0
        assert int(np.argmin(y[:STILL])) == START
        assert int(np.argmax(y)) == STOP
        # With no easing x'' is one spike of SPEED at the start frame; the kernel is not
        # normalised and peaks at A there, and the stop is 30 frames away (beyond the kernel
        # radius of 9), so the dip is A * SPEED to rounding. Measured: 2, 4 and 8 px.
        assert dip == pytest.approx(A * SPEED, abs=1e-9)
        assert overshoot == pytest.approx(A * SPEED, abs=1e-9)
        dips.append(dip)
        overshoots.append(overshoot)
    assert dips[0] < dips[1] < dips[2]
    assert overshoots[0] < overshoots[1] < overshoots[2]


def test_a_wider_kernel_spreads_the_dip_over_more_frames():
    x = _ball()
    narrow = cartoon_filter(x, FilterSettings(strength=1.0, sigma=1.0))
    wide = cartoon_filter(x, FilterSettings(strength=1.0, sigma=5.0))
    assert (wide[:STILL] < -0.5).sum() > (narrow[:STILL] < -0.5).sum()


@pytest.mark.parametrize("shift", [-3, 2, 4])
def test_a_time_shift_moves_the_dip_by_that_many_frames(shift):
    x = _ball()
    pull = cartoon_filter(x, FilterSettings(strength=1.0, shift=shift)) - x
    early = pull[: START + 8]  # around the start, well before the stop
    assert int(np.argmin(early)) == START + shift
    assert early.min() == pytest.approx(-SPEED, abs=1e-9)
    # Brought forward, the dip comes while the ball is still waiting: the ball itself backs off earlier.
    if shift < 0:
        y = x + pull
        assert int(np.argmin(y[:STILL])) == START + shift


# --- what the filter leaves alone -----------------------------------------------------------------


def test_a_still_signal_is_unchanged():
    x = np.full((30, 3, 2), 7.25)
    np.testing.assert_array_equal(cartoon_filter(x, FilterSettings(strength=2.0)), x)


@pytest.mark.parametrize("T", [2, 3, 5, 40])
def test_constant_velocity_is_unchanged_ends_included(T):
    x = 12.5 - 3.75 * np.arange(T)
    y = cartoon_filter(x, FilterSettings(strength=2.0, sigma=4.0, shift=1.5))
    np.testing.assert_allclose(y, x, rtol=0, atol=1e-9)


def test_the_middle_of_a_steady_stretch_is_unchanged():
    x = _ball()
    settings = FilterSettings(strength=2.0)
    assert settings.radius == 9
    y = cartoon_filter(x, settings)
    middle = slice(START + settings.radius + 1, STOP - settings.radius)
    assert middle.stop - middle.start > 5
    np.testing.assert_allclose(y[middle], x[middle], rtol=0, atol=1e-12)
    assert np.abs(y - x).max() > 1  # but it does change near the velocity changes


@pytest.mark.parametrize("A", [0.5, 1.0, 2.0])
def test_no_jump_at_the_first_or_last_frame(A):
    """The signal carries on past each end at its end velocity, so the ends move about as much
    as the signal does there (measured up to 1.55x the largest of its four end differences), and
    the filter pulls the end frames less than it pulls inside the clip (measured 0.42x)."""
    x = _wiggle()
    settings = FilterSettings(strength=A)
    y = cartoon_filter(x, settings)
    dx, dy = np.diff(x), np.diff(y)
    assert abs(dy[0]) <= 2 * np.abs(dx[:4]).max()
    assert abs(dy[-1]) <= 2 * np.abs(dx[-4:]).max()
    pull = np.abs(y - x)
    inside = pull[settings.radius : -settings.radius].max()
    assert inside > 1  # the filter does act
    assert pull[0] <= inside and pull[-1] <= inside


def test_zero_strength_returns_the_input_exactly():
    x = _wiggle()
    y = cartoon_filter(x, FilterSettings(strength=0.0, shift=2.0))
    np.testing.assert_array_equal(y, x)
    assert y is not x


def test_one_frame_comes_back_as_a_copy():
    x = np.array([[1.0, 2.0]])
    y = cartoon_filter(x, FilterSettings(strength=3.0))
    np.testing.assert_array_equal(y, x)
    y[0, 0] = 5.0
    assert x[0, 0] == 1.0


def test_the_input_is_not_modified():
    x = _ball()
    before = x.copy()
    cartoon_filter(x, FilterSettings(strength=1.0))
    np.testing.assert_array_equal(x, before)


def test_batched_signals_filter_each_column_on_its_own(skeleton):
    P = _motion(skeleton)  # (T, k, 2)
    settings = FilterSettings(strength=1.5, sigma=2.0, shift=-1.0)
    batched = cartoon_filter(P, settings)
    assert batched.shape == P.shape
    for j in range(P.shape[1]):
        for axis in range(2):
            np.testing.assert_allclose(batched[:, j, axis], cartoon_filter(P[:, j, axis], settings),
                                       rtol=0, atol=1e-12)


# --- filter_trajectories ---------------------------------------------------------------------------


def test_filtering_the_root_carries_the_whole_body(skeleton):
    P = _motion(skeleton)
    root = skeleton.index("root")
    out = filter_trajectories(skeleton, P, FilterSettings(strength=1.0), joints=["root"])
    change = out - P
    np.testing.assert_array_equal(out[:, root], cartoon_filter(P[:, root], FilterSettings(strength=1.0)))
    np.testing.assert_allclose(change, np.broadcast_to(change[:, root : root + 1], change.shape),
                               rtol=0, atol=1e-9)
    assert np.abs(change).max() > 1


def test_filtering_a_hand_moves_only_its_subtree():
    arm = Skeleton.from_joints([
        ("root", None, (0, 0)), ("shoulder", "root", (0, -50)), ("elbow", "shoulder", (30, -50)),
        ("hand", "elbow", (60, -50)), ("finger", "hand", (70, -50)), ("head", "shoulder", (0, -80)),
    ])
    T = 30
    turn = 0.003 * np.arange(T) ** 2  # the arm swings faster and faster
    P = np.array([rotate_about(arm, arm.positions, "shoulder", a) for a in turn])
    out = filter_trajectories(arm, P, FilterSettings(strength=2.0), joints=["hand"])
    hand = arm.index("hand")
    moved = [hand, *descendants(arm, hand)]
    still = [j for j in range(len(arm)) if j not in moved]
    np.testing.assert_array_equal(out[:, still], P[:, still])
    change = out - P
    assert np.abs(change[:, hand]).max() > 1
    np.testing.assert_allclose(change[:, arm.index("finger")], change[:, hand], rtol=0, atol=1e-12)


def test_filtering_no_joints_changes_nothing(skeleton):
    P = _motion(skeleton, T=12)
    out = filter_trajectories(skeleton, P, FilterSettings(strength=1.0), joints=[])
    np.testing.assert_array_equal(out, P)


# --- filter_bones ------------------------------------------------------------------------------


def _spinner():
    return Skeleton.from_joints([("pivot", None, (100, 100)), ("tip", "pivot", (150, 100))])


def _spin(angles, radius=50.0):
    """``(T, 2, 2)``: the spinner's pivot still, its tip at ``angles`` (radians)."""
    tip = 100 + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    return np.stack([np.full_like(tip, 100.0), tip], axis=1)


def test_a_bone_spinning_through_half_a_turn_has_no_jump():
    spinner = _spinner()
    steady = np.radians(150 + 7.0 * np.arange(20))  # through 180 degrees, where atan2 wraps
    angle, _ = bone_angles(spinner, _spin(steady))
    assert np.abs(np.diff(angle, axis=0)).max() > np.pi  # the raw angles do wrap
    P = _spin(steady)
    out = filter_bones(spinner, P, FilterSettings(strength=2.0))
    np.testing.assert_allclose(out, P, rtol=0, atol=1e-9)
    # Speeding up through the wrap: the filter acts, but smoothly.
    speeding = np.radians(120 + 0.5 * np.arange(24) ** 2)
    P = _spin(speeding)
    out = filter_bones(spinner, P, FilterSettings(strength=2.0))
    step_in = np.linalg.norm(np.diff(P[:, 1], axis=0), axis=1).max()
    step_out = np.linalg.norm(np.diff(out[:, 1], axis=0), axis=1).max()
    assert np.abs(out - P).max() > 1
    assert step_out < 2 * step_in


def test_a_still_motion_is_unchanged_by_filter_bones(skeleton):
    P = np.broadcast_to(rotate_about(skeleton, skeleton.positions, "left_elbow", 0.7), (15, len(skeleton), 2))
    np.testing.assert_allclose(filter_bones(skeleton, P, FilterSettings(strength=3.0)), P, rtol=0, atol=1e-9)


def test_a_rigid_steady_translation_is_unchanged_by_filter_bones(skeleton):
    T = 25
    shift = np.arange(T)[:, None] * np.array([2.5, -1.25])
    P = skeleton.positions[None] + shift[:, None, :]
    np.testing.assert_allclose(filter_bones(skeleton, P, FilterSettings(strength=3.0)), P, rtol=0, atol=1e-9)


def test_a_strong_filter_squashes_bones_but_never_below_a_tenth():
    spinner = _spinner()
    T = 30
    length = np.where(np.arange(T) < 15, 40.0, 80.0)  # a sudden stretch
    length[20:] = 10.0  # and a sudden squash
    P = _spin(np.full(T, 0.3), radius=1.0)
    P[:, 1] = P[:, 0] + length[:, None] * np.array([np.cos(0.3), np.sin(0.3)])
    out = filter_bones(spinner, P, FilterSettings(strength=20.0))
    _, filtered = bone_angles(spinner, out)
    floor = MIN_LENGTH_FRACTION * length.max()
    assert filtered.min() >= floor - 1e-9
    assert np.isclose(filtered, floor).any()  # the floor did hold something up
    # never flipped: the bone still points the way it did
    d = out[:, 1] - out[:, 0]
    np.testing.assert_allclose(np.arctan2(d[:, 1], d[:, 0]), 0.3, rtol=0, atol=1e-9)


def test_filter_bones_moves_a_root_like_the_ball(skeleton):
    P = _motion(skeleton)
    settings = FilterSettings(strength=1.0)
    root = skeleton.index("root")
    out = filter_bones(skeleton, P, settings)
    np.testing.assert_allclose(out[:, root], cartoon_filter(P[:, root], settings), rtol=0, atol=1e-12)


# --- bad input ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"strength": -1.0}, r"the filter strength must be a finite number >= 0, got -1.0$"),
        ({"strength": float("nan")}, r"the filter strength must be a finite number >= 0, got nan"),
        ({"strength": float("inf")}, r"the filter strength must be a finite number >= 0, got inf"),
        ({"strength": True}, r"the filter strength must be a finite number >= 0, got True"),
        ({"strength": "2"}, r"the filter strength must be a finite number >= 0, got '2'"),
        ({"strength": None}, r"the filter strength must be a finite number >= 0, got None"),
        ({"strength": 1.0, "sigma": 0},
         r"^the filter width sigma \(frames\) must be a finite number > 0, got 0.0$"),
        ({"strength": 1.0, "sigma": -2.0}, r"sigma \(frames\) must be a finite number > 0, got -2.0"),
        ({"strength": 1.0, "sigma": float("inf")}, r"sigma \(frames\) must be a finite number > 0, got inf"),
        ({"strength": 1.0, "shift": float("nan")},
         r"^the filter time shift \(frames\) must be a finite number, got nan"),
        ({"strength": 1.0, "shift": float("-inf")},
         r"time shift \(frames\) must be a finite number, got -inf"),
    ],
)
def test_bad_settings_are_refused(settings, message):
    with pytest.raises(FilterError, match=message):
        FilterSettings(**settings)


def test_settings_are_kept_as_floats():
    settings = FilterSettings(strength=np.int64(2), sigma=4, shift=np.float32(-1.5))
    assert (settings.strength, settings.sigma, settings.shift) == (2.0, 4.0, -1.5)
    assert all(type(v) is float for v in (settings.strength, settings.sigma, settings.shift))
    assert settings.radius == 14


@pytest.mark.parametrize(
    ("signal", "message"),
    [
        (np.zeros(0), r"the signal has no frames; give at least one"),
        (np.float64(3.0), r"the signal has no time axis"),
        (np.array([0.0, 1.0, np.nan, 2.0]), r"non-finite value at frame 2; give finite numbers"),
        (np.array([[0.0, 1.0], [np.inf, 2.0]]), r"non-finite value at frame 1"),
        ([["a", "b"]], r"the signal must be an array of numbers"),
    ],
)
def test_bad_signals_are_refused(signal, message):
    with pytest.raises(FilterError, match=message):
        cartoon_filter(signal, FilterSettings(strength=1.0))


def test_settings_must_be_filter_settings():
    with pytest.raises(FilterError, match=r"settings must be a FilterSettings, got float"):
        cartoon_filter(np.zeros(5), 1.0)


def test_unknown_joints_are_refused_with_the_joint_names(skeleton):
    P = _motion(skeleton, T=5)
    names = r"unknown joint 'tail'; the skeleton's joints are: root, hip, torso, neck, head, right_shoulder"
    with pytest.raises(FilterError, match=names):
        filter_trajectories(skeleton, P, FilterSettings(strength=1.0), joints=["root", "tail"])
    with pytest.raises(FilterError, match=r"a sequence of joint names such as \['root'\], got 'root'"):
        filter_trajectories(skeleton, P, FilterSettings(strength=1.0), joints="root")
    assert joint_indices(skeleton, ("hip", "root", "hip")) == [1, 0]


@pytest.mark.parametrize("function", [filter_bones, filter_trajectories])
def test_positions_of_the_wrong_shape_are_refused(skeleton, function):
    options = {"joints": ["root"]} if function is filter_trajectories else {}
    P = _motion(skeleton, T=5)
    for wrong in (P[:, :-1], P[..., :1], P[0], np.zeros((0, len(skeleton), 2))):
        with pytest.raises(FilterError, match=r"positions must have shape \(frames, 17, 2\)"):
            function(skeleton, wrong, FilterSettings(strength=1.0), **options)
    P[3, 4, 1] = np.nan
    with pytest.raises(FilterError, match=r"non-finite value at frame 3"):
        function(skeleton, P, FilterSettings(strength=1.0), **options)
