"""Tests for toonmotion.geometry.coordinates: mean value weights and the RSI curve Laplacian."""

import numpy as np
import pytest

from toonmotion.geometry.coordinates import (
    as_complex,
    as_points,
    mean_value_weights,
    rsi_laplacian_coefficients,
)
from toonmotion.io.char_cfg import load_char_cfg
from toonmotion.io.image import load_image, load_mask
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character

# A similarity transform: rotation by 2.1 rad, uniform scale 3.7, then a translation.
ROTATE, SCALE, SHIFT = 2.1, 3.7, np.array([-41.5, 260.25])


def _similar(P):
    return as_points(SCALE * np.exp(1j * ROTATE) * as_complex(P) + as_complex(SHIFT))


@pytest.fixture(scope="module")
def rigged():
    """Rigged characters by name, each rigged once for this module."""
    cache = {}

    def get(name, root=None):
        if name not in cache:
            if name == "sample":
                rgba, skeleton = sample_character()
                cache[name] = rig_drawing(rgba, skeleton=skeleton)
            else:
                folder = root / name
                texture = load_image(folder / "texture.png")
                size = (texture.shape[1], texture.shape[0])
                skeleton, _ = load_char_cfg(folder / "char_cfg.yaml")
                mask = load_mask(folder / "mask.png", size=size)
                cache[name] = rig_drawing(texture, mask=mask, skeleton=skeleton)
        return cache[name]

    return get


@pytest.fixture(params=["sample", "char1", "char2", "char3", "char4"])
def mesh(request, rigged):
    root = None if request.param == "sample" else request.getfixturevalue("drawings_root")
    return rigged(request.param, root).mesh


def _reproduce(V, F):
    rows, cols, w = mean_value_weights(V, F)
    out = np.zeros_like(V)
    np.add.at(out, rows, w[:, None] * V[cols])
    return out, rows, cols, w


# --- mean value weights --------------------------------------------------------------------


def test_mean_value_weights_reproduce_every_inner_vertex(mesh):
    """Eq. 3.5: an inner vertex is the weighted sum of its one-ring, to 1e-9 px."""
    V, F = mesh.V, mesh.F
    inner = np.arange(mesh.n_outline, len(V))
    assert len(inner) > 100
    rebuilt, rows, cols, w = _reproduce(V, F)
    error = np.abs(rebuilt[inner] - V[inner]).max()
    assert error < 1e-9, f"worst inner vertex is off by {error:.3g} px"
    # The identity is special to inner vertices: an outline vertex's open one-ring misses it.
    assert np.abs(rebuilt[: mesh.n_outline] - V[: mesh.n_outline]).max() > mesh.spacing / 10


def test_mean_value_weights_are_positive_sum_to_one_and_follow_the_edges(mesh):
    V, F = mesh.V, mesh.F
    rows, cols, w = mean_value_weights(V, F)
    assert np.all(w > 0)  # every one-ring of a sound mesh has all its angles below pi
    np.testing.assert_allclose(np.bincount(rows, weights=w, minlength=len(V)), 1.0, rtol=0, atol=1e-12)
    # One weight per (vertex, neighbour) pair: exactly the mesh's edges, both ways round.
    pairs = np.sort(np.stack([rows, cols], axis=1), axis=1)
    edges = mesh.edges
    assert len(rows) == 2 * len(edges)
    assert {tuple(p) for p in pairs.tolist()} == {tuple(e) for e in edges.tolist()}
    assert len(np.unique(rows * len(V) + cols)) == len(rows)


def test_mean_value_weights_are_similarity_invariant(mesh):
    rows, cols, w = mean_value_weights(mesh.V, mesh.F)
    rows2, cols2, w2 = mean_value_weights(_similar(mesh.V), mesh.F)
    np.testing.assert_array_equal(rows, rows2)
    np.testing.assert_array_equal(cols, cols2)
    np.testing.assert_allclose(w2, w, rtol=0, atol=1e-12)


def test_mean_value_weights_of_a_regular_one_ring():
    """A vertex amid a regular hexagon weighs its six neighbours equally; off-centre it leans."""
    ring = np.exp(1j * np.pi / 3 * np.arange(6))
    F = np.array([[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)])
    for centre in (0.0, 0.3 - 0.2j):
        V = as_points(np.concatenate([[centre], ring]))
        rows, cols, w = mean_value_weights(V, F)
        mine = rows == 0
        np.testing.assert_allclose(w[mine] @ V[cols[mine]], V[0], atol=1e-15)
        if centre == 0:
            np.testing.assert_allclose(w[mine], 1 / 6, rtol=1e-12)
        else:
            nearest = np.argmin(np.abs(ring - centre)) + 1
            assert w[mine][cols[mine] == nearest] == w[mine].max()



def test_mean_value_weights_of_a_vertex_with_only_flat_triangles_are_equal_and_finite():
    """Collapsed triangles (a folded pose) have no angles: the vertex weighs its neighbours equally."""
    V = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    with np.errstate(all="raise"):
        rows, cols, w = mean_value_weights(V, F)
    assert np.isfinite(w).all()
    np.testing.assert_allclose(np.bincount(rows, weights=w), 1.0)
    np.testing.assert_allclose(w[rows == 0], 1 / 3)


# --- the RSI curve Laplacian ------------------------------------------------------------


def _curve(n=40, seed=3):
    """A closed, wiggly curve: each vertex with its neighbours along it."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 50 + 10 * np.sin(3 * t) + rng.uniform(-3, 3, n)
    P = np.stack([r * np.cos(t), r * np.sin(t)], axis=1) + (120.0, 80.0)
    return np.roll(P, 1, axis=0), P, np.roll(P, -1, axis=0)


def test_rsi_coefficients_rebuild_each_vertex_from_its_neighbours():
    prev, point, after = _curve()
    c = rsi_laplacian_coefficients(prev, point, after)
    z_prev, z, z_after = as_complex(prev), as_complex(point), as_complex(after)
    np.testing.assert_allclose((z_prev + z_after) / 2 + c * (z_after - z_prev), z, rtol=0, atol=1e-12)


@pytest.mark.parametrize("n", [3, 40, 400])
def test_rsi_coefficients_do_not_change_under_rotation_scale_and_translation(n):
    prev, point, after = _curve(n)
    c = rsi_laplacian_coefficients(prev, point, after)
    moved = rsi_laplacian_coefficients(_similar(prev), _similar(point), _similar(after))
    np.testing.assert_allclose(moved, c, rtol=0, atol=1e-12)
    # ... and so a similar copy of the curve satisfies the same linear equations exactly.
    z_prev, z, z_after = (as_complex(_similar(p)) for p in (prev, point, after))
    np.testing.assert_allclose(z - (z_prev + z_after) / 2 - c * (z_after - z_prev), 0, atol=1e-10)


def test_rsi_coefficients_see_a_mirror_image_as_the_conjugate():
    prev, point, after = _curve()
    flip = np.array([-1.0, 1.0])
    c = rsi_laplacian_coefficients(prev, point, after)
    mirrored = rsi_laplacian_coefficients(prev * flip, point * flip, after * flip)
    np.testing.assert_allclose(mirrored, np.conj(c), rtol=0, atol=1e-12)


def test_rsi_coefficients_of_straight_and_degenerate_curves():
    prev = np.array([[0.0, 0.0], [5.0, 5.0], [2.0, 2.0]])
    point = np.array([[1.0, 0.0], [5.0, 5.0], [3.0, 9.0]])
    after = np.array([[2.0, 0.0], [5.0, 5.0], [2.0, 2.0]])
    c = rsi_laplacian_coefficients(prev, point, after)
    assert c[0] == 0  # the midpoint of a straight chord
    assert c[1] == 0 and c[2] == 0  # no chord: no coefficient, and no division by zero
    assert c.dtype == complex and c.shape == (3,)


def test_complex_points_round_trip_exactly():
    P = np.random.default_rng(0).normal(0, 1e3, size=(50, 2))
    np.testing.assert_array_equal(as_points(as_complex(P)), P)
    assert as_complex([[1.0, -2.0]]).tolist() == [1 - 2j]
