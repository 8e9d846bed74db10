"""Tests for toonmotion.testing.swinging_keys: key-frames that swing any skeleton's bones."""

import numpy as np
import pytest

from tests.conftest import DRAWINGS_DIR
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.testing.swinging_keys import swinging_keys


@pytest.fixture(scope="module")
def skeleton():
    config = DRAWINGS_DIR / "char2" / "char_cfg.yaml"
    if not config.exists():
        pytest.skip(f"needs the shared drawings at {DRAWINGS_DIR}")
    return load_skeleton_file(config)


def test_bones_turn_about_their_parents_and_keep_their_lengths(skeleton):
    timeline = swinging_keys(skeleton, seed=3)
    parents = skeleton.parents
    child = np.flatnonzero(parents >= 0)
    rest = skeleton.positions

    def lengths(points):
        return np.hypot(*(points[child] - points[parents[child]]).T)

    turned = []
    for key in timeline.keys:
        points = key.pose.positions
        np.testing.assert_allclose(lengths(points), lengths(rest), atol=1e-9)
        bones, rest_bones = points[child] - points[parents[child]], rest[child] - rest[parents[child]]
        cross = rest_bones[:, 0] * bones[:, 1] - rest_bones[:, 1] * bones[:, 0]
        turned.append(np.arctan2(cross, (rest_bones * bones).sum(axis=1)))
    turned = np.abs(np.array(turned))
    assert turned.max() > np.radians(8)  # the limbs swing
    roots = np.flatnonzero(parents < 0)
    assert all((key.pose.positions[roots, 1] <= rest[roots, 1] + 1e-9).all() for key in timeline.keys)


def test_the_cycle_closes_and_a_seed_repeats_itself(skeleton):
    a, b, c = (swinging_keys(skeleton, seed=s) for s in (5, 5, 6))
    np.testing.assert_allclose(a.keys[0].pose.positions, a.keys[-1].pose.positions, atol=1e-9)
    pairs = zip(a.keys, b.keys, strict=True)
    assert all(np.array_equal(x.pose.positions, y.pose.positions) for x, y in pairs)
    assert not np.allclose(a.keys[3].pose.positions, c.keys[3].pose.positions)
    assert [key.frame for key in a.keys] == list(range(0, 49, 6)) and a.ease == "in-out"
