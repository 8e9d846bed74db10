"""The motion prior (toonmotion.proxy3d.prior): joints matched to markers, up axis, resampling."""

import numpy as np
import pytest

from tests.proxy3d.conftest import clip_path
from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics
from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.errors import ProxyError
from toonmotion.io.bvh import load_bvh
from toonmotion.proxy3d.prior import Prior, prior_from_bvh, resample_prior


def _z_up(clip):
    """The same clip under a new root turned +90 degrees about X: its +Y up becomes +Z up."""
    return BvhClip(
        names=("World", *clip.names), parents=np.concatenate([[-1], clip.parents + 1]),
        offsets=np.vstack([np.zeros(3), clip.offsets]), channels=(("Xrotation",), *clip.channels),
        motion=np.hstack([np.full((clip.frame_count, 1), 90.0), clip.motion]), frame_time=clip.frame_time,
    )


@pytest.mark.parametrize("name, up", [("cmu_07_01_walk.bvh", "y"), ("cmu_jumping_jacks.bvh", "y"),
                                      ("fair_wave_hello.bvh", "z")])
def test_standard_markers_match_every_convention_with_a_tree(name, up):
    clip = load_bvh(clip_path(name))
    prior = prior_from_bvh(clip, STANDARD_JOINTS, start=1, stop=11)
    assert prior.frame_count == 10 and prior.fps == pytest.approx(clip.fps)
    parents = {n: (prior.names[p] if p >= 0 else None)
               for n, p in zip(prior.names, prior.parents, strict=True)}
    assert parents["left_hand"] == "left_elbow" and parents["left_knee"] == "left_hip"
    assert parents["hips"] is None and parents["left_hip"] == "hips" and parents["head"] == "neck"
    world = forward_kinematics(clip)[1:11, [clip.names.index(j) for j in prior.joints]]
    # Y-up clips: positions are the world's, untouched; a Z-up clip (FAIR's) is turned about X.
    x, y, z = np.moveaxis(world, -1, 0)
    assert np.array_equal(prior.positions, world if up == "y" else np.stack([x, z, -y], axis=-1))
    height = prior.positions[..., 1]
    assert np.all(height[:, prior.names.index("head")] > height[:, prior.names.index("left_foot")])


def test_a_z_up_clip_is_turned_to_y_up(walk_clip):
    upright = prior_from_bvh(walk_clip, STANDARD_JOINTS, start=1, stop=40)
    lying = _z_up(walk_clip)
    assert forward_kinematics(lying)[1, lying.names.index("Head"), 2] > 10  # the head is up +Z
    turned = prior_from_bvh(lying, STANDARD_JOINTS, start=1, stop=40)
    assert np.allclose(turned.positions, upright.positions, atol=1e-9)
    # Said explicitly, and wrongly: nothing is guessed over the caller.
    assert np.allclose(prior_from_bvh(lying, STANDARD_JOINTS, start=1, stop=40, up="y").positions,
                       forward_kinematics(lying)[1:40, [lying.names.index(j) for j in turned.joints]])


def test_explicit_map_and_own_names(walk_clip):
    prior = prior_from_bvh(walk_clip, ["pelvis", "LeftHand", "wrist"], joint_map={"pelvis": "Hips",
                                                                                   "wrist": "RightHand"})
    assert prior.joints == ("Hips", "LeftHand", "RightHand")
    assert prior.parents.tolist() == [-1, 0, 0]  # nearest marked ancestors


def test_missing_markers_are_named_in_one_line(walk_clip):
    with pytest.raises(ProxyError, match=r"the motion prior lacks the markers tail, left_wing: ") as caught:
        prior_from_bvh(walk_clip, ["hips", "tail", "left_wing"])
    said = str(caught.value)
    # One line a terminal shows whole: the clip's 31 joints are not all listed.
    assert "\n" not in said and len(said) < 400 and f"({len(walk_clip.names)} in all)" in said


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"joint_map": {"hips": "Nope"}}, "the joint map names 'Nope', which the mocap clip does not have"),
        ({"joint_map": {"spine": "Hips"}}, "markers 'hips' and 'spine' both match the mocap joint 'Hips'"),
        ({"start": 5000}, "holds none of the clip's 317 frames"),
        ({"up": "w"}, "up must be one of"),
    ],
)
def test_bad_prior_requests(walk_clip, kwargs, message):
    with pytest.raises(ProxyError, match=message):
        prior_from_bvh(walk_clip, ["hips", "spine", "head"], **kwargs)


def test_resampling_hits_the_original_frames_and_interpolates_between(walk_clip):
    prior = prior_from_bvh(walk_clip, STANDARD_JOINTS, start=1)
    fps = prior.fps / 5  # 24 fps from 120
    low = resample_prior(prior, fps)
    assert low.frame_count == (prior.frame_count - 1) // 5 + 1
    assert np.allclose(low.positions, prior.positions[::5], atol=1e-9)
    half = resample_prior(prior, prior.fps * 2)
    assert np.allclose(half.positions[1::2], (prior.positions[:-1] + prior.positions[1:]) / 2)
    assert low.names == prior.names and np.array_equal(low.parents, prior.parents)


def test_prior_validates_itself():
    with pytest.raises(ProxyError, match="cycle"):
        Prior(("a", "b"), [1, 0], np.zeros((1, 2, 3)), fps=12)
    with pytest.raises(ProxyError, match="non-finite"):
        Prior(("a",), [-1], np.full((1, 1, 3), np.nan), fps=12)
    with pytest.raises(ProxyError, match=r"shape \(frames, 1, 3\)"):
        Prior(("a",), [-1], np.zeros((0, 1, 3)), fps=12)
