"""Tests for toonmotion.animate.animation: key-frames or a motion in, a mesh per frame out."""

import numpy as np
import pytest

from toonmotion.animate.animation import (
    animate_motion,
    animate_timeline,
    exaggerate,
    same_depth_overlaps,
)
from toonmotion.animate.cartoon_filter import FilterSettings, filter_bones
from toonmotion.animate.inbetween import animate_frames, solve_keys
from toonmotion.animate.motion import Motion, motion_from_timeline
from toonmotion.deform.deformer import Deformer
from toonmotion.errors import SettingsError
from toonmotion.rig.edits import DepthEdit, apply_edit
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def hero():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    return character, Deformer(character), sample_keyframes(skeleton)


def test_a_timeline_animates_as_the_in_between_steps_do_one_by_one(hero):
    character, deformer, timeline = hero
    animation = animate_timeline(deformer, timeline)
    solved = solve_keys(deformer, timeline)
    frames = list(animate_frames(deformer, timeline, keys=solved))
    assert [f for f, _ in animation.meshes] == list(range(timeline.frame_count))
    for (_, U), (_, expected) in zip(animation.meshes, frames, strict=True):
        np.testing.assert_array_equal(U, expected)
    np.testing.assert_array_equal(
        animation.motion.positions, motion_from_timeline(character.skeleton, timeline).positions
    )
    assert len(animation.keys) == len(animation.solved) == len(timeline.keys)


def test_key_frames_are_their_own_solves_exactly(hero):
    _, deformer, timeline = hero
    animation = animate_timeline(deformer, timeline)
    meshes = dict(animation.meshes)
    for key, result in zip(animation.keys, animation.solved, strict=True):
        np.testing.assert_array_equal(meshes[key.frame], result.U)


def test_an_exaggerated_timeline_follows_the_filtered_poses(hero):
    character, deformer, timeline = hero
    settings = FilterSettings(strength=1.5)
    animation = animate_timeline(deformer, timeline, exaggeration=settings)
    plain = motion_from_timeline(character.skeleton, timeline)
    np.testing.assert_array_equal(
        animation.motion.positions, filter_bones(character.skeleton, plain.positions, settings)
    )


def test_an_unknown_method_is_refused(hero):
    _, deformer, timeline = hero
    with pytest.raises(SettingsError, match="method must be one of"):
        animate_timeline(deformer, timeline, method="guess")


def test_a_motion_animates_every_frame_at_its_own_or_the_given_rate(hero):
    character, deformer, timeline = hero
    motion = motion_from_timeline(character.skeleton, timeline)
    animation = animate_motion(deformer, motion)
    assert len(animation.meshes) == motion.frame_count and animation.motion.fps == motion.fps
    assert animate_motion(deformer, motion, fps=5).motion.fps == 5
    assert animation.keys == () and animation.solved == ()


def test_exaggerating_with_no_settings_gives_the_motion_back(hero):
    character, _, timeline = hero
    motion = motion_from_timeline(character.skeleton, timeline)
    assert exaggerate(motion, None) is motion


def test_exaggerating_chosen_joints_moves_only_them_and_what_hangs_below(hero):
    character, _, timeline = hero
    motion = motion_from_timeline(character.skeleton, timeline)
    out = exaggerate(motion, FilterSettings(strength=2.0), joints=["right_hand"])
    moved = np.abs(out.positions - motion.positions).max(axis=(0, 2)) > 1e-9
    assert moved[character.skeleton.index("right_hand")]
    assert not moved[character.skeleton.index("left_hand")]
    assert isinstance(out, Motion) and out.fps == motion.fps


def test_overlaps_are_reported_once_per_pair_with_every_key_they_happen_in(hero):
    character, deformer, timeline = hero
    animation = animate_timeline(deformer, timeline)
    keyed = [(key.frame, result.U) for key, result in zip(animation.keys, animation.solved, strict=True)]
    once = {(o.bone_a, o.bone_b): o for o in same_depth_overlaps(character, keyed)}
    twice = same_depth_overlaps(character, keyed + keyed)
    pairs = [(o.bone_a, o.bone_b) for o in twice]
    assert len(pairs) == len(set(pairs)) and set(pairs) == set(once)
    for o in twice:
        first = once[(o.bone_a, o.bone_b)]
        assert o.frames == first.frames * 2 and o.area == first.area > 0
        assert set(o.frames) <= {key.frame for key in animation.keys}


def test_overlaps_never_pair_a_bone_with_its_own_chain(hero):
    character, deformer, timeline = hero
    animation = animate_timeline(deformer, timeline)
    parents = character.skeleton.parents
    index = character.skeleton.index

    def chain(j):
        out = set()
        while j >= 0:
            out.add(j)
            j = int(parents[j])
        return out

    for o in same_depth_overlaps(
        character, [(k.frame, r.U) for k, r in zip(animation.keys, animation.solved, strict=True)]
    ):
        a, b = index(o.bone_a), index(o.bone_b)
        assert a not in chain(b) and b not in chain(a)


def test_regions_set_to_different_depths_are_not_reported(hero):
    character, deformer, timeline = hero
    animation = animate_timeline(deformer, timeline)
    keyed = [(k.frame, r.U) for k, r in zip(animation.keys, animation.solved, strict=True)]
    found = same_depth_overlaps(character, keyed)
    if not found:
        pytest.skip("the sample's key-frames have no same-depth overlaps to separate")
    layered = apply_edit(character, DepthEdit(value=5, bone=found[0].bone_a))
    assert (found[0].bone_a, found[0].bone_b) not in {
        (o.bone_a, o.bone_b) for o in same_depth_overlaps(layered, keyed)
    }
