"""Tests for toonmotion.rig.kinematics: rotations, bones to joint positions and back."""

import numpy as np
import pytest

from toonmotion.errors import PoseError
from toonmotion.rig.kinematics import (
    bone_angles,
    direction,
    positions_from_bones,
    rotate,
    rotation,
    transform,
)
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _random_skeleton(rng, k, roots=1):
    """A forest of ``k`` joints with ``roots`` roots, random parents and positions (pixels)."""
    joints = []
    for j in range(k):
        parent = None if j < roots else f"j{rng.integers(0, j)}"
        joints.append((f"j{j}", parent, tuple(rng.uniform(-300, 300, 2))))
    return Skeleton.from_joints(joints)


# --- rotations ----------------------------------------------------------------------------------


def test_a_positive_angle_turns_x_towards_y_clockwise_on_screen():
    np.testing.assert_allclose(rotation(np.pi / 2), [[0, -1], [1, 0]], atol=1e-15)
    np.testing.assert_allclose(rotate([1.0, 0.0], np.pi / 2), [0, 1], atol=1e-15)  # +x to +y (down)
    np.testing.assert_allclose(rotate([0.0, -1.0], np.pi / 2), [1, 0], atol=1e-15)  # up to right
    np.testing.assert_allclose(direction([0, np.pi / 2, np.pi]), [[1, 0], [0, 1], [-1, 0]], atol=1e-15)


def test_rotations_compose_and_invert():
    rng = np.random.default_rng(0)
    a, b = rng.uniform(-10, 10, (2, 50))
    np.testing.assert_allclose(rotation(a) @ rotation(b), rotation(a + b), rtol=0, atol=1e-13)
    np.testing.assert_allclose(rotation(a) @ rotation(-a), np.broadcast_to(np.eye(2), (50, 2, 2)),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.det(rotation(a)), 1.0, rtol=0, atol=1e-15)
    P = rng.normal(0, 100, (7, 2))
    np.testing.assert_allclose(rotate(rotate(P, 0.4, about=(3, 4)), 0.9, about=(3, 4)),
                               rotate(P, 1.3, about=(3, 4)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(rotate(rotate(P, a[0]), -a[0]), P, rtol=0, atol=1e-12)


def test_rotate_matches_rotation_matrices_and_broadcasts_angles():
    rng = np.random.default_rng(1)
    P = rng.normal(0, 50, (4, 6, 2))  # 4 frames of 6 points
    angle = rng.uniform(-np.pi, np.pi, 4)
    centre = rng.normal(0, 50, (4, 1, 2))
    turned = rotate(P, angle[:, None], about=centre)  # one angle and centre per frame
    for t in range(4):
        expected = centre[t] + (P[t] - centre[t]) @ rotation(angle[t]).T
        np.testing.assert_allclose(turned[t], expected, rtol=0, atol=1e-12)
    # One angle per point, and distances to the centre kept.
    each = rotate(P[0], angle[:1].repeat(6) + np.arange(6))
    for n in range(6):
        np.testing.assert_allclose(each[n], rotation(angle[0] + n) @ P[0, n], rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.hypot(*each.T), np.hypot(*P[0].T), rtol=1e-15)
    assert rotate(P, 0.3).shape == P.shape


def test_transform_maps_about_a_centre_and_does_not_touch_its_input():
    P = np.array([[3.0, 1.0], [1.0, 1.0]])
    out = transform(P, [[2.0, 0.0], [0.0, 3.0]], about=[1.0, 1.0])
    np.testing.assert_array_equal(out, [[5.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(P, [[3.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(transform(P, rotation(0.0)), P)


# --- bones <-> positions ------------------------------------------------------------------------


def test_bone_angles_are_batched_over_leading_axes(skeleton):
    rng = np.random.default_rng(5)
    P = skeleton.positions + rng.normal(0, 20, size=(2, 3, len(skeleton), 2))
    angle, length = bone_angles(skeleton, P)
    assert angle.shape == length.shape == (2, 3, len(skeleton.bones))
    for a in range(2):
        for b in range(3):
            one_angle, one_length = bone_angles(skeleton, P[a, b])
            np.testing.assert_array_equal(angle[a, b], one_angle)
            np.testing.assert_array_equal(length[a, b], one_length)
    # Each bone runs from its parent joint to its child: atan2(dy, dx) with y down.
    d = P[..., skeleton.bones[:, 1], :] - P[..., skeleton.bones[:, 0], :]
    np.testing.assert_allclose(length * np.cos(angle), d[..., 0], atol=1e-12)
    np.testing.assert_allclose(length * np.sin(angle), d[..., 1], atol=1e-12)
    np.testing.assert_allclose(bone_angles(skeleton, skeleton.positions)[1], skeleton.bone_lengths,
                               rtol=1e-15)


@pytest.mark.parametrize("seed", range(6))
def test_forward_kinematics_inverts_bone_angles_on_random_skeletons(seed):
    rng = np.random.default_rng(seed)
    skeleton = _random_skeleton(rng, int(rng.integers(1, 30)), roots=int(rng.integers(1, 4)))
    P = skeleton.positions
    angles, lengths = bone_angles(skeleton, P)
    np.testing.assert_allclose(positions_from_bones(skeleton, P, angles, lengths), P, rtol=0, atol=1e-12)
    # Roots given alone, in joint order, do the same.
    roots = P[skeleton.parents < 0]
    np.testing.assert_allclose(positions_from_bones(skeleton, roots, angles, lengths), P, rtol=0, atol=1e-12)


def test_forward_kinematics_inverts_bone_angles_on_batched_frames():
    rng = np.random.default_rng(7)
    skeleton = _random_skeleton(rng, 25, roots=2)
    P = skeleton.positions + rng.normal(0, 40, size=(5, 4, len(skeleton), 2))  # (5, 4) frames
    angles, lengths = bone_angles(skeleton, P)
    out = positions_from_bones(skeleton, P, angles, lengths)
    assert out.shape == P.shape
    np.testing.assert_allclose(out, P, rtol=0, atol=1e-12)
    # Batched frames give what one frame at a time gives, bit for bit.
    for a in range(5):
        for b in range(4):
            one = positions_from_bones(skeleton, P[a, b], angles[a, b], lengths[a, b])
            np.testing.assert_array_equal(out[a, b], one)


def test_leading_axes_broadcast_between_roots_and_bones(skeleton):
    angles, lengths = bone_angles(skeleton, skeleton.positions)
    turned = angles + np.linspace(0, 1, 3)[:, None]  # 3 frames, one pair of roots
    out = positions_from_bones(skeleton, skeleton.positions, turned, lengths)
    assert out.shape == (3, len(skeleton), 2)
    np.testing.assert_allclose(out[0], skeleton.positions, rtol=0, atol=1e-12)


def test_a_rigid_rotation_of_every_bone_rotates_the_pose(skeleton):
    rng = np.random.default_rng(2)
    P = skeleton.positions
    angles, lengths = bone_angles(skeleton, P)
    root = P[skeleton.parents < 0]
    for turn in rng.uniform(-np.pi, np.pi, 5):
        out = positions_from_bones(skeleton, root, angles + turn, lengths)
        np.testing.assert_allclose(out, rotate(P, turn, about=root[0]), rtol=0, atol=1e-12)


def test_given_offsets_replace_the_masked_bones_only():
    rng = np.random.default_rng(4)
    skeleton = _random_skeleton(rng, 12)
    P = skeleton.positions
    angles, lengths = bone_angles(skeleton, P)
    given = rng.random(len(lengths)) < 0.5
    offsets = P[skeleton.bones[:, 1]] - P[skeleton.bones[:, 0]]
    # Masked bones' angles and lengths are ignored: garbage there changes nothing.
    angles[given], lengths[given] = np.nan, np.nan
    out = positions_from_bones(skeleton, P, angles, lengths, offsets=offsets, given=given)
    np.testing.assert_allclose(out, P, rtol=0, atol=1e-12)
    moved = positions_from_bones(skeleton, P, angles, lengths, offsets=offsets + 1.0, given=given)
    ones = np.where(given[:, None], 1.0, 0.0) * [1.0, 1.0]  # +1 on the given bones only
    shift = positions_from_bones(skeleton, P, np.zeros_like(angles), np.zeros_like(lengths),
                                 offsets=ones, given=np.ones_like(given))
    np.testing.assert_allclose(moved - out, shift - shift[0], rtol=0, atol=1e-12)


def test_wrong_shapes_raise_pose_errors(skeleton):
    angles, lengths = bone_angles(skeleton, skeleton.positions)
    roots_shape = r"root positions must have shape \(\.\.\., 17, 2\) or \(\.\.\., 1, 2\)"
    with pytest.raises(PoseError, match=roots_shape):
        positions_from_bones(skeleton, np.zeros((3, 2)), angles, lengths)
    with pytest.raises(PoseError, match=r"bone angles must have shape \(\.\.\., 16\)"):
        positions_from_bones(skeleton, skeleton.positions, angles[:-1], lengths)
    with pytest.raises(PoseError, match="give both offsets and the mask"):
        positions_from_bones(skeleton, skeleton.positions, angles, lengths, offsets=np.zeros((16, 2)))
    with pytest.raises(PoseError, match=r"bone offsets must have shape"):
        positions_from_bones(skeleton, skeleton.positions, angles, lengths, offsets=np.zeros((15, 2)),
                             given=np.zeros(16, bool))
