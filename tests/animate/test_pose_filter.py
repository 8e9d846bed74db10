"""Tests for toonmotion.animate.pose_filter: the cartoon filter on a single pose (thesis 5.2.1).

Every property runs on the bundled sample character and on each shared drawing, with the two
pushes of the thesis' figures: up before a jump with both feet on the ground (fig. 5.4) and
sideways before a run with one foot down (fig. 5.3).
"""

import numpy as np
import pytest

from tests.conftest import drawing_names
from toonmotion.animate.pose_filter import MIN_CHAIN_FRACTION, exaggerate_pose
from toonmotion.errors import FilterError
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.rig.pose import Pose, rest_pose, rotate_about
from toonmotion.rig.skeleton import Skeleton

# The push, as a fraction of the figure's height, and which feet stay down.
PUSH = 0.15
CASES = {
    "jump": ((0.0, -PUSH), ("right_foot", "left_foot")),  # up, both feet down (fig. 5.4)
    "run": ((PUSH, 0.0), ("right_foot",)),  # towards the image's right, one foot down (fig. 5.3)
}

# The filtered figure's total area may differ from the rest mesh's by at most this fraction.
AREA_TOLERANCE = 0.02

def _height(character):
    rows = np.flatnonzero(character.mask.any(axis=1))
    return float(rows[-1] - rows[0] + 1)


def _push(character, case):
    accel, fixed = CASES[case]
    return np.array(accel) * _height(character), list(fixed)


def _chain_joints(skeleton, fixed, root):
    """Joints on a chain from ``root`` (an index) to any fixed joint."""
    on = set()
    for name in fixed:
        j = skeleton.index(name)
        while j != root:
            on.add(j)
            j = skeleton.parents[j]
        on.add(root)
    return on


def _nearest_chain_ancestor(skeleton, j, on):
    while j >= 0 and j not in on:
        j = skeleton.parents[j]
    return j


def _knee_angle(skeleton, P, side):
    """Angle at the knee between thigh and shin, degrees; 180 is a straight leg."""
    hip, knee, foot = (P[skeleton.index(f"{side}_{part}")] for part in ("hip", "knee", "foot"))
    a, b = hip - knee, foot - knee
    return float(np.degrees(np.arccos(a @ b / np.linalg.norm(a) / np.linalg.norm(b))))


# --- what stays, what moves ------------------------------------------------------------------------


def _check_fixed_root_and_the_rest(character, case):
    skeleton = character.skeleton
    accel, fixed = _push(character, case)
    P = np.array(skeleton.positions)
    pose = Pose(P)
    out = exaggerate_pose(skeleton, pose, accel, fixed).positions
    np.testing.assert_array_equal(pose.positions, P)  # the input pose is untouched
    for name in fixed:
        j = skeleton.index(name)
        assert np.array_equal(out[j], P[j]), f"{name} moved from {P[j]} to {out[j]}"
    root = skeleton.index("root")
    np.testing.assert_allclose(out[root] - P[root], -accel, rtol=0, atol=1e-9)
    on = _chain_joints(skeleton, fixed, root)
    moved = out - P
    for j in set(range(len(skeleton))) - on:
        carrier = _nearest_chain_ancestor(skeleton, j, on)
        expected = moved[carrier] if carrier >= 0 else -accel
        np.testing.assert_allclose(moved[j], expected, rtol=0, atol=1e-9,
                                   err_msg=f"{skeleton.names[j]} did not move with its chain ancestor")
    # The chains do deform: something on them moved other than rigidly with the root.
    chain_moves = np.array([moved[j] for j in on - {root, *map(skeleton.index, fixed)}])
    assert np.abs(chain_moves + accel).max() > 1


@pytest.mark.parametrize("case", CASES)
def test_sample_fixed_joints_stay_and_the_rest_follows(rigs, case):
    _check_fixed_root_and_the_rest(rigs.deformer("sample").character, case)


@pytest.mark.parametrize("case", CASES)
def test_drawing_fixed_joints_stay_and_the_rest_follows(drawing_dir, rigs, case):
    _check_fixed_root_and_the_rest(rigs.deformer(drawing_dir.name).character, case)


# --- area ------------------------------------------------------------------------------------------


def _check_area(deformer, name, case):
    character = deformer.character
    mesh = character.mesh
    accel, fixed = _push(character, case)
    pose = exaggerate_pose(character.skeleton, rest_pose(character.skeleton), accel, fixed)
    U = deformer.deform(pose).U
    rest = triangle_areas(mesh.V, mesh.F).sum()
    change = triangle_areas(U, mesh.F).sum() / rest - 1
    print(f"\n{name} {case}: area {change:+.2%}")
    assert abs(change) <= AREA_TOLERANCE


@pytest.mark.parametrize("case", list(CASES))
def test_sample_keeps_its_area(rigs, case):
    _check_area(rigs.deformer("sample"), "sample", case)


@pytest.mark.parametrize(("name", "case"), [
    pytest.param(name, case, id=f"{name}-{case}") for name in drawing_names() for case in CASES
])
def test_drawing_keeps_its_area(rigs, name, case):
    """The jump once changed the sample's area by -8% and char2's by +3.4%: stage two now holds
    the figure's area (docs/posing.md)."""
    _check_area(rigs.deformer(name), name, case)


# --- squash bends the legs (fig. 5.4) --------------------------------------------------------------


def _check_knees_bend(character, bend):
    """Knees bent by ``bend`` degrees (outwards or inwards), then pushed up: they bend further."""
    skeleton = character.skeleton
    b = np.radians(bend)
    P = rotate_about(skeleton, rotate_about(skeleton, skeleton.positions, "right_knee", b), "left_knee", -b)
    accel, fixed = _push(character, "jump")
    out = exaggerate_pose(skeleton, Pose(P), accel, fixed).positions
    for side in ("right", "left"):
        before, after = _knee_angle(skeleton, P, side), _knee_angle(skeleton, out, side)
        assert after < before - 1, f"{side} knee went from {before:.1f} to {after:.1f} degrees"


@pytest.mark.parametrize("bend", [20, -20])
def test_sample_knees_bend_more_when_pushed_up(rigs, bend):
    _check_knees_bend(rigs.deformer("sample").character, bend)


@pytest.mark.parametrize("bend", [20, -20])
def test_drawing_knees_bend_more_when_pushed_up(drawing_dir, rigs, bend):
    _check_knees_bend(rigs.deformer(drawing_dir.name).character, bend)


# --- the chain transform on a small leg ----------------------------------------------------------


def _leg():
    return Skeleton.from_joints([
        ("pelvis", None, (0, 0)), ("hip", "pelvis", (0, 10)), ("knee", "hip", (3, 14)),
        ("foot", "knee", (0, 18)), ("toe", "foot", (4, 18)), ("arm", "pelvis", (5, -5)),
    ])


def test_the_chain_is_rotated_then_scaled_along_the_new_direction():
    leg = _leg()
    P = leg.positions
    accel = np.array([2.0, -3.0])
    out = exaggerate_pose(leg, Pose(P), accel, ["foot"]).positions
    OB, OB2 = P[3] - P[0], P[3] - P[0] + accel
    s = np.linalg.norm(OB2) / np.linalg.norm(OB)
    u = OB2 / np.linalg.norm(OB2)
    turn = np.arctan2(OB[0] * OB2[1] - OB[1] * OB2[0], OB @ OB2)
    R = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]])
    M = (np.eye(2) + (s - 1) * np.outer(u, u)) @ R
    np.testing.assert_allclose(M @ OB, OB2, rtol=0, atol=1e-12)
    expected = P[0] + (P[:3] - P[0]) @ M.T - accel
    np.testing.assert_allclose(out[:3], expected, rtol=0, atol=1e-12)
    assert np.array_equal(out[3], P[3]) and np.array_equal(out[4], P[4])  # the toe stays with the foot
    np.testing.assert_allclose(out[5], P[5] - accel, rtol=0, atol=1e-12)  # the arm goes with the root
    # Across OB' nothing is scaled: the chain's extent perpendicular to it is the rotated one.
    n = np.array([-u[1], u[0]])
    np.testing.assert_allclose((out[:4] - out[0]) @ n, (P[:4] - P[0]) @ R.T @ n, rtol=0, atol=1e-12)


def test_a_shared_joint_takes_the_mean_of_its_chains():
    body = Skeleton.from_joints([
        ("root", None, (0, 0)), ("spine", "root", (0, 10)),
        ("a", "spine", (-5, 20)), ("b", "spine", (5, 20)),
    ])
    accel = np.array([3.0, -4.0])
    P = body.positions
    both = exaggerate_pose(body, Pose(P), accel, ["a", "b"]).positions
    via_a = exaggerate_pose(body, Pose(P), accel, ["a"]).positions
    via_b = exaggerate_pose(body, Pose(P), accel, ["b"]).positions
    np.testing.assert_allclose(both[1], (via_a[1] + via_b[1]) / 2, rtol=0, atol=1e-12)
    assert np.array_equal(both[2:], P[2:])


def test_a_given_root_moves_its_ancestors_with_it(rigs):
    skeleton = rigs.deformer("sample").character.skeleton
    P = skeleton.positions
    accel = np.array([10.0, -30.0])
    out = exaggerate_pose(skeleton, Pose(P), accel, ["right_foot"], root="right_hip").positions
    for name in ("root", "hip", "torso", "head", "left_foot", "left_hand", "right_hip"):
        j = skeleton.index(name)
        np.testing.assert_allclose(out[j] - P[j], -accel, rtol=0, atol=1e-9, err_msg=name)
    assert np.array_equal(out[skeleton.index("right_foot")], P[skeleton.index("right_foot")])


def test_a_forest_uses_the_tree_of_the_fixed_joints():
    forest = Skeleton.from_joints([
        ("man", None, (0, 0)), ("foot", "man", (0, 20)), ("hat", None, (0, -10)), ("brim", "hat", (5, -10)),
    ])
    P = forest.positions
    out = exaggerate_pose(forest, Pose(P), (0, -5), ["foot"]).positions
    np.testing.assert_allclose(out[0], (0, 5), rtol=0, atol=1e-12)
    np.testing.assert_allclose(out[2:], P[2:] + (0, 5), rtol=0, atol=1e-12)  # the hat goes along
    with pytest.raises(FilterError, match=r"fixed joints 'foot' and 'brim' are in different trees "
                                          r"\(roots 'man' and 'hat'\); give root= or fix joints of one tree"):
        exaggerate_pose(forest, Pose(P), (0, -5), ["foot", "brim"])


# --- bad input ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("accel", "fixed", "options", "message"),
    [
        ((0, -50), ["root"], {}, r"^joint 'root' is not on a chain from the root 'root'; fix joints below"),
        ((0, -50), ["right_foot"], {"root": "left_hip"},
         r"^joint 'right_foot' is not on a chain from the root 'left_hip'"),
        ((0, -50), ["right_foot", "tail"], {},
         r"^fixed joints: unknown joint 'tail'; the skeleton's joints are: root, hip, torso, neck"),
        ((0, -50), ["right_foot"], {"root": "pelvis"}, r"^root: unknown joint 'pelvis'; the skeleton's"),
        ((0, -50), [], {}, r"^there are no fixed joints; fix at least one joint"),
        ((0, -50), "right_foot", {}, r"^fixed joints must be a sequence of joint names"),
        ((np.nan, -50), ["right_foot"], {}, r"^the acceleration must be two finite numbers \(dx, dy\)"),
        ((0, np.inf), ["right_foot"], {}, r"^the acceleration must be two finite numbers"),
        ((1, 2, 3), ["right_foot"], {}, r"^the acceleration must be two finite numbers"),
        ("up", ["right_foot"], {}, r"^the acceleration must be two finite numbers .*, got 'up'"),
        ((0, -50), ["hip"], {}, r"^fixed joint 'hip' is at the position of the root 'root', so its chain"),
    ],
)
def test_bad_input_is_refused(rigs, accel, fixed, options, message):
    skeleton = rigs.deformer("sample").character.skeleton
    with pytest.raises(FilterError, match=message):
        exaggerate_pose(skeleton, rest_pose(skeleton), accel, fixed, **options)


def test_an_acceleration_that_cancels_the_chain_is_refused(rigs):
    skeleton = rigs.deformer("sample").character.skeleton
    P = skeleton.positions
    root, hip, foot = (skeleton.index(n) for n in ("root", "right_hip", "right_foot"))
    # The sample's hip bone leaves the root sideways, so the leg pivots at the hip joint.
    OB = P[foot] - P[hip]
    with pytest.raises(FilterError, match=r"^the acceleration \(28, -151\) cancels the chain from "
                                          r"'right_hip' to 'right_foot' \(it would shrink to 0.0% of its "
                                          r"length\); shorten"):
        exaggerate_pose(skeleton, rest_pose(skeleton), -OB, ["right_foot"])
    # Just above the limit is allowed: the foot stays and the root moves by -accel.
    near = -(1 - 1.01 * MIN_CHAIN_FRACTION) * OB
    out = exaggerate_pose(skeleton, rest_pose(skeleton), near, ["right_foot"]).positions
    np.testing.assert_allclose(out[foot] - out[hip], OB + near, rtol=0, atol=1e-9)
    np.testing.assert_allclose(out[root], P[root] - near, rtol=0, atol=1e-12)


def test_a_leg_from_the_root_pivots_at_the_root():
    """With no sideways hip bone the chain is eq. 5.5's: it pivots at the root."""
    from toonmotion.rig.skeleton import Skeleton

    leg = Skeleton.from_joints(
        [("root", None, (0, 0)), ("knee", "root", (5, 50)), ("foot", "knee", (0, 100))]
    )
    out = exaggerate_pose(leg, rest_pose(leg), (0, -50), ["foot"]).positions
    # OB' = (0, 50): the leg halves along y, keeping the knee's sideways offset.
    np.testing.assert_allclose(out, [[0, 50], [5, 75], [0, 100]], atol=1e-12)


def test_a_pose_for_another_skeleton_is_refused(rigs):
    skeleton = rigs.deformer("sample").character.skeleton
    with pytest.raises(FilterError, match=r"has 16 joint positions but the skeleton has 17 joints"):
        exaggerate_pose(skeleton, Pose(skeleton.positions[:-1]), (0, -10), ["right_foot"])
    with pytest.raises(FilterError, match=r"pose must be a Pose, got ndarray"):
        exaggerate_pose(skeleton, skeleton.positions, (0, -10), ["right_foot"])
