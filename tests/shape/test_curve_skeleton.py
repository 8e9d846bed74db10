"""Tests for toonmotion.shape.curve_skeleton."""

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage as ndi

from toonmotion.shape.curve_skeleton import (
    NODE_KINDS,
    curve_skeleton,
    default_bone_length,
    joint_suggestions,
    split_points,
)
from toonmotion.shape.thinning import hilditch_thin


def _plus():
    mask = np.zeros((61, 61), bool)
    mask[26:35, 4:57] = True
    mask[4:57, 26:35] = True
    return mask


def _bumpy_rectangle():
    """A 31 x 100 px rectangle with a 6 px tall, 8 px wide bump on its top side."""
    mask = np.zeros((50, 120), bool)
    mask[10:41, 10:110] = True
    mask[4:10, 56:64] = True
    return mask


def _ring():
    yy, xx = np.mgrid[:80, :80]
    r = np.hypot(xx - 39.5, yy - 39.5)
    return (r < 30) & (r > 15)


def _disk(radius=25):
    yy, xx = np.mgrid[:80, :80]
    return np.hypot(xx - 39.5, yy - 39.5) < radius


def _drawing_mask(folder):
    return np.asarray(Image.open(folder / "mask.png").convert("L")) >= 128


def _count(cs, kind):
    return sum(k == kind for k in cs.kinds)


def _check_graph(cs, mask):
    """Structural invariants every curve skeleton must satisfy."""
    k = len(cs.nodes)
    assert cs.nodes.shape == (k, 2) and cs.radius.shape == (k,) and len(cs.kinds) == k
    assert set(cs.kinds) <= set(NODE_KINDS)
    assert cs.branches.shape == (len(cs.paths), 2)
    assert np.all((cs.branches >= 0) & (cs.branches < k))
    # Nodes lie inside the mask, and their radius is the distance to the outline there.
    r, c = np.rint(cs.nodes[:, 1]).astype(int), np.rint(cs.nodes[:, 0]).astype(int)
    assert mask[r, c].all()
    assert np.all(cs.radius >= 1)
    junction = np.array([kind == "junction" for kind in cs.kinds])
    for (a, b), path in zip(cs.branches, cs.paths, strict=True):
        # A path runs from its first node's position to its second's.
        np.testing.assert_array_equal(path[0], cs.nodes[a])
        np.testing.assert_array_equal(path[-1], cs.nodes[b])
        # Pixel steps are 8-neighbour moves; only the step to a junction's centre is longer.
        step = np.linalg.norm(np.diff(path, axis=0), axis=1)
        assert np.all(step > 0), "repeated point in a branch path"
        inner = step[1 if junction[a] else 0 : len(step) - 1 if junction[b] else len(step)]
        assert np.all(inner <= np.sqrt(2) + 1e-9)
        assert step.max() <= 4.0, "a junction's centre is close to its pixels"
        # Every path pixel is in the mask.
        assert mask[np.rint(path[:, 1]).astype(int), np.rint(path[:, 0]).astype(int)].all()
    np.testing.assert_allclose(
        cs.lengths, [np.linalg.norm(np.diff(p, axis=0), axis=1).sum() for p in cs.paths]
    )


# Synthetic shapes ----------------------------------------------------------------------------


def test_plus_sign_has_four_ends_one_junction_four_branches():
    mask = _plus()
    cs = curve_skeleton(mask)
    _check_graph(cs, mask)
    assert _count(cs, "end") == 4 and _count(cs, "junction") == 1 and len(cs.kinds) == 5
    assert len(cs.paths) == 4
    j = cs.kinds.index("junction")
    np.testing.assert_allclose(cs.nodes[j], [30, 30], atol=1.5)
    # Every branch joins the junction to a different end point.
    others = np.where(cs.branches[:, 0] == j, cs.branches[:, 1], cs.branches[:, 0])
    assert np.all(np.any(cs.branches == j, axis=1))
    assert sorted(others.tolist()) == [i for i, k in enumerate(cs.kinds) if k == "end"]
    # The arms reach close to the ends of the plus, 26 px from the centre.
    assert np.all(cs.lengths > 18)


def test_bump_spur_is_pruned():
    mask = _bumpy_rectangle()
    pruned = curve_skeleton(mask)
    _check_graph(pruned, mask)
    assert _count(pruned, "junction") == 0
    assert _count(pruned, "end") == 2 and len(pruned.paths) == 1
    # The one branch runs along the rectangle, not up into the bump.
    assert pruned.lengths[0] > 60
    assert np.all(np.concatenate(pruned.paths)[:, 1] >= 10)


def test_bump_spur_is_kept_with_prune_zero():
    mask = _bumpy_rectangle()
    kept = curve_skeleton(mask, prune=0)
    _check_graph(kept, mask)
    assert _count(kept, "junction") >= 1
    # An end point sits in the bump (rows 4-9, columns 56-63).
    ends = kept.nodes[[k == "end" for k in kept.kinds]]
    in_bump = (ends[:, 1] < 10) & (ends[:, 0] >= 56) & (ends[:, 0] <= 63)
    assert in_bump.sum() == 1


def test_ring_gives_one_loop_node_and_a_closed_branch():
    mask = _ring()
    cs = curve_skeleton(mask)
    _check_graph(cs, mask)
    assert cs.kinds == ("loop",)
    assert cs.branches.tolist() == [[0, 0]]
    path = cs.paths[0]
    np.testing.assert_array_equal(path[0], path[-1])
    # The loop runs round the middle of the ring, radius 22.5.
    r = np.hypot(path[:, 0] - 39.5, path[:, 1] - 39.5)
    assert np.all(np.abs(r - 22.5) <= 2.0)
    assert cs.lengths[0] == pytest.approx(2 * np.pi * 22.5, rel=0.1)


def test_disk_thins_to_a_short_central_structure():
    cs = curve_skeleton(_disk(25))
    _check_graph(cs, _disk(25))
    assert 1 <= len(cs.nodes) <= 3
    assert set(cs.kinds) <= {"point", "end", "junction"}
    assert np.all(np.hypot(cs.nodes[:, 0] - 39.5, cs.nodes[:, 1] - 39.5) < 12.5)
    assert cs.lengths.sum() < 25


def test_single_pixel_gives_a_point_node():
    mask = np.zeros((5, 5), bool)
    mask[2, 2] = True
    cs = curve_skeleton(mask)
    assert cs.kinds == ("point",)
    np.testing.assert_array_equal(cs.nodes, [[2, 2]])
    assert len(cs.paths) == 0 and cs.branches.shape == (0, 2)


def test_empty_mask_gives_an_empty_graph():
    cs = curve_skeleton(np.zeros((6, 6), bool))
    assert cs.nodes.shape == (0, 2) and cs.kinds == () and cs.paths == ()


def _end_pixels(mask):
    """Pixels of the unpruned skeleton with exactly one skeleton neighbour."""
    skeleton = hilditch_thin(mask)
    degree = ndi.convolve(skeleton.astype(int), np.ones((3, 3), int), mode="constant") - 1
    return np.count_nonzero(skeleton & (degree == 1))


def test_prune_and_min_spur_zero_keep_every_branch():
    mask = _bumpy_rectangle()
    everything = curve_skeleton(mask, prune=0, min_spur=0)
    assert _count(everything, "end") == _end_pixels(mask)
    assert len(everything.paths) > len(curve_skeleton(mask).paths)


# Joint suggestions -----------------------------------------------------------------------------


def _arc_positions(path, points):
    """Arc length along ``path`` of each point, which must lie on it."""
    seg_a, seg_b = path[:-1], path[1:]
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(seg_b - seg_a, axis=1))])
    ab = seg_b - seg_a
    length2 = np.maximum(np.sum(ab * ab, axis=1), 1e-12)
    out = []
    for p in points:
        t = np.clip(np.sum((p - seg_a) * ab, axis=1) / length2, 0, 1)
        d = np.linalg.norm(seg_a + t[:, None] * ab - p, axis=1)
        i = int(np.argmin(d))
        assert d[i] < 1e-6, "a suggested joint is off its branch"
        out.append(arc[i] + t[i] * np.linalg.norm(ab[i]))
    return np.array(out), arc[-1]


@pytest.mark.parametrize("max_bone", [5.0, 12.0, 30.0])
def test_along_points_split_long_branches_into_short_pieces(max_bone):
    cs = curve_skeleton(_plus())
    points, kinds = joint_suggestions(cs, max_bone=max_bone)
    assert len(points) == len(kinds)
    assert kinds[: len(cs.nodes)] == cs.kinds
    np.testing.assert_array_equal(points[: len(cs.nodes)], cs.nodes)
    along = points[[k == "along" for k in kinds]]
    expected_total = 0
    for path, length in zip(cs.paths, cs.lengths, strict=True):
        split = split_points(path, max_bone)
        pieces = int(np.ceil(length / max_bone - 1e-9))
        assert len(split) == max(pieces - 1, 0)
        expected_total += len(split)
        at, total = _arc_positions(path, split)
        bounds = np.concatenate([[0.0], at, [total]])
        assert np.all(np.diff(bounds) <= max_bone + 1e-9)
        np.testing.assert_allclose(np.diff(bounds), total / max(pieces, 1))
        for p in split:  # each split point is among the suggestions
            assert np.any(np.all(np.isclose(along, p), axis=1))
    assert len(along) == expected_total


def test_short_branches_get_no_along_points():
    cs = curve_skeleton(_plus())
    points, kinds = joint_suggestions(cs, max_bone=1000.0)
    assert "along" not in kinds
    np.testing.assert_array_equal(points, cs.nodes)


def test_default_bone_is_a_fifth_of_the_diagonal():
    cs = curve_skeleton(_plus())
    every = np.concatenate([cs.nodes, *cs.paths])
    diagonal = np.linalg.norm(np.ptp(every, axis=0))
    assert default_bone_length(cs) == pytest.approx(diagonal / 5)
    points, kinds = joint_suggestions(cs)
    expected = sum(len(split_points(p, default_bone_length(cs))) for p in cs.paths)
    assert kinds.count("along") == expected > 0
    assert len(points) == len(cs.nodes) + expected


# Real drawings ---------------------------------------------------------------------------------


def test_drawing_skeleton_has_limbs_and_a_body(drawing_dir):
    mask = _drawing_mask(drawing_dir)
    cs = curve_skeleton(mask)
    _check_graph(cs, mask)
    assert _count(cs, "end") >= 4
    assert _count(cs, "junction") >= 1


def test_drawing_pruning_only_removes(drawing_dir):
    mask = _drawing_mask(drawing_dir)
    pruned, kept = curve_skeleton(mask), curve_skeleton(mask, prune=0, min_spur=0)
    _check_graph(kept, mask)
    assert _count(kept, "end") == _end_pixels(mask)
    assert _count(pruned, "end") <= _count(kept, "end")
    assert len(pruned.paths) <= len(kept.paths)
