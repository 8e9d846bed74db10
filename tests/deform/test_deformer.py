"""Tests for toonmotion.deform: the needle model, stage two, joint areas and depth layers.

Every property runs on the bundled sample character and on each shared drawing (rigged with
its mask and char_cfg skeleton). Cases that fail today are left out of the plain tests and
checked together, one ``xfail(strict=True)`` test per design gap (at the end), with what was
measured, so they neither hide nor break the build, and flag when any of them starts passing.
"""

from functools import partial

import numpy as np
import pytest

from tests.conftest import expect_every_case_to_fail
from toonmotion.deform.deformer import Deformation, Deformer, DeformSettings
from toonmotion.deform.depth import (
    default_depth,
    draw_order,
    find_overlaps,
    set_region_depth,
    triangle_layers,
)
from toonmotion.deform.joint_area import joint_area
from toonmotion.errors import PoseError, SettingsError
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.rig.pose import Pose, descendants, rest_pose, rotate_about
from toonmotion.testing.poses import extreme_poses

CHARACTERS = ("sample", "char1", "char2", "char3", "char4")

# Stretching one bone 1.5x may change the figure's total area by at most this fraction.
AREA_TOLERANCE = 0.02
STRETCH = 1.5
# Bones are named after their child joint: the forearm ends at the hand, the shin at the foot.
STRETCHED_BONES = {"forearm": "right_hand", "shin": "right_foot", "torso": "torso"}


@pytest.fixture
def rigged(name, rigs):
    """``get(**settings) -> Deformer`` for the parametrized character ``name``."""
    return lambda **settings: rigs.deformer(name, **settings)


def _cases(names, items, failing):
    """``(name, item)`` parameters but the known failures (each is a case of its gap's test)."""
    return [pytest.param(name, item, id=f"{name}-{item}")
            for name in names for item in items if (name, item) not in failing]


def _gap_cases(rigs, gap, checks):
    """``{case: check}`` for every known failure of ``gap``.

    ``checks`` holds ``(label, failing, check)``: ``failing`` maps ``(name, item)`` to ``(gap,
    what was measured)`` and ``check(rigged, name, item)`` is the body of the plain test.
    """
    return {
        f"{label} {name}-{item}": lambda check=check, name=name, item=item: check(
            lambda **settings: rigs.deformer(name, **settings), name, item)
        for label, failing, check in checks
        for (name, item), (case_gap, _) in failing.items() if case_gap == gap
    }


# The design gap behind the known failures, one test at the end of this module.
SMALL_LIMBS = "a limb of under ~3.5% of the figure cannot add the 2% bar when stretched 1.5x"


# --- poses -------------------------------------------------------------------------------


def _similarity(P, angle, centre, shift):
    c, s = np.cos(angle), np.sin(angle)
    return (np.asarray(P) - centre) @ np.array([[c, s], [-s, c]]) + centre + shift


def _stretch(skeleton, positions, bone, factor):
    """Lengthen ``bone`` (named after its child joint) by ``factor``, carrying everything below."""
    child = skeleton.index(bone)
    parent = skeleton.parents[child]
    out = np.array(positions, dtype=float)
    moved = np.concatenate([[child], descendants(skeleton, child)])
    out[moved] += (factor - 1) * (out[child] - out[parent])
    return out


def _raise_arm(skeleton, positions, side, degrees=60.0):
    """Turn the arm about its shoulder so the upper arm points ``degrees`` above horizontal, outwards."""
    shoulder, elbow = skeleton.index(f"{side}_shoulder"), skeleton.index(f"{side}_elbow")
    outwards = np.sign(positions[shoulder, 0] - positions[skeleton.index("neck"), 0])
    d = positions[elbow] - positions[shoulder]
    target = np.arctan2(-np.sin(np.radians(degrees)), outwards * np.cos(np.radians(degrees)))
    return rotate_about(skeleton, positions, f"{side}_shoulder", target - np.arctan2(d[1], d[0]))


def _test_pose(skeleton, kind):
    P = skeleton.positions
    elbow, knee = np.radians(60), np.radians(45)
    if kind == "elbows+":
        return rotate_about(skeleton, rotate_about(skeleton, P, "right_elbow", elbow), "left_elbow", -elbow)
    if kind == "elbows-":
        return rotate_about(skeleton, rotate_about(skeleton, P, "right_elbow", -elbow), "left_elbow", elbow)
    if kind == "knees+":
        return rotate_about(skeleton, rotate_about(skeleton, P, "right_knee", knee), "left_knee", -knee)
    if kind == "knees-":
        return rotate_about(skeleton, rotate_about(skeleton, P, "right_knee", -knee), "left_knee", knee)
    assert kind == "arms up"
    return _raise_arm(skeleton, _raise_arm(skeleton, P, "right"), "left")


def _area(U, F):
    return float(triangle_areas(U, F).sum())


# --- the rest pose and rigid motions -----------------------------------------------------------


@pytest.mark.parametrize("stage_two", [False, True], ids=["stage-one", "stage-two"])
@pytest.mark.parametrize("edge_term", ["rigid", "length"])
@pytest.mark.parametrize("name", CHARACTERS)
def test_rest_pose_reproduces_the_rest_mesh(rigged, stage_two, edge_term):
    deformer = rigged(stage_two=stage_two, edge_term=edge_term)
    V = deformer.character.mesh.V
    pose = rest_pose(deformer.character.skeleton)
    np.testing.assert_allclose(deformer.stage_one(pose), V, rtol=0, atol=1e-9)
    result = deformer.deform(pose)
    np.testing.assert_allclose(result.U, V, rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.stage_one, V, rtol=0, atol=1e-9)
    assert result.energy < 1e-12 and result.converged


@pytest.mark.parametrize("stage_two", [False, True], ids=["stage-one", "stage-two"])
@pytest.mark.parametrize("angle", [0.7, 2.5, -1.3])
@pytest.mark.parametrize("name", CHARACTERS)
def test_moving_the_whole_skeleton_rigidly_moves_the_mesh_rigidly(rigged, angle, stage_two):
    deformer = rigged(stage_two=stage_two)
    character = deformer.character
    centre, shift = np.array([37.0, -120.0]), np.array([55.5, -20.25])
    pose = Pose(_similarity(character.skeleton.positions, angle, centre, shift))
    result = deformer.deform(pose)
    expected = _similarity(character.mesh.V, angle, centre, shift)
    error = np.abs(result.U - expected).max()
    assert error < 1e-6, f"the mesh is {error:.3g} px from the rigidly moved rest mesh"
    np.testing.assert_allclose(triangle_areas(result.U, character.mesh.F),
                               triangle_areas(character.mesh.V, character.mesh.F), rtol=1e-9, atol=1e-9)


# --- area preservation --------------------------------------------------------------------


@pytest.mark.parametrize("preserve_area", [True, False])
@pytest.mark.parametrize("bone", sorted(set(STRETCHED_BONES.values()) | {"right_elbow", "left_knee"}))
@pytest.mark.parametrize("name", CHARACTERS)
def test_stage_one_scales_a_stretched_bones_region_exactly(rigged, bone, preserve_area):
    """The needle map is affine per bone: a region stretched 1.5x keeps its area (fig. 3.8), or
    grows by exactly 1.5x without area preservation; other bones' regions do not change."""
    deformer = rigged(preserve_area=preserve_area, stage_two=False)
    character = deformer.character
    skeleton, mesh = character.skeleton, character.mesh
    b = skeleton.bone_names.index(bone)
    P = _stretch(skeleton, skeleton.positions, bone, STRETCH)
    U = deformer.stage_one(Pose(P))
    rest = triangle_areas(mesh.V, mesh.F)
    posed = triangle_areas(U, mesh.F)
    region = ~character.binding.joint_triangle & (character.binding.bone[mesh.F[:, 0]] == b)
    assert region.sum() >= 5
    factor = 1.0 if preserve_area else STRETCH
    np.testing.assert_allclose(posed[region], factor * rest[region], rtol=1e-9, atol=1e-9)
    others = ~character.binding.joint_triangle & ~region
    np.testing.assert_allclose(posed[others], rest[others], rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize(("name", "part"), _cases(CHARACTERS, STRETCHED_BONES, {}))
def test_stretching_one_bone_keeps_the_figures_area(rigged, name, part, record_property):
    """The torso included: its joint bands once grew figures by 7-14% (stage two's area constraint)."""
    _check_area_kept(rigged, name, part, record_property)


def _check_area_kept(rigged, name, part, record_property):
    deformer = rigged()
    skeleton, mesh = deformer.character.skeleton, deformer.character.mesh
    P = _stretch(skeleton, skeleton.positions, STRETCHED_BONES[part], STRETCH)
    change = _area(deformer.deform(Pose(P)).U, mesh.F) / _area(mesh.V, mesh.F) - 1
    record_property("area_change", change)
    print(f"\n{name} {part} stretched {STRETCH}x, area preserved: {change:+.2%}")
    assert abs(change) <= AREA_TOLERANCE


AREA_GROWS_FAILS = {
    ("char2", "forearm"): (SMALL_LIMBS, "measured +1.68% (on: +0.14%): the forearm is ~3.4% of char2's "
                                        "area, so 1.5x adds ~1.7%"),
    ("char2", "shin"): (SMALL_LIMBS, "measured +1.58% (on: +0.16%): char2's shin is ~3% of its area"),
    ("char4", "shin"): (SMALL_LIMBS, "measured +1.69% (on: +0.13%): char4's shin is ~3.4% of its area"),
}


@pytest.mark.parametrize(("name", "part"), _cases(CHARACTERS, STRETCHED_BONES, AREA_GROWS_FAILS))
def test_without_area_preservation_a_stretch_grows_the_figure(rigged, name, part, record_property):
    _check_area_grows(rigged, name, part, record_property)


def _check_area_grows(rigged, name, part, record_property):
    skeleton, mesh = rigged().character.skeleton, rigged().character.mesh
    P = Pose(_stretch(skeleton, skeleton.positions, STRETCHED_BONES[part], STRETCH))
    rest = _area(mesh.V, mesh.F)
    kept = _area(rigged().deform(P).U, mesh.F) / rest - 1
    grown = _area(rigged(preserve_area=False).deform(P).U, mesh.F) / rest - 1
    record_property("area_change", grown)
    print(f"\n{name} {part} stretched {STRETCH}x: area {kept:+.2%} preserved, {grown:+.2%} not")
    assert grown > kept
    assert grown > AREA_TOLERANCE


# --- stage two ---------------------------------------------------------------------------------

POSES = ("elbows+", "elbows-", "knees+", "knees-", "arms up")

@pytest.mark.parametrize(("name", "kind"), _cases(CHARACTERS, POSES, {}))
def test_stage_two_lowers_its_energy_and_leaves_no_joint_triangle_inverted(rigged, name, kind):
    _check_stage_two(rigged, name, kind)


def _check_stage_two(rigged, name, kind):
    deformer = rigged()
    character = deformer.character
    F, joint = character.mesh.F, character.binding.joint_triangle
    result = deformer.deform(Pose(_test_pose(character.skeleton, kind)))
    start = deformer.solver.energy(result.stage_one)
    assert result.energy_start == pytest.approx(start, rel=1e-12)
    assert result.energy < start
    assert result.iterations <= deformer.settings.max_iterations
    before = int((triangle_areas(result.stage_one, F)[joint] <= 0).sum())
    after = int((triangle_areas(result.U, F)[joint] <= 0).sum())
    print(f"\n{name} {kind}: inverted joint triangles {before} -> {after}; "
          f"energy {start:.4g} -> {result.energy:.4g} in {result.iterations} iterations")
    assert after == 0


@pytest.mark.parametrize(("name", "kind"), _cases(CHARACTERS, POSES, {}))
def test_stage_two_stops_near_its_minimum(rigged, name, kind):
    """The default stopping rule (an iteration gains less than 0.01%) ends within 1% of the energy
    that iterating to convergence reaches, in one solve (no unfolding, which may widen the joint
    area differently after a shorter or longer solve)."""
    skeleton = rigged().character.skeleton
    pose = Pose(_test_pose(skeleton, kind))
    default = rigged(unfold=0).deform(pose)
    converged = rigged(unfold=0, tolerance=1e-10, max_iterations=3000).deform(pose)
    assert converged.converged and converged.energy <= default.energy
    print(f"\n{name} {kind}: energy {default.energy:.5g} in {default.iterations} iterations, "
          f"{converged.energy:.5g} in {converged.iterations}")
    assert default.energy <= 1.01 * converged.energy


@pytest.mark.parametrize("name", CHARACTERS)
def test_the_drawing_keeps_its_joints_where_the_skeleton_puts_them(rigged):
    """In every test pose the point of the drawing at each joint (where it lay at rest) stays
    within half a mesh spacing of the pose's joint. The thesis' stage two (``joint_anchor=0``)
    lets a joint area settle as a block, further off than that on every character."""
    def worst_gap(deformer):
        gaps = []
        for kind in POSES:
            pose = Pose(_test_pose(deformer.character.skeleton, kind))
            drawn = deformer.drawn_joints(deformer.deform(pose).U)
            inside = np.isfinite(drawn[:, 0])
            gaps.append(np.hypot(*(drawn[inside] - pose.positions[inside]).T).max())
        return max(gaps)

    deformer = rigged()
    # Every joint of these drawings lies inside its figure, so every one is held.
    assert np.isfinite(deformer.drawn_joints(deformer.character.mesh.V)).all()
    anchored, thesis = worst_gap(deformer), worst_gap(rigged(joint_anchor=0.0))
    half = deformer.character.mesh.spacing / 2
    print(f"\nworst joint gap: {anchored:.2f} px anchored, {thesis:.2f} px without "
          f"(half a spacing {half:.2f})")
    assert anchored <= half < thesis


@pytest.mark.parametrize("name", ["char1"])
def test_the_anchors_are_kept_where_the_drawing_folds_without_them_too(rigged, monkeypatch):
    """An anchor gives way only for a fold it makes. With the thesis' edge term a shoulder bent
    150 degrees folds triangles with the anchors and without them (one solve holding none tells):
    every anchor is kept, and the drawn joints stay nearer the skeleton's than without them."""
    deformer = rigged(edge_term="length")
    skeleton, F = deformer.character.skeleton, deformer.character.mesh.F
    pose = dict(extreme_poses(skeleton))["right_shoulder -150"]
    loose = rigged(edge_term="length", joint_anchor=0.0).deform(pose)
    assert (triangle_areas(loose.U, F) <= 0).any()  # it folds without the anchors
    gave_way = []
    monkeypatch.setattr(deformer, "_nearest_anchor", lambda *args: gave_way.append(args) or 0)
    held = deformer.deform(pose)
    assert (triangle_areas(held.U, F) <= 0).any() and gave_way == []
    gaps = [np.hypot(*(deformer.drawn_joints(result.U) - pose.positions).T) for result in (held, loose)]
    print(f"\nworst joint gap: {gaps[0].max():.2f} px held, {gaps[1].max():.2f} px without anchors")
    assert gaps[0].mean() < gaps[1].mean() and gaps[0].max() < gaps[1].max()


@pytest.mark.parametrize("name", ["sample", "char2"])
def test_an_anchor_gives_way_in_steps_and_keeps_its_joint_nearer(rigged):
    """Where holding a joint folds the drawing, its anchor gives way a step at a time: over the
    extreme poses nothing is left inverted, and the drawn joints stay nearer the skeleton's than
    when an anchor is let go at once (the sample's neck bent 150 degrees: 18 px against 40)."""
    def worst(deformer):
        gaps, inverted = [], 0
        for _, pose in extreme_poses(deformer.character.skeleton):
            U = deformer.deform(pose).U
            inverted += int((triangle_areas(U, deformer.character.mesh.F) <= 0).sum())
            gaps.append(np.nanmax(np.hypot(*(deformer.drawn_joints(U) - pose.positions).T)))
        return max(gaps), inverted

    stepped, inverted = worst(rigged())
    at_once, _ = worst(rigged(anchor_give=0.0))  # DeformSettings.anchor_give: let go at once
    print(f"\nworst joint gap over the extreme poses: {stepped:.1f} px in steps, {at_once:.1f} px at once")
    assert inverted == 0
    assert stepped < at_once


@pytest.mark.parametrize("name", CHARACTERS)
def test_stage_two_moves_only_the_joint_area(rigged):
    deformer = rigged()
    skeleton = deformer.character.skeleton
    result = deformer.deform(Pose(_test_pose(skeleton, "elbows+")))
    # The joint area, widened only where unfolding needed it.
    assert np.all(result.free[deformer.free])
    fixed = ~result.free
    assert fixed.any() and deformer.free.any()
    np.testing.assert_array_equal(result.U[fixed], result.stage_one[fixed])
    assert np.abs(result.U[deformer.free] - result.stage_one[deformer.free]).max() > 1e-3
    # With stage two off the result is stage one itself.
    alone = rigged(stage_two=False).deform(Pose(_test_pose(skeleton, "elbows+")))
    np.testing.assert_array_equal(alone.U, result.stage_one)
    assert alone.iterations == 0


@pytest.mark.parametrize("joint", ["right_elbow", "right_knee", "left_shoulder"])
@pytest.mark.parametrize("name", CHARACTERS)
def test_warm_start_matches_the_cold_solve_in_no_more_iterations(rigged, joint):
    deformer = rigged()
    skeleton = deformer.character.skeleton
    before = Pose(rotate_about(skeleton, skeleton.positions, joint, 0.5))
    after = Pose(rotate_about(skeleton, skeleton.positions, joint, 0.53))
    previous = deformer.deform(before)
    cold = deformer.deform(after)
    warm = deformer.deform(after, previous=previous)
    np.testing.assert_array_equal(warm.stage_one, cold.stage_one)
    assert warm.energy <= 1.01 * cold.energy
    assert warm.iterations <= cold.iterations
    assert warm.energy_start <= cold.energy_start


@pytest.mark.parametrize("name", ["sample", "char3"])
def test_a_warm_start_worse_than_stage_one_is_ignored(rigged):
    deformer = rigged()
    skeleton = deformer.character.skeleton
    pose = Pose(_test_pose(skeleton, "knees+"))
    cold = deformer.deform(pose)
    U1 = cold.stage_one
    noise = np.random.default_rng(0).normal(0, 20, size=U1.shape)
    bad = Deformation(U=U1 + noise, stage_one=U1, iterations=0, energy_start=0.0, energy=0.0, converged=True)
    warm = deformer.deform(pose, previous=bad)
    np.testing.assert_array_equal(warm.U, cold.U)
    assert warm.energy_start == cold.energy_start and warm.iterations == cold.iterations


# --- settings and pose errors ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"weights": (-1.0, 1.0, 1.0)}, r"weights must be three finite numbers >= 0, not all zero"),
        ({"weights": (0.0, 0.0, 0.0)}, r"not all zero; got \[0.0, 0.0, 0.0\]"),
        ({"weights": (1.0, 1.0)}, r"weights must be three finite numbers"),
        ({"weights": (1.0, 1.0, 1.0, 1.0)}, r"weights must be three finite numbers"),
        ({"weights": (1.0, np.nan, 1.0)}, r"weights must be three finite numbers"),
        ({"joint_width": -0.5}, r"joint area width must be a finite number >= 0, got -0.5"),
        ({"joint_width": np.inf}, r"joint area width must be a finite number >= 0"),
        ({"tolerance": 0.0}, r"tolerance must be a number > 0, got 0.0"),
        ({"tolerance": -1e-3}, r"tolerance must be a number > 0"),
        ({"tolerance": np.nan}, r"tolerance must be a number > 0"),
        ({"max_iterations": 0}, r"max_iterations must be a whole number >= 1, got 0"),
        ({"max_iterations": 2.5}, r"max_iterations must be a whole number >= 1"),
        ({"edge_term": "springy"}, r"edge term must be one of rigid, length, got 'springy'"),
        ({"unfold": -1}, r"unfold must be a whole number >= 0, got -1"),
        ({"unfold": 1.5}, r"unfold must be a whole number >= 0"),
        ({"joint_anchor": -1.0}, r"joint anchor weight must be a finite number >= 0, got -1.0"),
        ({"joint_anchor": np.inf}, r"joint anchor weight must be a finite number >= 0"),
        ({"joint_anchor": True}, r"joint anchor weight must be a finite number >= 0, got True"),
    ],
)
def test_bad_settings_are_refused(settings, message, rigs):
    character = rigs.character("sample")
    with pytest.raises(SettingsError, match=message):
        Deformer(character, DeformSettings(**settings))


@pytest.mark.parametrize("name", ["sample"])
def test_a_pose_for_another_skeleton_is_refused(rigged):
    deformer = rigged()
    P = deformer.character.skeleton.positions
    for wrong in (P[:-1], np.vstack([P, P[:1]])):
        with pytest.raises(PoseError, match=r"has \d+ joint positions but the skeleton has 17 joints"):
            deformer.deform(Pose(np.array(wrong)))
        with pytest.raises(PoseError, match="joint positions"):
            deformer.stage_one(Pose(np.array(wrong)))


# --- joint areas ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", CHARACTERS)
def test_joint_area_grows_with_its_width_from_the_thesis_band(rigged):
    character = rigged().character
    mesh, skeleton, binding = character.mesh, character.skeleton, character.binding
    band = joint_area(mesh, skeleton, binding, character.mask, width=0)
    np.testing.assert_array_equal(band, binding.joint_area)
    assert band is not binding.joint_area
    # The thesis' band is the vertices of the joint triangles.
    np.testing.assert_array_equal(np.flatnonzero(band), np.unique(mesh.F[binding.joint_triangle]))
    previous = band
    for width in (0.5, 1.0, 1.5, 3.0):
        wider = joint_area(mesh, skeleton, binding, character.mask, width=width)
        assert np.all(wider[previous]), f"width {width} drops vertices of a narrower area"
        assert wider.sum() >= previous.sum()
        previous = wider
    assert previous.sum() > band.sum()
    np.testing.assert_array_equal(rigged().free, joint_area(mesh, skeleton, binding, character.mask))


# --- depth layers ----------------------------------------------------------------------------------


def _swing_right_arm_across(skeleton):
    """The right arm turned about its shoulder to point across the body, a little down."""
    P = skeleton.positions
    d = P[skeleton.index("right_elbow")] - P[skeleton.index("right_shoulder")]
    return rotate_about(skeleton, P, "right_shoulder", np.arctan2(0.6, 1.0) - np.arctan2(d[1], d[0]))


@pytest.mark.parametrize("name", ["sample"])
def test_set_region_depth_sets_the_clicked_vertexs_whole_region(rigged):
    binding = rigged().character.binding
    skeleton = rigged().character.skeleton
    depth = default_depth(skeleton)
    assert depth.shape == (len(skeleton.bones),) and not depth.any()
    b = skeleton.bone_names.index("right_hand")
    vertex = int(np.flatnonzero(binding.bone == b)[7])
    new = set_region_depth(depth, binding, vertex, 2)
    assert not depth.any()  # a new array; the old one is kept
    assert new[b] == 2 and np.count_nonzero(new) == 1
    per_vertex = new[binding.bone]
    np.testing.assert_array_equal(per_vertex == 2, binding.bone == b)
    assert set_region_depth(new, binding, vertex, -1)[b] == -1
    for bad in (-1, len(binding.bone)):
        with pytest.raises(SettingsError, match=rf"there is no vertex {bad}; the mesh has \d+ vertices"):
            set_region_depth(depth, binding, bad, 1)


@pytest.mark.parametrize("name", ["sample"])
def test_draw_order_sorts_triangles_by_layer_stably(rigged):
    character = rigged().character
    mesh, binding, skeleton = character.mesh, character.binding, character.skeleton
    depth = default_depth(skeleton)
    np.testing.assert_array_equal(draw_order(mesh, binding, depth), np.arange(len(mesh.F)))
    for bone, value in (("right_hand", 2), ("right_elbow", 1), ("torso", -1)):
        vertex = int(np.flatnonzero(binding.bone == skeleton.bone_names.index(bone))[0])
        depth = set_region_depth(depth, binding, vertex, value)
    layers = triangle_layers(mesh, binding, depth)
    np.testing.assert_array_equal(layers, depth[binding.bone[mesh.F]].max(axis=1))
    order = draw_order(mesh, binding, depth)
    assert sorted(order.tolist()) == list(range(len(mesh.F)))
    assert order.tolist() == sorted(range(len(mesh.F)), key=lambda t: layers[t])  # Python's sort is stable
    # Joint triangles between the forearm and the upper arm draw with the forearm, in front.
    forearm = (binding.bone[mesh.F] == skeleton.bone_names.index("right_hand")).any(axis=1)
    assert set(layers[forearm].tolist()) == {2}
    assert set(np.unique(layers).tolist()) == {-1, 0, 1, 2}


@pytest.mark.parametrize("name", ["sample"])
def test_find_overlaps_reports_an_arm_across_the_body_and_its_depth(rigged):
    deformer = rigged()
    character = deformer.character
    mesh, binding, skeleton = character.mesh, character.binding, character.skeleton
    depth = default_depth(skeleton)
    assert find_overlaps(mesh, binding, skeleton, mesh.V, depth) == []
    assert find_overlaps(mesh, binding, skeleton, deformer.deform(rest_pose(skeleton)).U, depth) == []

    U = deformer.deform(Pose(_swing_right_arm_across(skeleton))).U
    overlaps = find_overlaps(mesh, binding, skeleton, U, depth)
    arm = {"right_elbow", "right_hand"}
    pairs = {frozenset((o.bone_a, o.bone_b)) for o in overlaps}
    assert frozenset(("torso", "right_hand")) in pairs
    assert all(pair & arm for pair in pairs), f"only the arm moved, yet {pairs} overlap"
    assert frozenset(arm) not in pairs  # bones that share a joint are never compared
    assert all(o.same_depth for o in overlaps)
    assert all(o.area > 0.25 * mesh.spacing**2 for o in overlaps)
    areas = [o.area for o in overlaps]
    assert areas == sorted(areas, reverse=True)
    # A forearm lying on the chest, not a seam: a good part of the forearm's own area.
    region = (binding.bone[mesh.F] == skeleton.bone_names.index("right_hand")).sum(axis=1) >= 2
    forearm = triangle_areas(mesh.V, mesh.F)[region].sum()
    top = overlaps[0]
    assert {top.bone_a, top.bone_b} == {"torso", "right_hand"} and top.area > 0.25 * forearm

    for bone in arm:  # click a vertex of each arm bone and bring it forward
        vertex = int(np.flatnonzero(binding.bone == skeleton.bone_names.index(bone))[0])
        depth = set_region_depth(depth, binding, vertex, 1)
    ordered = find_overlaps(mesh, binding, skeleton, U, depth)
    assert [(o.bone_a, o.bone_b, o.area) for o in ordered] == [(o.bone_a, o.bone_b, o.area) for o in overlaps]
    assert not any(o.same_depth for o in ordered)


# --- known design gaps: one strict xfail each, over every case it breaks ------------------------

GAPS = {"small-limbs": SMALL_LIMBS}


@pytest.mark.parametrize("gap", [
    pytest.param(gap, id=key, marks=pytest.mark.xfail(strict=True, raises=AssertionError, reason=gap))
    for key, gap in GAPS.items()
])
def test_known_design_gap(rigs, record_property, gap):
    """Every known failure of ``gap``, each as strict as its plain test above."""
    checks = [("area grows", AREA_GROWS_FAILS, partial(_check_area_grows, record_property=record_property))]
    expect_every_case_to_fail(_gap_cases(rigs, gap, checks))
