"""Tests for toonmotion.testing.poses: pose sets from a skeleton's structure, not its names."""

import numpy as np

from toonmotion.rig.pose import rest_pose
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character
from toonmotion.testing.poses import bend_joints, chain_starts, extreme_poses, key_poses, stretch_poses


def _renamed(skeleton):
    """The same skeleton with every joint called ``j<i>``: nothing may depend on the names."""
    return Skeleton(names=tuple(f"j{i}" for i in range(len(skeleton))), parents=skeleton.parents,
                    positions=skeleton.positions)


def test_pose_sets_do_not_depend_on_joint_names():
    _, skeleton = sample_character()
    other = _renamed(skeleton)
    assert bend_joints(skeleton) == bend_joints(other)
    assert chain_starts(skeleton) == chain_starts(other)
    for a, b in zip(key_poses(skeleton), key_poses(other), strict=True):
        np.testing.assert_array_equal(a.positions, b.positions)
    for (_, a), (_, b) in zip(extreme_poses(skeleton), extreme_poses(other), strict=True):
        np.testing.assert_array_equal(a.positions, b.positions)


def test_the_sample_skeleton_bends_its_elbows_and_knees_and_raises_its_limbs():
    _, skeleton = sample_character()
    names = {skeleton.names[j] for j in bend_joints(skeleton)}
    assert {"right_elbow", "left_elbow", "right_knee", "left_knee"} <= names
    starts = {skeleton.names[j] for j in chain_starts(skeleton)}
    assert {"right_shoulder", "left_shoulder", "right_hip", "left_hip"} <= starts
    labels = [label for label, _ in extreme_poses(skeleton)]
    # 150 degrees above the root (an elbow), 120 below it (a knee), both ways.
    assert {"right_elbow +150", "right_elbow -150", "left_knee +120", "left_knee -120"} <= set(labels)
    assert {"chains raised", "upper body +40", "upper body -40"} <= set(labels)


def test_bends_turn_one_joint_by_the_angle_and_stretches_lengthen_one_bone():
    _, skeleton = sample_character()
    P = skeleton.positions
    poses = dict(extreme_poses(skeleton))
    e = skeleton.index("right_elbow")
    Q = poses["right_elbow +150"].positions
    child = skeleton.index("right_hand")
    before, after = P[child] - P[e], Q[child] - Q[e]
    turn = np.degrees(np.arctan2(before[0] * after[1] - before[1] * after[0], before @ after))
    assert abs(abs(turn) - 150) < 1e-9
    np.testing.assert_array_equal(Q[: child], P[: child])
    rest = skeleton.bone_lengths
    for label, pose in stretch_poses(skeleton):
        lengths = np.linalg.norm(pose.positions[skeleton.bones[:, 1]] - pose.positions[skeleton.bones[:, 0]],
                                 axis=1)
        changed = np.flatnonzero(~np.isclose(lengths, rest, rtol=0, atol=1e-9))
        assert len(changed) == 1 and skeleton.bone_names[changed[0]] == label.split()[0]
        assert abs(lengths[changed[0]] - 1.5 * rest[changed[0]]) < 1e-9
    assert len(stretch_poses(skeleton)) == int((rest > 1e-6).sum())
    np.testing.assert_array_equal(key_poses(skeleton)[0].positions, rest_pose(skeleton).positions)
