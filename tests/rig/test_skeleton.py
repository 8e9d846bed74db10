"""Tests for toonmotion.rig.skeleton."""

import numpy as np
import pytest

from toonmotion.errors import SkeletonError, ToonmotionError
from toonmotion.rig.skeleton import Skeleton

# A man and, tracked apart from him, his hat: a forest of two trees, given children first.
MAN_AND_HAT = [
    ("hand", "elbow", (30.0, 40.0)),
    ("brim", "hat", (12.0, -5.0)),
    ("elbow", "shoulder", (20.0, 30.0)),
    ("head", "neck", (10.0, 5.0)),
    ("shoulder", "neck", (15.0, 20.0)),
    ("neck", "hip", (10.0, 15.0)),
    ("hat", None, (10.0, -8.0)),
    ("hip", None, (10.0, 50.0)),
]


def _check_parents_first(skeleton):
    parents = skeleton.parents
    for i, p in enumerate(parents):
        assert p == -1 or 0 <= p < i, f"joint {skeleton.names[i]} comes before its parent"


def test_from_joints_orders_parents_first_and_keeps_the_forest():
    s = Skeleton.from_joints(MAN_AND_HAT)
    _check_parents_first(s)
    assert sorted(s.names) == sorted(j[0] for j in MAN_AND_HAT)
    roots = {s.names[i] for i in np.flatnonzero(s.parents == -1)}
    assert roots == {"hat", "hip"}
    given = {name: (parent, xy) for name, parent, xy in MAN_AND_HAT}
    for name, parent, xy in s.joints():
        assert given[name] == (parent, xy)
    for i, name in enumerate(s.names):
        np.testing.assert_array_equal(s.positions[i], given[name][1])
        parent = given[name][0]
        assert s.parents[i] == (-1 if parent is None else s.names.index(parent))
    assert len(s) == 8
    assert s.parents.dtype == np.int64 and s.positions.dtype == np.float64
    assert s.positions.shape == (8, 2)


def test_joints_round_trip_through_from_joints():
    s = Skeleton.from_joints(MAN_AND_HAT)
    again = Skeleton.from_joints(s.joints())
    assert again.names == s.names
    np.testing.assert_array_equal(again.parents, s.parents)
    np.testing.assert_array_equal(again.positions, s.positions)


def test_a_single_joint_is_a_skeleton_without_bones():
    s = Skeleton.from_joints([("root", None, (1, 2))])
    assert s.names == ("root",)
    assert s.bones.shape == (0, 2)
    assert s.bone_names == ()
    assert s.bone_lengths.shape == (0,)


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        ([("a", None, (0, 0)), ("b", "ghost", (1, 1))], r"joint 'b' names an unknown parent 'ghost'"),
        (
            [("a", "b", (0, 0)), ("b", "a", (1, 1))],
            r"the skeleton has a cycle through joints a, b",
        ),
        (
            # A cycle beside a proper tree is still a cycle; the tree's joints are not blamed.
            [("r", None, (0, 0)), ("c", "r", (1, 0)), ("a", "b", (0, 1)), ("b", "a", (1, 1))],
            r"cycle through joints a, b;",
        ),
        ([("r", None, (0, 0)), ("a", "a", (1, 1))], r"cycle through joints a;"),
        ([("a", None, (0, 0)), ("a", "a", (1, 1))], r"joint name 'a' is used twice"),
        ([("a", None, (0, 0)), ("", "a", (1, 1))], r"a joint has an empty name"),
        ([("a", None, (0, 0)), ("   ", "a", (1, 1))], r"a joint has an empty name"),
        ([("a", None, (0, float("nan")))], r"joint 'a' has a non-finite position"),
        ([("a", None, (float("inf"), 0))], r"joint 'a' has a non-finite position"),
        ([("a", None, (1,))], r"joint 'a' has position \(1,\); give two numbers \[x, y\]"),
        ([("a", None, (1, 2, 3))], r"joint 'a' has position .*give two numbers \[x, y\]"),
        ([("a", None, "xy")], r"joint 'a' has position 'xy'; give two numbers"),
        ([("a", None, None)], r"joint 'a' has position None; give two numbers"),
        ([("a", None, ("one", 2))], r"joint 'a' has position .*give two numbers"),
        ([], r"the skeleton has no joints; give at least one"),
    ],
    ids=[
        "unknown-parent",
        "cycle",
        "cycle-beside-tree",
        "self-parent",
        "duplicate",
        "empty-name",
        "blank-name",
        "nan",
        "inf",
        "one-coordinate",
        "three-coordinates",
        "string",
        "none",
        "non-numeric",
        "no-joints",
    ],
)
def test_malformed_skeletons_raise_skeleton_error(joints, message):
    with pytest.raises(SkeletonError, match=message) as info:
        Skeleton.from_joints(joints)
    assert isinstance(info.value, ToonmotionError)
    assert "\n" not in str(info.value)


def test_bones_names_and_lengths():
    s = Skeleton.from_joints(
        [
            ("root", None, (0.0, 0.0)),
            ("a", "root", (3.0, 4.0)),
            ("b", "a", (3.0, 10.0)),
            ("c", "root", (-1.0, 0.0)),
            ("other", None, (50.0, 50.0)),
            ("same", "other", (50.0, 50.0)),
        ]
    )
    bones = s.bones
    assert bones.shape == (4, 2)
    # One bone per non-root joint, (parent, child), named after the child.
    assert sorted(s.names[c] for c in bones[:, 1]) == ["a", "b", "c", "same"]
    assert s.bone_names == tuple(s.names[c] for c in bones[:, 1])
    for (p, c), name in zip(bones, s.bone_names, strict=True):
        assert s.parents[c] == p
        assert s.names[c] == name
    lengths = dict(zip(s.bone_names, s.bone_lengths, strict=True))
    assert lengths == {"a": 5.0, "b": 6.0, "c": 1.0, "same": 0.0}


def test_index_finds_joints_and_lists_names_when_missing():
    s = Skeleton.from_joints(MAN_AND_HAT)
    for i, name in enumerate(s.names):
        assert s.index(name) == i
    with pytest.raises(SkeletonError, match="no joint is called 'foot'") as info:
        s.index("foot")
    assert f"the joints are: {', '.join(s.names)}" in str(info.value)


def test_arrays_are_read_only():
    s = Skeleton.from_joints(MAN_AND_HAT)
    with pytest.raises(ValueError, match="read-only"):
        s.positions[0, 0] = 99.0
    with pytest.raises(ValueError, match="read-only"):
        s.parents[1] = 0
    assert not s.positions.flags.writeable and not s.parents.flags.writeable


def test_skeleton_is_frozen():
    s = Skeleton.from_joints(MAN_AND_HAT)
    with pytest.raises(AttributeError):
        s.names = ("x",)
