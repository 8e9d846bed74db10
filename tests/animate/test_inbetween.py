"""Tests for toonmotion.animate.inbetween and the bundled sample animation."""

import numpy as np
import pytest

from tests.conftest import expect_every_case_to_fail, rig_character
from toonmotion.animate.inbetween import METHODS, animate_frames, solve_keys
from toonmotion.animate.timeline import EASES, Keyframe, make_timeline
from toonmotion.deform.deformer import Deformer
from toonmotion.errors import SettingsError
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.pose import Pose, check_pose, rest_pose, rotate_about
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character

# Between two keys a vertex may move per frame at most this multiple of its share of the keys'
# difference (key difference / frames between them) times the ease's steepest slope. Uniform
# motion along a straight line gives 1; a turn moves along an arc, a little longer than its chord.
SMOOTHNESS = 1.5
STEEPEST = {"linear": 1.0, "in-out": 1.5, "in": 2.0, "out": 2.0}


@pytest.fixture(scope="module")
def sample():
    """The sample character's deformer, rigged once for this module."""
    rgba, skeleton = sample_character()
    return Deformer(rig_drawing(rgba, skeleton=skeleton))


@pytest.fixture(scope="module")
def char1(drawings_root_module):
    return Deformer(rig_character(drawings_root_module / "char1"))


@pytest.fixture(scope="module")
def drawings_root_module():
    from tests.conftest import DRAWINGS_DIR, _require

    return _require(DRAWINGS_DIR)


def _frames(deformer, timeline, method, keys=None):
    out = list(animate_frames(deformer, timeline, method=method, keys=keys))
    assert [f for f, _ in out] == list(range(timeline.frame_count))
    return np.array([U for _, U in out])


def _wave(skeleton, frames=(2, 10, 18, 26), ease="linear"):
    """Rest, both elbows bent, both arms half raised, rest."""
    P = skeleton.positions
    bent = rotate_about(skeleton, rotate_about(skeleton, P, "right_elbow", 1.0), "left_elbow", -1.0)
    up = rotate_about(skeleton, rotate_about(skeleton, P, "right_shoulder", 0.8), "left_shoulder", -0.8)
    poses = [P, bent, up, P]
    keys = [Keyframe(f, Pose(np.array(p))) for f, p in zip(frames, poses, strict=True)]
    return make_timeline(skeleton, keys, ease=ease)


# --- key frames and frame counts -----------------------------------------------------------------


@pytest.mark.parametrize("method", METHODS)
def test_key_frames_are_the_solved_keys_bit_for_bit(sample, method):
    timeline = sample_keyframes(sample.character.skeleton)
    keys = solve_keys(sample, timeline)
    assert len(keys) == len(timeline.keys)
    for given in (keys, None):  # keys solved beforehand, or solved by animate_frames itself
        frames = _frames(sample, timeline, method, keys=given)
        assert len(frames) == timeline.frame_count == 37
        for key, solved in zip(timeline.keys, keys, strict=True):
            assert np.array_equal(frames[key.frame], solved.U), f"frame {key.frame} is not its key"
    # solve_keys warm-starts each key from the one before, as deform(previous=...) does.
    previous = None
    for key, solved in zip(timeline.keys, keys, strict=True):
        previous = sample.deform(key.pose, previous=previous)
        assert np.array_equal(previous.U, solved.U)


@pytest.mark.parametrize("method", METHODS)
def test_frames_before_the_first_key_hold_it(sample, method):
    timeline = _wave(sample.character.skeleton)
    keys = solve_keys(sample, timeline)
    frames = _frames(sample, timeline, method, keys=keys)
    assert len(frames) == 27
    for f in range(3):
        assert np.array_equal(frames[f], keys[0].U)


@pytest.mark.parametrize("method", METHODS)
def test_a_timeline_of_rest_keys_is_the_rest_mesh_throughout(sample, method):
    skeleton = sample.character.skeleton
    timeline = make_timeline(skeleton, [Keyframe(0, rest_pose(skeleton)), Keyframe(5, rest_pose(skeleton))])
    frames = _frames(sample, timeline, method)
    rest = np.broadcast_to(sample.character.mesh.V, frames.shape)
    np.testing.assert_allclose(frames, rest, rtol=0, atol=1e-9)


def test_a_bogus_method_is_refused(sample):
    timeline = _wave(sample.character.skeleton)
    with pytest.raises(SettingsError, match=r"method must be one of interpolate, solve, got 'bogus'"):
        next(animate_frames(sample, timeline, method="bogus"))


def test_a_bogus_method_is_refused_when_called(sample):
    with pytest.raises(SettingsError):
        animate_frames(sample, _wave(sample.character.skeleton), method="bogus")


# --- smooth in-betweens ---------------------------------------------------------------------------


def _worst_step(frames, timeline):
    """Per pair of keys: the largest vertex move between consecutive frames over that pair's
    share of the keys' difference (largest key-to-key move / frames between the keys)."""
    worst = []
    for a, b in zip(timeline.keys, timeline.keys[1:], strict=False):
        i, j = a.frame, b.frame
        difference = np.linalg.norm(frames[j] - frames[i], axis=1).max()
        steps = np.linalg.norm(np.diff(frames[i:j + 1], axis=0), axis=2).max()
        worst.append(steps / (difference / (j - i)))
    return np.array(worst)


# The design gap behind the known failures of the two tests below; one test covers them all.
SOLVE_DRIFT = "'solve' warm-starts each frame from the last and stage two stops early: frames drift from keys"

# Stage two's unfolding (docs/posing.md) widens the joint area on the frames where a triangle is
# crushed; the widened solve lands apart from the previous frame's, where the crushed triangles
# made a spike at the armpit (visible in the picture, invisible to this test), so 'solve' pops once.
UNFOLD_POP = "'solve' pops on the frame where stage two first widens its joint area round a crushed triangle"
UNFOLD_FAILS = {
    ("char1", "linear", "solve"): "frame 14 -> 15 moves 33.1 px where its neighbours move 10.5 px (3.2x), "
                                  "17 -> 18 61.5 px against 9.7 (6.3x): the joint area widens round a "
                                  "spike at the right armpit, and again",
    ("char1", "in-out", "solve"): "the same frames with in-out easing",
}
# With the joints anchored (DeformSettings.joint_anchor) the worst step of char1's second pair of keys is
# 3.5x the key difference per frame (bar 2.25x), and the sample's in-out solve no longer pops (2.33x before).

SMOOTHNESS_FAILS = {
    ("sample", "linear", "solve"): "frame 6 (a key) pops 31.7 px from frame 5 where its neighbours move "
                                   "~14.5 px: 2.18x the key difference per frame. The key is solved from "
                                   "the previous key, the frames before it from the previous frame, and "
                                   "stage two stops early (tolerance 1e-3), so the two land apart",
}


def _smooth_cases():
    """Every case but the known failures (the strict xfail tests below have those)."""
    return [pytest.param(who, ease, method, id=f"{who}-{ease}-{method}")
            for who in ("sample", "char1") for ease in ("linear", "in-out") for method in METHODS
            if (who, ease, method) not in SMOOTHNESS_FAILS and (who, ease, method) not in UNFOLD_FAILS]


@pytest.mark.parametrize(("who", "ease", "method"), _smooth_cases())
def test_in_betweens_move_smoothly_from_key_to_key(request, who, ease, method):
    _check_smooth(request.getfixturevalue(who), who, ease, method)


def _check_smooth(deformer, who, ease, method):
    skeleton = deformer.character.skeleton
    if who == "sample":
        timeline = make_timeline(skeleton, sample_keyframes(skeleton).keys, fps=12, ease=ease)
    else:
        timeline = _wave(skeleton, ease=ease)
    frames = _frames(deformer, timeline, method)
    worst = _worst_step(frames, timeline)
    print(f"\n{who} {ease} {method}: worst step / (key difference / frames), per pair of keys: "
          f"{np.round(worst, 2)}")
    assert np.all(worst <= SMOOTHNESS * STEEPEST[ease])
    assert set(STEEPEST) == set(EASES)


HOLD_FAILS = {
    ("sample", "solve"): "the held pose drifts 0.95 px while its two keys differ by 0.25 px",
    ("char1", "solve"): "the held pose drifts 23.6 px while its two keys differ by 0.67 px: every frame "
                        "warm-starts from the last and stage two, stopped early by its 1e-3 tolerance, "
                        "keeps descending (energy 2622 -> 2256 over 8 re-solves of one pose)",
}


@pytest.mark.parametrize(("who", "method"), [
    pytest.param(w, m, id=f"{w}-{m}")
    for w in ("sample", "char1") for m in METHODS if (w, m) not in HOLD_FAILS
])
def test_a_held_pose_holds_still(request, who, method):
    _check_hold(request.getfixturevalue(who), who, method)


def _check_hold(deformer, who, method):
    skeleton = deformer.character.skeleton
    P = skeleton.positions
    bent = Pose(rotate_about(skeleton, rotate_about(skeleton, P, "right_elbow", 1.0), "left_elbow", -1.0))
    timeline = make_timeline(skeleton, [Keyframe(0, bent), Keyframe(6, bent)])
    keys = solve_keys(deformer, timeline)
    frames = _frames(deformer, timeline, method, keys=keys)
    keys_apart = np.abs(keys[1].U - keys[0].U).max()
    drift = np.abs(frames - keys[0].U).max()
    print(f"\n{who} {method}: keys {keys_apart:.3g} px apart, frames drift {drift:.3g} px")
    assert drift <= keys_apart + 1e-9


@pytest.mark.xfail(strict=True, raises=AssertionError, reason=UNFOLD_POP)
def test_solved_frames_do_not_pop_where_stage_two_unfolds(request):
    """Every case of ``UNFOLD_FAILS``, each as strict as the smoothness test."""
    expect_every_case_to_fail({
        f"smooth {who}-{ease}-{method}": lambda who=who, ease=ease, method=method: _check_smooth(
            request.getfixturevalue(who), who, ease, method) for who, ease, method in UNFOLD_FAILS})


@pytest.mark.xfail(strict=True, raises=AssertionError, reason=SOLVE_DRIFT)
def test_solved_frames_stay_with_their_keys(request):
    """Every case of ``SMOOTHNESS_FAILS`` and ``HOLD_FAILS``, each as strict as its plain test."""
    cases = {f"smooth {who}-{ease}-{method}": lambda who=who, ease=ease, method=method: _check_smooth(
        request.getfixturevalue(who), who, ease, method) for who, ease, method in SMOOTHNESS_FAILS}
    cases.update({f"hold {who}-{method}": lambda who=who, method=method: _check_hold(
        request.getfixturevalue(who), who, method) for who, method in HOLD_FAILS})
    expect_every_case_to_fail(cases)


# --- the sample animation ---------------------------------------------------------------------------


def test_sample_keyframes_are_valid_poses_that_keep_every_bone_length(sample):
    skeleton = sample.character.skeleton
    timeline = sample_keyframes(skeleton)
    assert [k.frame for k in timeline.keys] == [0, 6, 12, 18, 24, 30, 36]
    assert timeline.fps == 12 and timeline.ease == "in-out" and timeline.frame_count == 37
    for key in timeline.keys:
        assert check_pose(skeleton, key.pose) is key.pose
        np.testing.assert_allclose(bone_angles(skeleton, key.pose.positions)[1], skeleton.bone_lengths,
                                   rtol=0, atol=1e-9)
    first, crouch, hop, landing, *_, last = timeline.keys
    np.testing.assert_array_equal(first.pose.positions, skeleton.positions)
    np.testing.assert_array_equal(last.pose.positions, skeleton.positions)
    np.testing.assert_array_equal(landing.pose.positions, crouch.pose.positions)
    feet = [skeleton.index("right_foot"), skeleton.index("left_foot")]
    np.testing.assert_allclose(crouch.pose.positions[feet], skeleton.positions[feet], atol=1e-9)  # planted
    hip = skeleton.index("hip")
    assert crouch.pose.positions[hip, 1] > skeleton.positions[hip, 1]  # lower (y down)
    assert np.all(hop.pose.positions[feet, 1] < skeleton.positions[feet, 1])  # off the ground


def test_sample_keyframes_scale_with_the_character():
    small = sample_character(scale=0.5)[1]
    big = sample_character(scale=1.0)[1]
    for a, b in zip(sample_keyframes(small).keys, sample_keyframes(big).keys, strict=True):
        np.testing.assert_allclose(2 * a.pose.positions, b.pose.positions, rtol=1e-12, atol=1e-9)


SAMPLE_KEY_FAILS = {}


@pytest.mark.parametrize("frame", [
    pytest.param(f, marks=[pytest.mark.xfail(strict=True, reason=SAMPLE_KEY_FAILS[f])]
                 if f in SAMPLE_KEY_FAILS else [])
    for f in (0, 6, 12, 18, 24, 30, 36)
])
def test_sample_animation_keys_have_no_inverted_joint_triangle(sample, frame):
    character = sample.character
    timeline = sample_keyframes(character.skeleton)
    keys = dict(zip((k.frame for k in timeline.keys), solve_keys(sample, timeline), strict=True))
    areas = triangle_areas(keys[frame].U, character.mesh.F)
    inverted = int((areas[character.binding.joint_triangle] <= 0).sum())
    assert inverted == 0, f"{inverted} joint triangles inverted at key frame {frame}"


def test_a_key_edit_is_in_the_key_and_fades_through_the_inbetweens(sample):
    """A drag on a key's mesh is exactly in that key and carried in and out by the in-betweens."""
    from toonmotion.deform.tuning import DragEdit

    skeleton = sample.character.skeleton
    head = skeleton.positions[skeleton.index("head")]
    rest = rest_pose(skeleton)
    plain = make_timeline(skeleton, [Keyframe(0, rest), Keyframe(8, rest), Keyframe(16, rest)], fps=12)
    drag = DragEdit(start=[head], end=[head + (6.0, -4.0)])
    tuned = make_timeline(skeleton, [Keyframe(0, rest), Keyframe(8, rest, (drag,)), Keyframe(16, rest)],
                          fps=12)
    before = _frames(sample, plain, "interpolate")
    after = _frames(sample, tuned, "interpolate")
    vertex = int(np.argmin(np.hypot(*(before[8] - head).T)))
    np.testing.assert_allclose(after[8][vertex], head + (6.0, -4.0), atol=1e-9)
    moved = [np.hypot(*(after[f][vertex] - before[f][vertex])) for f in range(17)]
    assert moved[0] == moved[16] == 0
    # Linear in-betweens: the edit grows and fades in equal steps.
    np.testing.assert_allclose(moved[:9], np.linspace(0, moved[8], 9), atol=1e-6)
    np.testing.assert_allclose(moved[8:], np.linspace(moved[8], 0, 9), atol=1e-6)


def test_replacing_the_poses_with_their_own_changes_nothing(sample):
    """``poses=`` (how exaggerated poses come in) with the timeline's own poses gives its frames."""
    from toonmotion.animate.motion import motion_from_timeline

    skeleton = sample.character.skeleton
    timeline = sample_keyframes(skeleton)
    keys = solve_keys(sample, timeline)
    own = motion_from_timeline(skeleton, timeline).positions
    default = _frames(sample, timeline, "interpolate", keys)
    replaced = list(animate_frames(sample, timeline, keys=keys, poses=own))
    assert [f for f, _ in replaced] == list(range(timeline.frame_count))
    np.testing.assert_allclose(np.array([U for _, U in replaced]), default, atol=1e-9)
    with pytest.raises(SettingsError, match="replacement poses must have shape"):
        animate_frames(sample, timeline, keys=keys, poses=own[:-1])
