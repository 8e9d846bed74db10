"""Tests for toonmotion.geometry.polygon."""

import numpy as np
import pytest
import shapely

from toonmotion.geometry.polygon import (
    loop_edges,
    points_in_polygon,
    signed_area,
    subdivide_loop,
    triangle_areas,
    triangle_min_angles,
)

# On screen (y down) this square runs down the left side, right along the bottom and up the
# right side: counter-clockwise as the viewer sees it.
SCREEN_CCW_SQUARE = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], float)


def _star_polygon(rng, n=40, center=(50.0, 40.0)):
    """A random simple polygon: star-shaped about ``center``, counter-clockwise on screen."""
    theta = np.sort(rng.uniform(0, 2 * np.pi, n))
    radius = rng.uniform(8.0, 30.0, n)
    # Increasing angle with y down turns clockwise on screen; reverse for counter-clockwise.
    P = np.stack([np.cos(theta), np.sin(theta)], axis=1) * radius[:, None] + center
    return P[::-1].copy()


def _y_up_shoelace(P):
    """Textbook shoelace area in a y-up frame, after flipping the screen's y axis."""
    x, y = P[:, 0], -P[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


# signed_area ----------------------------------------------------------------------------


def test_signed_area_is_positive_for_counter_clockwise_on_screen():
    assert signed_area(SCREEN_CCW_SQUARE) == pytest.approx(1.0)
    assert signed_area(SCREEN_CCW_SQUARE[::-1]) == pytest.approx(-1.0)


def test_signed_area_east_then_up_on_screen_is_a_left_turn():
    # East, then towards the top of the screen (y decreasing): the viewer sees a left turn.
    triangle = np.array([[0, 0], [4, 0], [4, -3]], float)
    assert signed_area(triangle) == pytest.approx(6.0)


def test_signed_area_matches_shoelace_with_y_flipped():
    rng = np.random.default_rng(1)
    for _ in range(20):
        P = rng.uniform(-50, 50, size=(rng.integers(3, 12), 2))
        assert signed_area(P) == pytest.approx(_y_up_shoelace(P), rel=1e-12, abs=1e-9)


def test_signed_area_rectangle_is_invariant_to_start_vertex_and_translation():
    rect = np.array([[2, 3], [2, 8], [9, 8], [9, 3]], float)  # 7 x 5, counter-clockwise
    for shift in range(4):
        assert signed_area(np.roll(rect, shift, axis=0)) == pytest.approx(35.0)
    assert signed_area(rect + [1000.0, -250.0]) == pytest.approx(35.0)


def test_signed_area_accepts_integer_lists():
    assert signed_area([[0, 0], [0, 2], [3, 2], [3, 0]]) == pytest.approx(6.0)


# triangle_areas / triangle_min_angles ---------------------------------------------------


def test_triangle_areas_agree_with_signed_area():
    rng = np.random.default_rng(2)
    V = rng.uniform(0, 100, size=(30, 2))
    F = np.array([rng.choice(30, 3, replace=False) for _ in range(200)])
    areas = triangle_areas(V, F)
    expected = np.array([signed_area(V[f]) for f in F])
    np.testing.assert_allclose(areas, expected, rtol=1e-12, atol=1e-9)
    # Reversing a triangle flips its sign.
    np.testing.assert_allclose(triangle_areas(V, F[:, ::-1]), -expected, rtol=1e-12, atol=1e-9)


def test_triangle_min_angle_of_equilateral_triangle_is_60_degrees():
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, np.sqrt(3) / 2]])
    F = np.array([[0, 1, 2], [2, 1, 0]])
    np.testing.assert_allclose(np.degrees(triangle_min_angles(V, F)), 60.0, atol=1e-9)


def test_triangle_min_angles_known_triangles():
    V = np.array([[0, 0], [1, 0], [0, 1], [2, 0], [10, 0], [0, 1]], float)
    F = np.array([[0, 1, 2], [0, 3, 5], [0, 4, 5]])
    expected = [45.0, np.degrees(np.arctan2(1, 2)), np.degrees(np.arctan2(1, 10))]
    np.testing.assert_allclose(np.degrees(triangle_min_angles(V, F)), expected, atol=1e-9)


def test_triangle_min_angles_match_law_of_cosines_and_never_exceed_60():
    rng = np.random.default_rng(3)
    V = rng.uniform(0, 10, size=(300, 2))
    F = np.arange(300).reshape(100, 3)
    got = triangle_min_angles(V, F)
    a = np.linalg.norm(V[F[:, 1]] - V[F[:, 2]], axis=1)
    b = np.linalg.norm(V[F[:, 2]] - V[F[:, 0]], axis=1)
    c = np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1)
    angles = np.stack(
        [
            np.arccos((b**2 + c**2 - a**2) / (2 * b * c)),
            np.arccos((c**2 + a**2 - b**2) / (2 * c * a)),
            np.arccos((a**2 + b**2 - c**2) / (2 * a * b)),
        ],
        axis=1,
    )
    np.testing.assert_allclose(got, angles.min(axis=1), atol=1e-7)
    assert np.all(got <= np.pi / 3 + 1e-12)


def test_triangle_min_angle_of_degenerate_triangle_is_zero():
    V = np.array([[0, 0], [1, 1], [2, 2], [5, 5]], float)
    F = np.array([[0, 1, 2], [0, 0, 3]])
    assert np.all(np.isfinite(triangle_min_angles(V, F)))
    assert triangle_min_angles(V, F)[0] == pytest.approx(0.0, abs=1e-6)


# subdivide_loop --------------------------------------------------------------------------


def _edge_lengths(P):
    return np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1)


@pytest.mark.parametrize("max_edge", [0.7, 2.0, 5.0, 100.0])
def test_subdivide_loop_keeps_vertices_bounds_edges_and_traces_same_polygon(max_edge):
    rng = np.random.default_rng(4)
    P = _star_polygon(rng)
    Q = subdivide_loop(P, max_edge)

    # The original vertices appear in the same cyclic order, starting at index 0.
    index = [int(np.flatnonzero(np.all(Q == p, axis=1))[0]) for p in P]
    assert index[0] == 0
    assert np.all(np.diff(index) > 0)

    # No edge, the closing one included, is longer than max_edge.
    assert _edge_lengths(Q).max() <= max_edge * (1 + 1e-9)

    # Every new point lies on the original outline, so the polygon is the same.
    ring = shapely.LinearRing(P)
    assert shapely.distance(ring, shapely.points(Q)).max() < 1e-9
    assert signed_area(Q) == pytest.approx(signed_area(P), rel=1e-12)
    assert len(Q) == np.sum(np.ceil(_edge_lengths(P) / max_edge - 1e-9).clip(min=1))


def test_subdivide_loop_spaces_inserted_points_evenly():
    P = np.array([[0, 0], [10, 0], [10, 3]], float)
    Q = subdivide_loop(P, 3.0)
    # 10 px -> 4 pieces of 2.5; 3 px -> 1 piece; the closing edge (~10.44 px) -> 4 pieces.
    assert len(Q) == 4 + 1 + 4
    np.testing.assert_allclose(Q[:5], [[0, 0], [2.5, 0], [5, 0], [7.5, 0], [10, 0]])
    closing = _edge_lengths(Q)[5:]
    np.testing.assert_allclose(closing, closing[0])


def test_subdivide_loop_leaves_an_edge_of_exactly_max_edge_alone():
    square = SCREEN_CCW_SQUARE * 2.0
    np.testing.assert_array_equal(subdivide_loop(square, 2.0), square)


def test_subdivide_loop_survives_a_repeated_vertex():
    P = np.array([[0, 0], [0, 0], [0, 4], [4, 4]], float)
    Q = subdivide_loop(P, 1.0)
    assert np.all(np.isfinite(Q))
    assert _edge_lengths(Q).max() <= 1.0 + 1e-9


# loop_edges ------------------------------------------------------------------------------


def test_loop_edges_closes_every_loop():
    edges = loop_edges([np.array([0, 1, 2]), np.array([5, 6, 7, 8])])
    assert edges.tolist() == [[0, 1], [1, 2], [2, 0], [5, 6], [6, 7], [7, 8], [8, 5]]


def test_loop_edges_of_no_loops_is_empty():
    edges = loop_edges([])
    assert edges.shape == (0, 2)
    assert edges.dtype.kind == "i"


# points_in_polygon -----------------------------------------------------------------------


def _square(x0, y0, x1, y1):
    return np.array([[x0, y0], [x0, y1], [x1, y1], [x1, y0]], float)


def test_points_in_polygon_point_in_hole_is_outside():
    outer, hole = _square(0, 0, 10, 10), _square(3, 3, 7, 7)[::-1]
    points = np.array([[5, 5], [1, 1], [8.5, 5], [20, 20], [-1, 5]], float)
    expected = [False, True, True, False, False]
    assert points_in_polygon(points, [outer, hole]).tolist() == expected
    # Orientation of the loops does not matter.
    assert points_in_polygon(points, [outer[::-1], hole[::-1]]).tolist() == expected


def test_points_in_polygon_matches_shapely_on_random_points():
    rng = np.random.default_rng(5)
    outer = _star_polygon(rng, n=60)
    hole = _square(46, 36, 54, 44)[::-1]  # the star reaches at least 8 px from (50, 40)
    polygon = shapely.Polygon(outer, [hole])
    assert polygon.is_valid
    points = rng.uniform([10, 0], [90, 80], size=(3000, 2))
    # Keep clear of the edges, where either answer is allowed.
    points = points[shapely.distance(polygon.boundary, shapely.points(points)) > 1e-6]
    expected = shapely.contains_xy(polygon, points[:, 0], points[:, 1])
    assert 0 < expected.sum() < len(points)
    np.testing.assert_array_equal(points_in_polygon(points, [outer, hole]), expected)


def test_points_in_polygon_with_separate_outer_loops():
    loops = [_square(0, 0, 2, 2), _square(5, 0, 7, 2)]
    points = np.array([[1, 1], [6, 1], [3.5, 1]], float)
    assert points_in_polygon(points, loops).tolist() == [True, True, False]


def test_points_in_polygon_edges_and_corners_are_outside():
    square = _square(0, 0, 2, 2)
    points = np.array([[0, 1], [2, 1], [1, 0], [1, 2], [0, 0], [2, 2], [1, 1]], float)
    assert points_in_polygon(points, [square]).tolist() == [False] * 6 + [True]


def test_points_in_polygon_is_even_odd_for_a_loop_that_crosses_itself():
    """A loop wound twice round a region leaves it outside; a bow tie holds both wings."""
    twice = np.concatenate([_square(0, 0, 4, 4), _square(1, 1, 3, 3)])  # in, then round again
    assert points_in_polygon(np.array([[2, 2], [0.5, 2]], float), [twice]).tolist() == [False, True]
    bow_tie = np.array([[0, 0], [4, 4], [4, 0], [0, 4]], float)
    points = np.array([[0.5, 2], [3.5, 2], [2, 0.5], [2, 3.5]], float)
    assert points_in_polygon(points, [bow_tie]).tolist() == [True, True, False, False]


def test_points_in_polygon_loops_without_area_hold_nothing():
    points = np.array([[0.5, 0.5], [1, 1]], float)
    segment = np.array([[0, 0], [2, 2]], float)
    assert points_in_polygon(points, [segment, segment[:1]]).tolist() == [False, False]
    assert points_in_polygon(np.zeros((0, 2)), [_square(0, 0, 1, 1)]).shape == (0,)
