"""Tests for toonmotion.geometry.segments."""

import warnings

import numpy as np
import pytest
import shapely

from toonmotion.geometry.segments import arc_lengths, closest_points_on_segments, resample_by_arc_length


def test_closest_points_shapes():
    points, A, B = np.zeros((5, 2)), np.zeros((3, 2)), np.ones((3, 2))
    closest, distance = closest_points_on_segments(points, A, B)
    assert closest.shape == (5, 3, 2)
    assert distance.shape == (5, 3)


def test_closest_points_match_brute_force_on_random_data():
    rng = np.random.default_rng(0)
    points = rng.uniform(-20, 20, size=(60, 2))
    A = rng.uniform(-10, 10, size=(25, 2))
    B = rng.uniform(-10, 10, size=(25, 2))
    closest, distance = closest_points_on_segments(points, A, B)

    # Distances agree with shapely's exact point-to-segment distance.
    segments = shapely.linestrings(np.stack([A, B], axis=1))
    expected = shapely.distance(shapely.points(points)[:, None], segments[None, :])
    np.testing.assert_allclose(distance, expected, rtol=1e-9, atol=1e-9)

    # Each closest point lies on its segment and realises the distance.
    on_segment = shapely.distance(shapely.points(closest), segments[None, :])
    assert on_segment.max() < 1e-9
    np.testing.assert_allclose(np.linalg.norm(points[:, None] - closest, axis=2), distance)

    # No point sampled densely along a segment is closer.
    t = np.linspace(0, 1, 1001)
    samples = A[None, :, :] + t[:, None, None] * (B - A)[None, :, :]  # (t, k, 2)
    sampled = np.linalg.norm(points[:, None, None] - samples[None], axis=3).min(axis=1)
    assert np.all(distance <= sampled + 1e-12)


def test_closest_point_clamps_to_segment_ends():
    A, B = np.array([[0.0, 0.0]]), np.array([[4.0, 0.0]])
    points = np.array([[-3.0, 4.0], [7.0, -4.0], [2.0, 0.0]])
    closest, distance = closest_points_on_segments(points, A, B)
    np.testing.assert_allclose(closest[:, 0], [[0, 0], [4, 0], [2, 0]])
    np.testing.assert_allclose(distance[:, 0], [5.0, 5.0, 0.0])


def test_zero_length_segment_is_a_point_without_warnings():
    points = np.array([[3.0, 4.0], [1.0, 1.0], [1.0, 1.0]])
    A = np.array([[1.0, 1.0], [0.0, 0.0]])
    B = np.array([[1.0, 1.0], [2.0, 0.0]])  # segment 0 is degenerate
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        closest, distance = closest_points_on_segments(points, A, B)
    assert np.all(np.isfinite(closest))
    np.testing.assert_allclose(closest[:, 0], [[1, 1]] * 3)
    np.testing.assert_allclose(distance[:, 0], [np.hypot(2, 3), 0.0, 0.0])
    np.testing.assert_allclose(closest[:, 1], [[2, 0], [1, 0], [1, 0]])


def test_distance_is_symmetric_in_segment_direction():
    rng = np.random.default_rng(1)
    points = rng.normal(size=(20, 2))
    A, B = rng.normal(size=(7, 2)), rng.normal(size=(7, 2))
    c1, d1 = closest_points_on_segments(points, A, B)
    c2, d2 = closest_points_on_segments(points, B, A)
    np.testing.assert_allclose(d1, d2, atol=1e-12)
    np.testing.assert_allclose(c1, c2, atol=1e-12)


@pytest.mark.parametrize("n_points", [0, 1])
def test_few_points(n_points):
    closest, distance = closest_points_on_segments(
        np.ones((n_points, 2)), np.zeros((2, 2)), np.array([[1.0, 0.0], [0.0, 1.0]])
    )
    assert closest.shape == (n_points, 2, 2)
    assert np.all(distance == 1.0)


# arc length and resampling -----------------------------------------------------------------------


def test_arc_lengths_sum_the_steps_and_start_at_zero():
    P = np.array([[0, 0], [3, 4], [3, 4], [0, 0]], float)
    assert arc_lengths(P).tolist() == [0.0, 5.0, 5.0, 10.0]
    assert arc_lengths(P[:1]).tolist() == [0.0]


def test_resampling_evenly_spaces_points_along_the_polyline():
    rng = np.random.default_rng(3)
    P = np.cumsum(rng.normal(0, 5, (30, 2)), axis=0)
    total = arc_lengths(P)[-1]
    Q = resample_by_arc_length(P, np.linspace(0, total, 200))
    np.testing.assert_allclose(Q[[0, -1]], P[[0, -1]], atol=1e-9)
    # Every resampled point lies on the polyline, and consecutive ones are at most one step apart.
    _, distance = closest_points_on_segments(Q, P[:-1], P[1:])
    assert distance.min(axis=1).max() < 1e-9
    assert np.linalg.norm(np.diff(Q, axis=0), axis=1).max() <= total / 199 + 1e-9
    # The vertices themselves come back at their own arc lengths.
    np.testing.assert_allclose(resample_by_arc_length(P, arc_lengths(P)), P, atol=1e-9)


def test_resampling_by_fraction_clamps_to_the_ends():
    P = np.array([[0, 0], [4, 0], [4, 2]], float)
    out = resample_by_arc_length(P, [-0.5, 0.0, 0.25, 1.0, 2.0], fraction=True)
    assert out.tolist() == [[0, 0], [0, 0], [1.5, 0], [4, 2], [4, 2]]
    assert resample_by_arc_length(P, [-3.0, 10.0]).tolist() == [[0, 0], [4, 2]]
