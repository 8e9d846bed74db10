"""Tests for toonmotion.rig.auto_skeleton."""

import numpy as np
import pytest

from toonmotion.errors import SkeletonError
from toonmotion.rig.auto_skeleton import skeleton_from_curve_skeleton
from toonmotion.shape.curve_skeleton import curve_skeleton


def _plus():
    mask = np.zeros((81, 81), dtype=bool)
    mask[36:45, 4:77] = True
    mask[4:77, 36:45] = True
    return mask  # centre (40, 40), arm tips near x or y = 4 and 76


def _bar(length=120):
    mask = np.zeros((20, length + 10), dtype=bool)
    mask[6:14, 5 : 5 + length] = True
    return mask  # centre line y = 9.5, from x = 5 to x = 4 + length


def _children(skeleton):
    children = {i: [] for i in range(len(skeleton))}
    for child, parent in enumerate(skeleton.parents):
        if parent >= 0:
            children[int(parent)].append(child)
    return children


def _chain(skeleton, start, children):
    """Joints from ``start`` down a chain that must not branch."""
    out = [start]
    while children[out[-1]]:
        (nxt,) = children[out[-1]]
        out.append(nxt)
    return out


def test_plus_is_rooted_at_the_junction_with_four_chains():
    s = skeleton_from_curve_skeleton(curve_skeleton(_plus()))
    assert s.names[0] == "root" and s.parents[0] == -1
    assert np.count_nonzero(s.parents == -1) == 1
    np.testing.assert_allclose(s.positions[0], [40, 40], atol=1.5)
    children = _children(s)
    assert len(children[0]) == 4
    tips = []
    for first in children[0]:
        chain = _chain(s, first, children)
        tips.append(s.positions[chain[-1]])
        # Each chain heads away from the root along one arm.
        d = np.linalg.norm(s.positions[chain] - s.positions[0], axis=1)
        assert np.all(np.diff(d) > 0)
    tips = np.array(tips)
    expected = np.array([[40, 4], [40, 76], [4, 40], [76, 40]], dtype=float)
    for tip in expected:
        assert np.min(np.linalg.norm(tips - tip, axis=1)) <= 6.0
    assert all(n == "root" or n.startswith("joint") for n in s.names)


def test_bar_without_junction_is_rooted_near_its_middle():
    mask = _bar(120)
    s = skeleton_from_curve_skeleton(curve_skeleton(mask))
    assert np.count_nonzero(s.parents == -1) == 1
    root = s.positions[s.index("root")]
    assert abs(root[0] - 64.5) <= 3.0
    assert abs(root[1] - 9.5) <= 2.0
    # Both halves hang off the root, reaching the two ends of the bar.
    children = _children(s)
    assert len(children[0]) == 2
    ends = sorted(s.positions[_chain(s, c, children)[-1]][0] for c in children[0])
    assert ends[0] <= 10 and ends[1] >= 119


@pytest.mark.parametrize("max_bone", [10.0, 17.0, 40.0])
def test_max_bone_splits_long_branches(max_bone):
    s = skeleton_from_curve_skeleton(curve_skeleton(_bar(200)), max_bone=max_bone)
    assert s.bone_lengths.max() <= max_bone + 2.0
    # Splitting is even, not just capped: no bone much shorter than needed either.
    assert s.bone_lengths.min() >= max_bone / 2 - 2.0
    total = s.bone_lengths.sum()
    assert total >= 190.0
    assert len(s.bones) >= int(np.ceil(190.0 / max_bone))


def test_default_max_bone_is_a_fifth_of_the_figure():
    s = skeleton_from_curve_skeleton(curve_skeleton(_bar(200)))
    assert s.bone_lengths.max() <= 200 / 5 + 2.0
    assert len(s.bones) >= 5


def test_plus_max_bone_splits_each_arm():
    s = skeleton_from_curve_skeleton(curve_skeleton(_plus()), max_bone=12.0)
    assert s.bone_lengths.max() <= 12.0 + 2.0
    children = _children(s)
    assert len(children[0]) == 4
    for first in children[0]:
        assert len(_chain(s, first, children)) >= 3


def test_two_blobs_give_a_forest():
    mask = np.zeros((40, 100), dtype=bool)
    mask[5:35, 5:30] = True
    mask[10:30, 50:95] = True
    s = skeleton_from_curve_skeleton(curve_skeleton(mask))
    roots = [s.names[i] for i in np.flatnonzero(s.parents == -1)]
    assert sorted(roots) == ["root", "root2"]
    # Each tree stays on its own blob.
    children = _children(s)
    for root, (x0, x1) in (("root", (50, 95)), ("root2", (5, 30))):
        stack = [s.index(root)]
        while stack:
            i = stack.pop()
            assert x0 - 1 <= s.positions[i][0] <= x1
            stack.extend(children[i])
    assert len(set(s.names)) == len(s.names)


def test_a_dot_gets_one_upright_bone():
    mask = np.zeros((9, 9), dtype=bool)
    mask[4, 4] = True
    s = skeleton_from_curve_skeleton(curve_skeleton(mask))
    assert s.names == ("root", "joint1")
    assert s.bone_lengths[0] >= 1.0
    np.testing.assert_array_equal(s.positions[0], [4, 4])


def test_empty_curve_skeleton_raises():
    with pytest.raises(SkeletonError, match="the curve skeleton is empty"):
        skeleton_from_curve_skeleton(curve_skeleton(np.zeros((5, 5), dtype=bool)))
