"""As-rigid-as-possible in-betweens (keyshape/arap.py): the properties the issue names."""

import numpy as np
import pytest

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.arap import ArapPair, triangulate_shape


def _rotation(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s], [s, c]])


def _rigid_fit_residual(shape, key):
    """How far ``shape`` is from a rotation plus translation of ``key`` (Procrustes), and the angle."""
    a, b = key - key.mean(axis=0), shape - shape.mean(axis=0)
    U, _, Vt = np.linalg.svd(a.T @ b)
    R = (U @ Vt).T
    return np.abs(a @ R.T - b).max(), np.arctan2(R[1, 0], R[0, 0])


def test_the_ends_reproduce_the_keys(outlines):
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        pair = ArapPair(outlines[i], outlines[j], closed=True)
        assert np.abs(pair.at(0.0) - outlines[i]).max() <= 1e-9
        assert np.abs(pair.at(1.0) - outlines[j]).max() <= 1e-9


@pytest.mark.parametrize("degrees", [30, 90, 170, -170])
def test_between_a_shape_and_a_turned_copy_every_inbetween_is_rigid_the_short_way(outlines, degrees):
    key = outlines[0]
    turned = (key - key.mean(axis=0)) @ _rotation(np.radians(degrees)).T + key.mean(axis=0) + [40, -25]
    pair = ArapPair(key, turned, closed=True)
    for t in np.linspace(0, 1, 9):
        residual, angle = _rigid_fit_residual(pair.at(t), key)
        assert residual <= 1e-6
        assert np.degrees(angle) == pytest.approx(t * degrees, abs=1e-6)  # 170 degrees: +85 at t = 0.5


def test_no_inbetween_of_the_test_pairs_turns_a_triangle_over(smooth_keys):
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        pair = ArapPair(smooth_keys[i], smooth_keys[j], closed=True)
        for shape in pair.inbetweens(9):
            a, b, c = (shape[pair.triangles[:, k]] for k in range(3))
            area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
            assert (area > 0).all()


def test_a_closed_contour_keeps_only_the_triangles_inside_it(outlines):
    import shapely

    triangles = triangulate_shape(outlines[0], closed=True)
    centres = outlines[0][triangles].mean(axis=1)
    assert shapely.contains_xy(shapely.Polygon(outlines[0]), centres[:, 0], centres[:, 1]).all()
    assert set(triangles.ravel()) == set(range(len(outlines[0])))


@pytest.mark.parametrize(("second", "message"), [
    ([(0, 0), (1, 0)], "the same count"),
    ([(0, 0), (1, 1), (2, 2), (3, 3)], "one line"),
    ([(0, 0), (1, 0), (np.nan, 1), (0, 1)], "finite"),
])
def test_bad_pairs_are_refused_in_one_line(second, message):
    first = [(0, 0), (1, 0), (1, 1), (0, 1)]
    with pytest.raises(KeyShapeError, match=message) as caught:
        ArapPair(first, second, closed=True)
    assert "\n" not in str(caught.value)


def test_a_triangle_flat_in_a_later_key_takes_its_neighbours_map_and_the_pair_stays_rigid():
    """The model triangulates its first key; a later key traced from pixels can hold three of
    those corners on one straight run, a triangle of no area, whose map the inversion could not
    find (a singular matrix on a blob picked in the editor). Between such a key and a turned copy
    the in-betweens stay rigid, the flat triangle turned with the rest."""
    first = np.array([(0.0, 0), (10, -6), (20, 0), (20, 20), (10, 24), (0, 20)])  # a triangle (0, 1, 2)
    flat = first.copy()
    flat[1] = (10, 0)  # in this key corners 0, 1 and 2 are on the line y = 0
    triangles = triangulate_shape(first, closed=True)
    assert any(set(t) == {0, 1, 2} for t in triangles.tolist())
    turned = (flat - flat.mean(axis=0)) @ _rotation(np.radians(60)).T + flat.mean(axis=0)
    pair = ArapPair(flat, turned, closed=True, triangles=triangles)
    for t in np.linspace(0, 1, 5):
        residual, angle = _rigid_fit_residual(pair.at(t), flat)
        assert residual <= 1e-6 and np.degrees(angle) == pytest.approx(60 * t, abs=1e-6)
