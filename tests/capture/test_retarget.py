"""Tests for toonmotion.capture.retarget (thesis 4.5, eq. 4.7-4.8)."""

import numpy as np
import pytest

from toonmotion.animate.motion import Motion
from toonmotion.capture.retarget import retarget
from toonmotion.errors import MotionError
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import rotate_about
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _dance(skeleton, frames=30):
    """Elbows swinging, a knee bending, a stretch and a hop: every kind of change."""
    out = []
    for f in range(frames):
        t = f / frames * 2 * np.pi
        P = rotate_about(skeleton, skeleton.positions, "right_elbow", 2.5 * np.sin(t))
        P = rotate_about(skeleton, P, "left_knee", -0.6 * np.sin(t), scale=1 + 0.2 * np.sin(t))
        out.append(P + (3.0 * f, -20 * np.sin(t) ** 2))
    return np.stack(out)


def _scaled(skeleton, factor, offset):
    return Skeleton(names=skeleton.names, parents=skeleton.parents.copy(),
                    positions=skeleton.positions * factor + offset)


def test_onto_its_own_skeleton_is_the_motion(skeleton):
    motion = Motion(skeleton, _dance(skeleton), fps=12)
    out = retarget(motion, skeleton)
    np.testing.assert_allclose(out.positions, motion.positions, atol=1e-9)
    assert out.fps == 12 and out.skeleton is skeleton


def test_onto_a_smaller_copy_is_the_motion_scaled(skeleton):
    """Lengths follow the captured ratios and roots move in proportion: a similar figure
    replays a similar motion."""
    motion = Motion(skeleton, _dance(skeleton), fps=12)
    small = _scaled(skeleton, 0.5, (40.0, -7.0))
    out = retarget(motion, small)
    np.testing.assert_array_equal(out.positions[0], small.positions)
    expected = 0.5 * (motion.positions - motion.positions[0]) + small.positions
    np.testing.assert_allclose(out.positions, expected, atol=1e-9)


def test_bones_copy_turns_and_stretches_not_positions(skeleton):
    """A target in another rest pose (arms down) turns each bone by the captured increments."""
    motion = Motion(skeleton, _dance(skeleton), fps=12)
    arms_down = Skeleton(names=skeleton.names, parents=skeleton.parents.copy(),
                         positions=rotate_about(skeleton, skeleton.positions, "right_shoulder", 1.2))
    out = retarget(motion, arms_down)
    a_src, l_src = bone_angles(skeleton, motion.positions)
    a_out, l_out = bone_angles(arms_down, out.positions)
    turn = np.angle(np.exp(1j * ((a_out - a_out[0]) - (a_src - a_src[0]))))
    np.testing.assert_allclose(turn, 0, atol=1e-9)
    usable = l_src[0] > 1e-6
    np.testing.assert_allclose(l_out[:, usable] / l_out[0, usable], l_src[:, usable] / l_src[0, usable],
                               rtol=1e-9)


def test_a_joint_map_and_unmatched_bones():
    """Joints named differently match through the map; a bone the capture lacks turns with its parent."""
    source = Skeleton.from_joints(
        [("hip", None, (0, 0)), ("knee", "hip", (0, 10)), ("foot", "knee", (0, 20))]
    )
    target = Skeleton.from_joints([("pelvis", None, (5, 5)), ("knee", "pelvis", (5, 25)),
                                   ("ankle", "knee", (5, 45)), ("toe", "ankle", (15, 45))])
    frames = np.stack([source.positions, rotate_about(source, source.positions, "hip", np.pi / 2)])
    out = retarget(Motion(source, frames, fps=10), target, joint_map={"pelvis": "hip", "ankle": "foot"})
    # The leg turns a quarter turn about the pelvis, and the toe with it.
    np.testing.assert_allclose(out.positions[1], [[5, 5], [-15, 5], [-35, 5], [-35, 15]], atol=1e-9)


def test_a_forest_hat_and_man():
    """Two objects tracked apart (the thesis' hat and man) retarget together."""
    source = Skeleton.from_joints([("hat", None, (0, -5)), ("brim", "hat", (4, -5)),
                                   ("hip", None, (0, 10)), ("head", "hip", (0, 0))])
    target = _scaled(source, 2.0, (100.0, 100.0))
    frames = np.stack([source.positions, source.positions + (0, -6)])
    out = retarget(Motion(source, frames, fps=10), target)
    np.testing.assert_allclose(out.positions[1], target.positions + (0, -12), atol=1e-9)


def test_mismatched_motions_are_refused(skeleton):
    motion = Motion(skeleton, _dance(skeleton, 3), fps=12)
    stranger = Skeleton.from_joints([("a", None, (0, 0)), ("b", "a", (1, 0))])
    with pytest.raises(MotionError, match="no bone of the target matches"):
        retarget(motion, stranger)
    swapped = Skeleton.from_joints([("root", None, (0, 0)), ("right_hand", "root", (1, 0)),
                                    ("right_elbow", "right_hand", (2, 0))])
    with pytest.raises(MotionError, match="has no matching bone in the motion"):
        retarget(motion, swapped)
    with pytest.raises(MotionError, match="the joint map names 'tail', which the target"):
        retarget(motion, skeleton, joint_map={"tail": "root"})
    with pytest.raises(MotionError, match="the joint map names 'tail', which the motion"):
        retarget(motion, skeleton, joint_map={"root": "tail"})


def test_a_captured_bone_seen_end_on_keeps_enough_length_to_pose(skeleton):
    """The forearm foreshortened to 0.5% at one frame (pointing at the camera): the target's
    forearm keeps SHORTEST of its length there, so the frame can be posed, and every other frame
    is as the capture says."""
    from toonmotion.capture.retarget import SHORTEST
    from toonmotion.rig.pose import Pose, check_pose

    frames = np.repeat(skeleton.positions[None], 5, axis=0)
    hand, elbow = skeleton.index("right_hand"), skeleton.index("right_elbow")
    frames[2, hand] = frames[2, elbow] + 0.005 * (frames[2, hand] - frames[2, elbow])
    found = retarget(Motion(skeleton, frames, fps=12), skeleton)
    _, length = bone_angles(skeleton, found.positions)
    _, rest = bone_angles(skeleton, skeleton.positions)
    b = skeleton.bone_names.index("right_hand")
    assert length[2, b] == pytest.approx(SHORTEST * rest[b])
    for t in range(5):
        check_pose(skeleton, Pose(found.positions[t]), where=f"frame {t}")
    np.testing.assert_allclose(found.positions[[0, 1, 3, 4]], frames[[0, 1, 3, 4]], atol=1e-9)
