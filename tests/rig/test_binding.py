"""Tests for toonmotion.rig.binding (decomposition, thesis 3.3, eq. 3.1)."""

import numpy as np
import pytest
import shapely

from toonmotion.errors import SkeletonError, ToonmotionError
from toonmotion.rig.binding import (
    INTERIOR,
    JOINT,
    SILHOUETTE,
    Correction,
    CorrectionError,
    attach_inside,
    classify,
    decompose,
)
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.mesh import check_mesh, triangulate
from toonmotion.shape.silhouette import trace_silhouette

# A U: two arms 20 px wide, 4 px apart (columns 24-27 are background), joined at the bottom.
GAP = (24, 28)
BAR_TOP = 40


def _u_mask():
    mask = np.zeros((60, 60), dtype=bool)
    mask[4:52, 4:24] = True  # left arm
    mask[4:52, 28:48] = True  # right arm
    mask[BAR_TOP:52, 4:48] = True  # bottom
    return mask


def _u_skeleton():
    # The left bone hugs the arm's outer side and the right bone its inner side, so most of
    # the left arm is nearer the right arm's bone in straight-line distance.
    return Skeleton.from_joints(
        [
            ("bl", None, (6.0, 46.0)),
            ("br", "bl", (30.0, 46.0)),  # bone along the bottom
            ("lt", "bl", (6.0, 6.0)),  # left arm
            ("rt", "br", (30.0, 6.0)),  # right arm
        ]
    )


@pytest.fixture(scope="module")
def u_shape():
    mask = _u_mask()
    mesh = triangulate(trace_silhouette(mask), spacing=3.0)
    assert check_mesh(mesh) == []
    skeleton = _u_skeleton()
    return mesh, skeleton, mask, decompose(mesh, skeleton, mask, rule="straight")


def _distance_to_segment(points, a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    t = np.clip((points - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * (b - a)), axis=1)


def _bone_index(skeleton, name):
    return skeleton.bone_names.index(name)


def test_left_arm_never_attaches_across_the_gap(u_shape):
    mesh, skeleton, _, binding = u_shape
    V = mesh.V
    left_arm = (V[:, 0] < GAP[0]) & (V[:, 1] < BAR_TOP - 2)
    right_arm = (V[:, 0] >= GAP[1] - 0.5) & (V[:, 1] < BAR_TOP - 2)
    to_left = _distance_to_segment(V, (6, 46), (6, 6))
    to_right = _distance_to_segment(V, (30, 46), (30, 6))
    tempted = left_arm & (to_right < to_left)
    # The rule is tested where it matters: plenty of the left arm is nearer the right bone.
    assert tempted.sum() >= 20
    assert not np.any(binding.bone[left_arm] == _bone_index(skeleton, "rt"))
    # Near the bar the bottom bone is nearest and reachable; higher up only the arm's own bone.
    high = V[:, 1] < BAR_TOP - 12
    assert np.all(binding.bone[left_arm & high] == _bone_index(skeleton, "lt"))
    assert (tempted & high).sum() >= 10
    assert np.all(binding.bone[tempted & high] == _bone_index(skeleton, "lt"))
    assert np.all(binding.bone[right_arm & high] == _bone_index(skeleton, "rt"))
    # Every bone lies inside the figure, so no vertex needed the fallback.
    assert not binding.fallback.any()


def test_every_vertex_gets_a_bone(u_shape):
    mesh, skeleton, _, binding = u_shape
    assert binding.bone.shape == (len(mesh.V),)
    assert binding.fallback.shape == (len(mesh.V),)
    assert binding.bone.min() >= 0 and binding.bone.max() < len(skeleton.bones)
    # The bottom bone gets the bar between the arms.
    V = mesh.V
    middle = (V[:, 0] > 12) & (V[:, 0] < 26) & (V[:, 1] > 44)
    assert middle.any()
    assert np.all(binding.bone[middle] == _bone_index(skeleton, "br"))


def _check_classification(mesh, binding):
    b = binding.bone[mesh.F]
    shares = (b[:, 0] == b[:, 1]) & (b[:, 1] == b[:, 2])
    np.testing.assert_array_equal(binding.joint_triangle, ~shares)
    n = len(mesh.V)
    silhouette = np.arange(n) < mesh.n_outline
    np.testing.assert_array_equal(binding.vertex_kind == SILHOUETTE, silhouette)
    in_joint_triangle = np.zeros(n, dtype=bool)
    for f, is_joint in zip(mesh.F, binding.joint_triangle, strict=True):
        if is_joint:
            in_joint_triangle[f] = True
    np.testing.assert_array_equal(binding.vertex_kind == JOINT, ~silhouette & in_joint_triangle)
    np.testing.assert_array_equal(
        binding.vertex_kind == INTERIOR, ~silhouette & ~in_joint_triangle
    )
    np.testing.assert_array_equal(binding.joint_area, in_joint_triangle)


def test_classification_matches_the_definitions(u_shape):
    mesh, _, _, binding = u_shape
    _check_classification(mesh, binding)
    # Not vacuous: every kind and both kinds of triangle occur.
    assert binding.joint_triangle.any() and not binding.joint_triangle.all()
    assert set(np.unique(binding.vertex_kind)) == {SILHOUETTE, INTERIOR, JOINT}
    # The silhouette vertices among joint triangles belong to the joint area too.
    assert np.any(binding.joint_area & (binding.vertex_kind == SILHOUETTE))
    joint_triangle, kind = classify(mesh, binding.bone)
    np.testing.assert_array_equal(joint_triangle, binding.joint_triangle)
    np.testing.assert_array_equal(kind, binding.vertex_kind)


def test_binding_arrays_are_read_only(u_shape):
    _, _, _, binding = u_shape
    for array in (binding.bone, binding.fallback, binding.joint_triangle, binding.vertex_kind,
                  binding.joint_area):
        assert not array.flags.writeable


CURVE = np.array([[2.3, 10.7], [25.1, 10.7], [25.1, 20.3], [2.3, 20.3]])


def test_attach_inside_moves_exactly_the_vertices_in_the_curve(u_shape):
    mesh, skeleton, mask, binding = u_shape
    before = binding.bone.copy()
    corrected = attach_inside(binding, mesh, skeleton, CURVE, "br")
    polygon = shapely.Polygon(CURVE)
    # No vertex sits on the curve, so inside and outside are unambiguous.
    assert shapely.distance(polygon.exterior, shapely.points(mesh.V)).min() > 1e-6
    inside = shapely.contains_xy(polygon, mesh.V[:, 0], mesh.V[:, 1])
    assert inside.sum() >= 10
    br = _bone_index(skeleton, "br")
    assert np.all(corrected.bone[inside] == br)
    np.testing.assert_array_equal(corrected.bone[~inside], before[~inside])
    assert np.any(before[inside] != br)  # something actually moved
    np.testing.assert_array_equal(binding.bone, before)  # the old binding is untouched
    assert binding.corrections == ()
    (correction,) = corrected.corrections
    assert isinstance(correction, Correction)
    assert correction.bone == "br"
    np.testing.assert_array_equal(correction.curve, CURVE)
    np.testing.assert_array_equal(corrected.fallback, binding.fallback)
    _check_classification(mesh, corrected)


def test_decompose_replays_corrections(u_shape):
    mesh, skeleton, mask, binding = u_shape
    once = attach_inside(binding, mesh, skeleton, CURVE, "br")
    twice = attach_inside(once, mesh, skeleton, CURVE[:, ::-1] + [4, -4], "rt")
    assert len(twice.corrections) == 2
    replayed = decompose(mesh, skeleton, mask, corrections=twice.corrections, rule="straight")
    for field in ("bone", "fallback", "joint_triangle", "vertex_kind", "joint_area"):
        np.testing.assert_array_equal(getattr(replayed, field), getattr(twice, field))
    assert [c.bone for c in replayed.corrections] == ["br", "rt"]
    for a, b in zip(replayed.corrections, twice.corrections, strict=True):
        np.testing.assert_array_equal(a.curve, b.curve)


@pytest.mark.parametrize(
    ("curve", "message"),
    [
        ([[0, 0], [10, 0]], "at least 3"),
        ([], "at least 3"),
        ([0, 1, 2, 3, 4, 5], "at least 3"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "at least 3"),
        ([[0, 0], [10, np.nan], [0, 10]], "non-finite"),
    ],
    ids=["two-points", "empty", "flat", "3d", "nan"],
)
def test_malformed_correction_curves_raise(u_shape, curve, message):
    mesh, skeleton, _, binding = u_shape
    with pytest.raises(CorrectionError, match=message) as info:
        attach_inside(binding, mesh, skeleton, curve, "br")
    assert isinstance(info.value, ToonmotionError)


@pytest.mark.parametrize("name", ["elbow", "bl"], ids=["unknown", "root-is-not-a-bone"])
def test_correction_to_an_unknown_bone_raises(u_shape, name):
    mesh, skeleton, _, binding = u_shape
    with pytest.raises(SkeletonError, match=f"no bone is called '{name}'") as info:
        attach_inside(binding, mesh, skeleton, CURVE, name)
    assert "the bones are: br, rt, lt" in str(info.value)


@pytest.mark.parametrize(
    "joints",
    [
        [("a", None, (10.0, 10.0)), ("b", "a", (10.0, 10.0))],
        [("a", None, (10.0, 10.0))],
    ],
    ids=["zero-length", "no-bones"],
)
def test_skeleton_without_a_usable_bone_raises(u_shape, joints):
    mesh, _, mask, _ = u_shape
    with pytest.raises(SkeletonError, match="no bone of non-zero length"):
        decompose(mesh, Skeleton.from_joints(joints), mask)


def test_zero_length_bones_are_skipped_not_fatal(u_shape):
    mesh, skeleton, mask, binding = u_shape
    joints = [*skeleton.joints(), ("stub", "lt", (6.0, 6.0))]
    with_stub = Skeleton.from_joints(joints)
    result = decompose(mesh, with_stub, mask, rule="straight")
    assert "stub" in with_stub.bone_names
    geodesic = decompose(mesh, with_stub, mask, rule="geodesic")
    assert not np.any(geodesic.bone == with_stub.bone_names.index("stub"))
    assert [with_stub.bone_names[b] for b in geodesic.bone] == \
        [skeleton.bone_names[b] for b in decompose(mesh, skeleton, mask, rule="geodesic").bone]
    assert not np.any(result.bone == with_stub.bone_names.index("stub"))
    names = [with_stub.bone_names[b] for b in result.bone]
    assert names == [skeleton.bone_names[b] for b in binding.bone]


def test_a_bone_wholly_outside_the_figure_is_refused_by_the_geodesic_rule(u_shape):
    mesh, _, mask, _ = u_shape
    skeleton = Skeleton.from_joints([("a", None, (6.0, 46.0)), ("in_left", "a", (6.0, 6.0)),
                                     ("b", None, (56.0, 50.0)), ("outside", "b", (56.0, 6.0))])
    with pytest.raises(SkeletonError, match="bone 'outside' lies wholly outside the drawing"):
        decompose(mesh, skeleton, mask, rule="geodesic")
    # Within two mesh spacings of the figure it is taken as drawn a little off its limb: the
    # arm's half nearer it is its own (the inner half is as near the other bone round the bar).
    near = Skeleton.from_joints([("a", None, (6.0, 46.0)), ("in_left", "a", (6.0, 6.0)),
                                 ("b", None, (52.0, 50.0)), ("outside", "b", (52.0, 6.0))])
    binding = decompose(mesh, near, mask, rule="geodesic")
    upper_right = (mesh.V[:, 0] > (GAP[1] + 48) / 2) & (mesh.V[:, 1] < BAR_TOP - 12)
    assert upper_right.sum() > 30
    assert np.all(binding.bone[upper_right] == near.bone_names.index("outside"))


def test_bone_outside_the_figure_falls_back_but_attaches_everything(u_shape):
    mesh, _, mask, _ = u_shape
    skeleton = Skeleton.from_joints(
        [
            ("a", None, (6.0, 46.0)),
            ("in_left", "a", (6.0, 6.0)),  # inside the left arm
            ("b", None, (56.0, 50.0)),
            ("outside", "b", (56.0, 6.0)),  # right of the right arm, off the figure
        ]
    )
    binding = decompose(mesh, skeleton, mask, rule="straight")
    assert binding.bone.shape == (len(mesh.V),)
    assert binding.bone.min() >= 0 and binding.bone.max() < len(skeleton.bones)
    assert binding.fallback.any()
    # Only the right arm is cut off from the left bone by the gap; the rest reaches it.
    V = mesh.V
    assert np.all(V[binding.fallback, 0] > GAP[0])
    left_arm = V[:, 0] < GAP[0]
    assert not binding.fallback[left_arm].any()
    assert np.all(binding.bone[left_arm] == skeleton.bone_names.index("in_left"))
    # The outer half of the right arm is nearest the outside bone, even with the penalty.
    far_right = (V[:, 0] > 44) & (V[:, 1] < BAR_TOP - 2)
    assert np.all(binding.bone[far_right] == skeleton.bone_names.index("outside"))
    _check_classification(mesh, binding)
