"""Tests for toonmotion.render.cloth: cloth triangles z-buffered through a perspective camera.

The reference does not share the rasteriser's arithmetic: each pixel's ray (``camera.rays``) is
intersected with each triangle in the world (Moller-Trumbore), and the nearest hit in front is the
pixel's. Pixel centres within rounding of a triangle's edge may go either way.
"""

import numpy as np
import pytest

from toonmotion.errors import SceneError
from toonmotion.proxy3d.camera import PerspectiveCamera, rotations
from toonmotion.render.cloth import render_cloth
from toonmotion.render.zbuffer import AMBIENT, render_primitives

EDGE = 1e-7  # barycentric coordinates this close to 0 are rounding's to decide


def _camera(width=64, height=48, azimuth=20.0, elevation=10.0):
    """A camera looking at the origin from 4 m, focal 60 pixels."""
    angles = np.radians([azimuth, elevation, 0.0])
    forward = rotations([angles])[0][2]
    return PerspectiveCamera(60.0, width, height, [[*angles, *(-4.0 * forward)]])


def _reference(cam, V, F):
    """Per pixel: the nearest triangle in front and its depth along the camera's axis (-1 and inf
    where none), and whether any triangle's edge passes within rounding of the pixel's centre."""
    i, j = np.mgrid[0:cam.height, 0:cam.width]
    pixels = np.stack([j, i], axis=-1).reshape(1, -1, 2).astype(float)
    o, d = cam.centres[0], cam.rays(pixels)[0]  # (P, 3), unit depth along the axis
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = b - a, c - a
    p = np.cross(d[:, None], e2[None])  # (P, T, 3)
    det = (p * e1[None]).sum(-1)
    s = o - a  # (T, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        w1 = (p * s[None]).sum(-1) / det
        q = np.cross(s, e1)  # (T, 3)
        w2 = (d @ q.T) / det
        t = (q * e2).sum(-1)[None] / det  # the depth: d has unit depth
    w0 = 1 - w1 - w2
    inside = (np.abs(det) > 1e-15) & (w0 >= 0) & (w1 >= 0) & (w2 >= 0) & (t > 0)
    near = np.abs(np.stack([w0, w1, w2])).min(axis=0) < EDGE
    depth = np.where(inside, t, np.inf)
    nearest = depth.argmin(axis=1)
    best = depth.min(axis=1)
    ids = np.where(np.isfinite(best), nearest, -1)
    shape = (cam.height, cam.width)
    return ids.reshape(shape), best.reshape(shape), near.any(axis=1).reshape(shape)


def _sheet(rng, n=6):
    """A crumpled sheet of ``n`` x ``n`` vertices round the origin, folded over itself."""
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    V = np.stack([x, y, 0.6 * np.sin(2.5 * x) * np.cos(1.5 * y)], -1).reshape(-1, 3)
    V += rng.normal(0, 0.05, V.shape)
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None]).ravel()
    F = np.concatenate([np.stack([a, a + n, a + 1], 1), np.stack([a + 1, a + n, a + n + 1], 1)])
    return V, F


@pytest.mark.parametrize("seed", range(4))
def test_every_pixel_is_the_nearest_triangle_its_ray_meets(seed):
    rng = np.random.default_rng(seed)
    V, F = _sheet(rng)
    cam = _camera(azimuth=rng.uniform(-60, 60), elevation=rng.uniform(-30, 30))
    colours = rng.integers(0, 256, (len(F), 3), dtype=np.uint8)
    layer = render_cloth(cam, 0, V, F, colours, shading="flat")
    ids, depth, edge = _reference(cam, V, F)
    sure = ~edge
    assert sure.mean() > 0.9
    np.testing.assert_array_equal(layer.ids[sure], ids[sure])
    np.testing.assert_array_equal(layer.coverage[sure], ids[sure] >= 0)
    hit = sure & (ids >= 0)
    assert hit.sum() > 200
    np.testing.assert_allclose(layer.depth[hit], depth[hit], rtol=1e-9)
    np.testing.assert_array_equal(layer.colour[hit], colours[ids[hit]])
    assert np.isinf(layer.depth[~layer.coverage]).all()


def test_cloth_is_two_sided_and_lit_the_same_from_either_winding():
    cam = _camera(azimuth=0.0, elevation=0.0)
    V = np.array([[-0.5, -0.5, 0.0], [0.5, -0.5, 0], [0.5, 0.5, 0], [-0.5, 0.5, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    front = render_cloth(cam, 0, V, F, [[200, 100, 50]] * 2, shading="smooth")
    back = render_cloth(cam, 0, V, F[:, ::-1], [[200, 100, 50]] * 2, shading="smooth")
    np.testing.assert_array_equal(front.colour, back.colour)
    np.testing.assert_array_equal(front.coverage, back.coverage)
    np.testing.assert_allclose(front.depth, back.depth, rtol=1e-12)
    # A flat square facing the camera is lit evenly: one colour, no darker than the ambient share.
    seen = front.colour[front.coverage]
    assert len(np.unique(seen, axis=0)) == 1
    assert (seen >= np.floor(AMBIENT * np.array([200, 100, 50]))).all()


def test_cloth_keeps_the_nearer_of_itself_and_what_is_drawn_under_it():
    cam = _camera(azimuth=0.0, elevation=0.0)
    under = render_primitives(cam, 0, spheres=[[0.0, 0.0, 0.0, 0.3]], colours=[[0, 0, 255]])
    V = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0], [1.0, 1.0, 0], [-1.0, 1.0, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    layer = render_cloth(cam, 0, V, F, [[255, 0, 0]] * 2, shading="flat", under=under, first_id=1)
    ball = under.coverage
    # The sphere's front pokes 0.3 m through the sheet at the origin: its pixels stay the sphere's.
    np.testing.assert_array_equal(layer.ids[ball], 0)
    np.testing.assert_array_equal(layer.depth[ball], under.depth[ball])
    assert (layer.ids[layer.coverage & ~ball] >= 1).all()
    assert (layer.colour[layer.coverage & ~ball] == [255, 0, 0]).all()


def test_a_triangle_behind_the_camera_is_not_drawn_and_bad_input_is_refused():
    cam = _camera(azimuth=0.0, elevation=0.0)
    behind = np.array([[0.0, 0.0, 5.0], [1.0, 0, 5.0], [0, 1, 5.0]])
    assert not render_cloth(cam, 0, behind, [[0, 1, 2]], [[1, 2, 3]]).coverage.any()
    with pytest.raises(SceneError, match="finite"):
        render_cloth(cam, 0, np.full((3, 3), np.nan), [[0, 1, 2]], [[1, 2, 3]])
    with pytest.raises(SceneError, match="shading"):
        render_cloth(cam, 0, behind, [[0, 1, 2]], [[1, 2, 3]], shading="glossy")
