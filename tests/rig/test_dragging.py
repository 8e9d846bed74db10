"""Tests for toonmotion.rig.dragging: a dragged joint turns its bone (FK), reaches with a chain
(IK) or stretches, as animation tools do; on the shared drawings' skeletons (char_cfg) and the
bundled sample's, every joint dragged to points all round it."""

import numpy as np
import pytest

from toonmotion.errors import PoseError
from toonmotion.io.char_cfg import load_char_cfg
from toonmotion.rig.dragging import drag_joint
from toonmotion.rig.pose import descendants
from toonmotion.rig.skeleton import Skeleton
from toonmotion.samples import sample_character


@pytest.fixture(params=["sample", "drawing"])
def skeleton(request, drawing_dir):
    if request.param == "sample":
        return sample_character(scale=0.5)[1]
    return load_char_cfg(drawing_dir / "char_cfg.yaml")[0]


def _targets(skeleton, joint):
    """Points all round ``joint``, near and far (a quarter to twice the figure's size)."""
    size = np.ptp(skeleton.positions, axis=0).max()
    angles = np.linspace(0, 2 * np.pi, 7, endpoint=False)
    for radius in (0.25 * size, 2.0 * size):
        for a in angles:
            yield skeleton.positions[joint] + radius * np.array([np.cos(a), np.sin(a)])


def _lengths(skeleton, P):
    bones = skeleton.bones
    return np.hypot(*(P[bones[:, 1]] - P[bones[:, 0]]).T)


def _pairwise(P):
    return np.hypot(*(P[:, None] - P[None]).transpose(2, 0, 1))


def test_a_turn_keeps_every_bone_and_carries_the_joints_below_rigidly(skeleton):
    rest = skeleton.positions
    for j in range(len(skeleton)):
        below = np.append(descendants(skeleton, j), j)
        for target in _targets(skeleton, j):
            P = drag_joint(skeleton, rest, j, target)
            np.testing.assert_allclose(_lengths(skeleton, P), _lengths(skeleton, rest), atol=1e-9)
            np.testing.assert_allclose(_pairwise(P[below]), _pairwise(rest[below]), atol=1e-9)
            if skeleton.parents[j] < 0:  # a root moves the figure
                np.testing.assert_allclose(P[j], target, atol=1e-9)
                continue
            pivot = skeleton.parents[j]
            while pivot >= 0 and np.hypot(*(rest[j] - rest[pivot])) <= 1e-6:
                pivot = skeleton.parents[pivot]
            if pivot < 0:
                continue
            # The joint points at the target from its pivot; nothing above the pivot's branch moved.
            towards, now = target - P[pivot], P[j] - P[pivot]
            across = abs(towards[0] * now[1] - towards[1] * now[0])
            assert across <= 1e-6 * np.hypot(*towards) * np.hypot(*now)
            assert towards @ now > 0
            moved = np.flatnonzero(np.hypot(*(P - rest).T) > 1e-9)
            assert set(moved) <= set(descendants(skeleton, pivot))


def test_a_reach_keeps_every_bone_its_base_and_its_bend_and_ends_on_the_target(skeleton):
    rest = skeleton.positions
    lengths = _lengths(skeleton, rest)
    reached = 0
    for j in range(len(skeleton)):
        for target in _targets(skeleton, j):
            P = drag_joint(skeleton, rest, j, target, mode="reach")
            np.testing.assert_allclose(_lengths(skeleton, P), lengths, atol=1e-6)
            if np.hypot(*(P[j] - target)) <= 1e-2:
                reached += 1
            moved = set(np.flatnonzero(np.hypot(*(P - rest).T) > 1e-9).tolist())
            if moved and len(moved) < len(skeleton):  # all below one joint that stayed: the base
                assert any(a not in moved and moved <= set(descendants(skeleton, a).tolist())
                           for a in range(len(skeleton)))
    assert reached > 0


def test_a_two_bone_reach_bends_the_elbow_to_the_side_it_was_bent():
    arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (10, 2)),
                                ("hand", "elbow", (20, 0)), ("finger", "hand", (24, 0))])
    def bend(P):
        u, v = P[1] - P[0], P[2] - P[1]
        return np.sign(u[0] * v[1] - u[1] * v[0])

    side = bend(arm.positions)
    for target in ([5, 12], [12, -5], [-8, 3], [15, 1]):
        P = drag_joint(arm, arm.positions, "hand", target, mode="reach")
        np.testing.assert_allclose(P[2], target, atol=1e-2)
        np.testing.assert_allclose(P[0], [0, 0])  # the base stays
        assert bend(P) == side
        np.testing.assert_allclose(np.hypot(*(P[3] - P[2])), 4)  # the finger rides with the hand


def test_out_of_reach_the_chain_points_straight_at_the_target():
    arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (10, 0)),
                                ("hand", "elbow", (10, 10))])
    P = drag_joint(arm, arm.positions, "hand", (0, 100), mode="reach")
    np.testing.assert_allclose(P, [[0, 0], [0, 10], [0, 20]], atol=1e-9)


def test_a_reach_stops_at_a_pinned_joint_and_a_pinned_joint_does_not_move():
    leg = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 10)),
                                ("ankle", "knee", (0, 20)), ("toe", "ankle", (5, 20))])
    P = drag_joint(leg, leg.positions, "toe", (8, 15), mode="reach", bones=3, pinned=["knee"])
    np.testing.assert_allclose(P[:2], leg.positions[:2])  # the knee is the chain's base
    np.testing.assert_allclose(P[3], (8, 15), atol=1e-2)
    stays = drag_joint(leg, leg.positions, "ankle", (9, 9), pinned=["ankle"])
    np.testing.assert_allclose(stays, leg.positions)


def test_a_stretch_moves_the_joint_to_the_target_and_everything_below_along():
    arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (10, 0)),
                                ("hand", "elbow", (20, 0))])
    P = drag_joint(arm, arm.positions, "elbow", (15, 5), mode="stretch")
    np.testing.assert_allclose(P, [[0, 0], [15, 5], [25, 5]])


@pytest.mark.parametrize(
    ("kwargs", "said"),
    [
        ({"mode": "spin"}, "a drag's mode must be one of turn, reach, stretch, got 'spin'"),
        ({"joint": 9}, "no joint 9: joints are numbered 0 to 2"),
        ({"joint": "tail"}, "tail"),
        ({"target": (1, np.nan)}, "a drag's target must be a point"),
        ({"target": (1, 2, 3)}, "a drag's target must be a point"),
        ({"bones": 0}, "an IK chain must have at least one bone, got 0"),
        ({"positions": np.zeros((2, 2))}, "a pose of this skeleton has 3 joints"),
    ],
)
def test_a_bad_drag_is_refused_in_one_line(kwargs, said):
    arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (10, 0)),
                                ("hand", "elbow", (20, 0))])
    call = {"positions": arm.positions, "joint": "hand", "target": (5, 5), **kwargs}
    with pytest.raises(Exception, match=".*") as refused:
        drag_joint(arm, call.pop("positions"), call.pop("joint"), call.pop("target"), **call)
    assert said in str(refused.value) and "\n" not in str(refused.value)
    assert isinstance(refused.value, (PoseError,)) or "tail" in said
