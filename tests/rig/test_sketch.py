"""Posing by sketching (rig/sketch.py): strokes drawn through a known pose give that pose back,
on every shared drawing's skeleton and the sample's, whatever the strokes' order and direction."""

import numpy as np
import pytest

from tests.conftest import SAMPLE, drawing_names
from toonmotion.errors import SketchError
from toonmotion.io.char_cfg import load_char_cfg
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.rig.skeleton import Skeleton
from toonmotion.rig.sketch import match_sketch, stroke_chains
from toonmotion.rig.sketch_graph import sketch_graph
from toonmotion.samples import sample_character
from toonmotion.testing.sketching import figure_size, strokes_through, turned


@pytest.fixture(params=[*drawing_names(), SAMPLE])
def skeleton(request, drawings_root_or_none):
    if request.param == SAMPLE:
        return sample_character()[1]
    return load_char_cfg(drawings_root_or_none / request.param / "char_cfg.yaml")[0]


@pytest.fixture
def drawings_root_or_none(request):
    if request.node.callspec.params.get("skeleton") == SAMPLE:
        return None
    return request.getfixturevalue("drawings_root")


def chains(skeleton):
    return stroke_chains(skeleton)


def bent(skeleton, rng, *, turns=2, most=0.6):
    return turned(skeleton, rng, turns=turns, most=most)


def size(positions):
    return figure_size(positions)


def test_a_stick_figure_drawn_over_the_drawing_gives_its_pose(skeleton):
    rng = np.random.default_rng(7)
    worst = []
    for _ in range(10):
        target = bent(skeleton, rng)
        strokes = strokes_through(target, chains(skeleton), rng)
        found = match_sketch(skeleton, Pose(skeleton.positions), strokes)
        worst.append(np.linalg.norm(found.pose.positions - target, axis=1).max() / size(target))
        assert not found.elsewhere
        assert len(found.bones) == sum(skeleton.bone_lengths > 1.0)
    # Every joint lands where it was drawn; a slight bend that is no corner (the stroke is
    # jittered by 0.8 px) puts its joint by the rest lengths along the stroke, a few px off.
    assert max(worst) <= 0.04
    assert np.median(worst) <= 0.015


def test_one_limb_sketched_moves_that_limb_only(skeleton):
    rng = np.random.default_rng(3)
    ends = set(range(len(skeleton))) - set(skeleton.parents.tolist())
    limbs = [c if c[-1] in ends else c[::-1]
             for c in chains(skeleton) if len(c) >= 3 and ends & {c[0], c[-1]}]
    assert limbs
    for limb in limbs:  # turned at its first joint: the stroke starts on the body
        target = skeleton.positions.copy()
        target[limb] = rotate_about(skeleton, skeleton.positions, skeleton.names[limb[0]], 0.8)[limb]
        found = match_sketch(skeleton, Pose(skeleton.positions), strokes_through(target, [limb], rng))
        moved = np.linalg.norm(found.pose.positions - skeleton.positions, axis=1) > 0
        below = np.linalg.norm(target - skeleton.positions, axis=1) > 1e-9
        error = np.linalg.norm(found.pose.positions[below] - target[below], axis=1)
        assert error.max() <= 0.03 * size(target)
        assert not (moved & ~below).any(), "a joint outside the sketched limb moved"


def test_a_bone_sketched_alone_carries_the_joints_below_it():
    s = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (100, 0)),
                              ("hand", "elbow", (180, 0))])
    found = match_sketch(s, Pose(s.positions), [[(0, 0), (0, 100)]])  # the upper arm turned down
    assert found.bones == ("elbow",)
    np.testing.assert_allclose(found.pose.positions, [[0, 0], [0, 100], [0, 180]], atol=1e-9)


def test_a_straight_stroke_covers_the_unbranched_joints_it_passes():
    s = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (100, 0)),
                              ("hand", "elbow", (180, 20))])
    found = match_sketch(s, Pose(s.positions), [np.linspace((0, 0), (0, 180), 40)])
    assert found.bones == ("elbow", "hand")
    np.testing.assert_allclose(found.pose.positions[1], [0, 180 * 100 / (100 + np.hypot(80, 20))], atol=1e-6)


def test_a_stick_figure_drawn_beside_the_drawing_is_scaled_and_hung_from_its_root(skeleton):
    rng = np.random.default_rng(5)
    target = bent(skeleton, rng)
    root = target[0]
    beside = (target - root) * 0.5 + root + [1.2 * size(target), 0]
    strokes = strokes_through(beside, chains(skeleton), rng, noise=0)
    found = match_sketch(skeleton, Pose(skeleton.positions), strokes)
    assert found.elsewhere
    np.testing.assert_allclose(found.pose.positions[0], skeleton.positions[0], atol=1e-9)
    angles, lengths = bone_angles(skeleton, found.pose.positions)
    expected, rest = bone_angles(skeleton, target)
    turn = np.degrees(np.abs(np.angle(np.exp(1j * (angles - expected)))))
    assert turn[rest > 1].max() <= 3.0


def test_strokes_that_meet_make_one_figure():
    points, edges = sketch_graph([np.array([(0.0, 0), (0, 100)]), np.array([(3.0, 50), (60, 50)]),
                                  np.array([(60.0, 52), (60, 120)])], snap=6)
    assert len(points) == 5 and len(edges) == 4


@pytest.mark.parametrize("strokes, message", [
    ([], "list of strokes"),
    ([[(0, 0)]], "at least 2"),
    ([[(0, 0), (np.nan, 1)]], "finite"),
    ([[(0, 0), (1e308, 1)]], "beyond 10,000,000 px"),  # once hung shapely's simplify
    ([[(5, 5), (5, 5)]], "empty"),
    ([[(30 * i, 0), (30 * i, 20)] for i in range(40)], "more than the skeleton"),
    ([[(x, 200 * (x // 50 % 2)) for x in range(0, 650, 50)]], "shape"),
])
def test_sketches_that_cannot_be_read_are_refused_in_one_line(strokes, message):
    skeleton = sample_character()[1]
    with pytest.raises(SketchError, match=message) as caught:
        match_sketch(skeleton, Pose(skeleton.positions), strokes)
    assert "\n" not in str(caught.value)
