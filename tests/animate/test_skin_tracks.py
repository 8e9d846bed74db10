"""The skinned-rig view of an animation (toonmotion.animate.skin_tracks): stage one is exactly
linear blend skinning of the bone frames, in any orthonormal frame."""

import numpy as np
import pytest

from tests.conftest import SAMPLE
from toonmotion.animate.skin_tracks import bind_offsets, bone_matrices, skin_tracks, skinned, vertex_bones
from toonmotion.api import animate_character
from toonmotion.errors import ExportError
from toonmotion.rig.pose import Pose
from toonmotion.rig.skeleton import Skeleton
from toonmotion.sample_animation import sample_keyframes

FLIP = np.array([1.0, -1.0])


@pytest.mark.parametrize("skinning", ["one-bone", "weights"])
@pytest.mark.parametrize("preserve_area", [True, False], ids=["area", "no area"])
@pytest.mark.parametrize("flip", [False, True], ids=["y down", "y up"])
def test_skinning_the_bone_frames_is_stage_one_and_offsets_land_on_every_frame(rigs, skinning, preserve_area,
                                                                                 flip):
    deformer = rigs.deformer(SAMPLE, skinning=skinning, preserve_area=preserve_area)
    hero = deformer.character
    animation = animate_character(deformer, sample_keyframes(hero.skeleton))
    f = FLIP if flip else np.ones(2)
    tracks = skin_tracks(hero.skeleton, animation.motion.positions * f, preserve_area=preserve_area,
                         rest=hero.skeleton.positions * f)
    bone, weight = vertex_bones(hero, skinning=skinning)
    V = hero.mesh.V * f
    for t, U in animation.meshes:
        M = bone_matrices(tracks, t)
        stage_one = deformer.stage_one(Pose(animation.motion.positions[t])) * f
        assert np.abs(skinned(V, bone, weight, M) - stage_one).max() < 1e-9
        offset = bind_offsets(V, bone, weight, M, U * f)
        assert np.abs(skinned(V + offset, bone, weight, M) - U * f).max() < 1e-9


def test_angles_stay_continuous_through_whole_turns():
    arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    turn = np.linspace(0, 4 * np.pi, 50)
    P = np.zeros((50, 2, 2))
    P[:, 1] = 10 * np.stack([np.cos(turn), np.sin(turn)], axis=1)
    tracks = skin_tracks(arm, P)
    assert np.allclose(tracks.bone_angle[:, 0], turn) and np.allclose(tracks.joint_angle[:, 1], turn)
    _, local = tracks.local_joints()
    assert np.abs(np.diff(local[:, 1])).max() < np.pi


def test_zero_length_bones_translate_and_squashed_bones_are_refused():
    # "tip" sits on "hand" at rest: its vertices only follow the hand's translation.
    chain = Skeleton.from_joints([("a", None, (0, 0)), ("hand", "a", (10, 0)), ("tip", "hand", (10, 0))])
    P = np.array([[[0, 0], [0, 10], [3, 12]]], float)
    tracks = skin_tracks(chain, P)
    M = bone_matrices(tracks, 0)
    assert np.allclose(M[1], [[1, 0, -10], [0, 1, 10]])  # a translation by the hand's move
    assert tracks.joint_angle[0, 2] == tracks.joint_angle[0, 1]  # the tip turns with its parent
    with pytest.raises(ExportError, match="bone hand is squashed to a point in frame 0"):
        skin_tracks(chain, np.array([[[0, 0], [0, 0], [0, 0]]], float))
