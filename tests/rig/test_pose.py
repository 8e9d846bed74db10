"""Tests for toonmotion.rig.pose: building, checking and bending poses."""

import numpy as np
import pytest

from toonmotion.errors import PoseError
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import (
    MIN_POSED_FRACTION,
    Pose,
    carried_pose,
    check_pose,
    descendants,
    pose_from_joints,
    pose_to_joints,
    rest_pose,
    rotate_about,
)
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _joints(skeleton, positions=None):
    positions = skeleton.positions if positions is None else positions
    return {name: [float(x), float(y)] for name, (x, y) in zip(skeleton.names, positions, strict=True)}


def _brute_descendants(skeleton, j):
    """Joints with ``j`` among their ancestors, by walking up from each joint."""
    out = []
    for i in range(len(skeleton)):
        p = skeleton.parents[i]
        while p >= 0 and p != j:
            p = skeleton.parents[p]
        if p == j:
            out.append(i)
    return out


# --- pose_from_joints and check_pose ------------------------------------------------------------


def test_pose_from_joints_puts_positions_in_joint_order(skeleton):
    joints = _joints(skeleton)
    shuffled = dict(reversed(list(joints.items())))
    pose = pose_from_joints(skeleton, shuffled)
    np.testing.assert_array_equal(pose.positions, skeleton.positions)
    assert pose_to_joints(skeleton, pose) == joints
    assert list(pose_to_joints(skeleton, pose)) == list(skeleton.names)


def test_a_pose_is_read_only(skeleton):
    pose = rest_pose(skeleton)
    with pytest.raises(ValueError):
        pose.positions[0, 0] = 1.0
    # rest_pose copies: the skeleton's rest positions are not shared with the pose.
    assert not np.shares_memory(pose.positions, skeleton.positions)


def test_unknown_joint_is_named_with_the_skeletons_joints(skeleton):
    joints = _joints(skeleton) | {"tail": [0, 0]}
    with pytest.raises(PoseError, match=r"pose: unknown joint 'tail'; the skeleton's joints are: root, hip"):
        pose_from_joints(skeleton, joints)


@pytest.mark.parametrize(
    ("drop", "message"),
    [
        (["left_hand"], r"joint 'left_hand' has no position; give every joint \[x, y\]$"),
        (["left_hand", "neck", "head"], r"joint 'neck' has no position.* \(3 are missing\)"),
    ],
)
def test_missing_joints_are_named(skeleton, drop, message):
    joints = {k: v for k, v in _joints(skeleton).items() if k not in drop}
    with pytest.raises(PoseError, match=message):
        pose_from_joints(skeleton, joints)


@pytest.mark.parametrize("value", [[np.nan, 1.0], [1.0, np.inf], [-np.inf, 0.0]])
def test_non_finite_position_is_refused(skeleton, value):
    joints = _joints(skeleton) | {"right_knee": value}
    with pytest.raises(PoseError, match=r"joint 'right_knee' has a non-finite position"):
        pose_from_joints(skeleton, joints)


@pytest.mark.parametrize("value", ["12, 40", None, [1.0], [1.0, 2.0, 3.0], ["x", 2.0], {"x": 1}])
def test_position_that_is_not_two_numbers_is_refused(skeleton, value):
    joints = _joints(skeleton) | {"neck": value}
    with pytest.raises(PoseError, match=r"joint 'neck' has position .*; give two numbers \[x, y\]"):
        pose_from_joints(skeleton, joints)


def test_joints_must_be_a_mapping(skeleton):
    with pytest.raises(PoseError, match="keys.json: joints must be a mapping"):
        pose_from_joints(skeleton, list(_joints(skeleton).values()), where="keys.json")


def test_numbers_in_any_numeric_form_are_accepted(skeleton):
    assert np.all(skeleton.positions == np.rint(skeleton.positions))  # whole pixels: exact below
    joints = {name: (int(x), np.float32(y)) for name, (x, y) in _joints(skeleton).items()}
    pose = pose_from_joints(skeleton, joints)
    assert pose.positions.dtype == np.float64
    np.testing.assert_array_equal(pose.positions, skeleton.positions)


def test_collapsed_bone_is_refused_with_its_lengths(skeleton):
    P = np.array(skeleton.positions)
    hand, elbow = skeleton.index("right_hand"), skeleton.index("right_elbow")
    rest = np.linalg.norm(P[hand] - P[elbow])
    P[hand] = P[elbow] + 0.5 * MIN_POSED_FRACTION * (P[hand] - P[elbow])
    with pytest.raises(PoseError, match=rf"bone 'right_hand' is squashed to {0.01 * rest:.3g} px "
                                        rf"\(rest length {rest:.3g} px\); keep it at least 2%"):
        pose_from_joints(skeleton, _joints(skeleton, P))
    # Squashed to just over the limit is still a pose; a zero-length rest bone may do anything.
    P[hand] = P[elbow] + 1.01 * MIN_POSED_FRACTION * (skeleton.positions[hand] - P[elbow])
    P[skeleton.index("hip")] += (30.0, -5.0)  # root -> hip has rest length 0
    check_pose(skeleton, Pose(P))


def test_check_pose_counts_joints(skeleton):
    with pytest.raises(PoseError, match=r"frame 3: has 16 joint positions but the skeleton has 17 joints"):
        check_pose(skeleton, Pose(np.array(skeleton.positions[:-1])), where="frame 3")
    P = np.array(skeleton.positions)
    P[skeleton.index("left_foot"), 1] = np.nan
    with pytest.raises(PoseError, match=r"joint 'left_foot' has a non-finite position"):
        check_pose(skeleton, Pose(P))


# --- descendants, rotate_about ---------------------------------------------------------------------


def test_descendants_are_every_joint_below_parents_first(skeleton):
    for j in range(len(skeleton)):
        below = descendants(skeleton, j)
        assert below.tolist() == _brute_descendants(skeleton, j)
        order = {int(i): n for n, i in enumerate(below)}
        for i in below:  # a joint's parent comes before it (or is j itself)
            p = int(skeleton.parents[i])
            assert p == j or order[p] < order[int(i)]
    names = [skeleton.names[i] for i in descendants(skeleton, skeleton.index("right_shoulder"))]
    assert names == ["right_elbow", "right_hand"]
    assert len(descendants(skeleton, skeleton.index("root"))) == len(skeleton) - 1


@pytest.mark.parametrize("joint", ["right_elbow", "left_shoulder", "torso", "right_hip", "root"])
@pytest.mark.parametrize("angle", [0.7, -2.5, np.pi])
def test_rotate_about_turns_only_what_lies_below_and_keeps_lengths(skeleton, joint, angle):
    P = skeleton.positions
    Q = rotate_about(skeleton, P, joint, angle)
    j = skeleton.index(joint)
    below = descendants(skeleton, j)
    still = np.setdiff1d(np.arange(len(skeleton)), below)
    np.testing.assert_array_equal(Q[still], P[still])  # bit for bit, the joint itself too
    np.testing.assert_allclose(bone_angles(skeleton, Q)[1], skeleton.bone_lengths, rtol=0, atol=1e-12)
    # Every joint below keeps its distance to the pivot and turns by exactly ``angle`` about it.
    rel_p, rel_q = P[below] - P[j], Q[below] - P[j]
    np.testing.assert_allclose(np.linalg.norm(rel_q, axis=1), np.linalg.norm(rel_p, axis=1), atol=1e-12)
    turned = np.arctan2(rel_q[:, 1], rel_q[:, 0]) - np.arctan2(rel_p[:, 1], rel_p[:, 0])
    moving = np.linalg.norm(rel_p, axis=1) > 0
    np.testing.assert_allclose(np.exp(1j * (turned[moving] - angle)), 1.0, rtol=0, atol=1e-12)
    # Turning back restores the pose; the input is not modified.
    np.testing.assert_allclose(rotate_about(skeleton, Q, joint, -angle), P, rtol=0, atol=1e-12)
    assert Q is not P


def test_rotate_about_positive_angle_is_clockwise_on_screen(skeleton):
    # The right forearm points down-left (-x, +y); a quarter turn clockwise on screen (y down)
    # points it up-left: (dx, dy) -> (-dy, dx).
    P = skeleton.positions
    e, h = skeleton.index("right_elbow"), skeleton.index("right_hand")
    Q = rotate_about(skeleton, P, "right_elbow", np.pi / 2)
    dx, dy = P[h] - P[e]
    np.testing.assert_allclose(Q[h] - Q[e], [-dy, dx], atol=1e-12)


def test_rotate_about_scales_the_bones_below(skeleton):
    Q = rotate_about(skeleton, skeleton.positions, "right_shoulder", 0.3, scale=1.5)
    lengths = bone_angles(skeleton, Q)[1]
    for b, name in enumerate(skeleton.bone_names):
        factor = 1.5 if name in ("right_elbow", "right_hand") else 1.0
        assert lengths[b] == pytest.approx(factor * skeleton.bone_lengths[b], rel=1e-12, abs=1e-12)


def test_rotate_about_a_leaf_changes_nothing(skeleton):
    Q = rotate_about(skeleton, skeleton.positions, "left_foot", 1.0)
    np.testing.assert_array_equal(Q, skeleton.positions)


def test_a_pose_carried_onto_moved_joints_keeps_every_other_joint_and_each_bones_turn(skeleton):
    rng = np.random.default_rng(3)
    pose = Pose(skeleton.positions + rng.normal(0, 15, skeleton.positions.shape))
    same = carried_pose(skeleton, skeleton, pose)
    np.testing.assert_array_equal(same.positions, pose.positions)  # nothing moved: exactly the pose
    moved = skeleton.positions.copy()
    elbow = skeleton.index("left_elbow")
    moved[elbow] += (3.0, -2.0)
    after = Skeleton(skeleton.names, skeleton.parents, moved)
    carried = carried_pose(skeleton, after, pose).positions
    others = np.arange(len(skeleton)) != elbow
    np.testing.assert_array_equal(carried[others], pose.positions[others])
    # The upper arm's turn and stretch from rest to pose, applied to the moved rest elbow.
    shoulder = skeleton.parents[elbow]
    rest_bone, posed_bone = (complex(*(p[elbow] - p[shoulder])) for p in (skeleton.positions, pose.positions))
    expected = posed_bone / rest_bone * complex(*(moved[elbow] - skeleton.positions[shoulder]))
    assert complex(*(carried[elbow] - pose.positions[shoulder])) == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(carried_pose(skeleton, after, rest_pose(skeleton)).positions, moved, atol=1e-9)
    fewer = Skeleton.from_joints([("extra", None, (0.0, 0.0))])
    with pytest.raises(PoseError, match="'extra' is not in the skeleton"):
        carried_pose(skeleton, fewer, pose)
