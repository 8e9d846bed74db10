"""Tests for anti-aliased elements: ``k x k`` rays a pixel resolved into coverage (alpha), colour,
depth and ids (toonmotion.render.samples, SampleBuffer in toonmotion.render.zbuffer).

The reference does not share the renderers' arithmetic: each ray, through the point
``(j + (s - (k - 1) / 2) / k, i + ...)`` of pixel ``(i, j)`` (``camera.rays``), is met with the
sphere or the triangles in the world, and a pixel's alpha is the fraction of its rays that hit.
Rays within rounding of an edge may go either way: pixels holding one are not compared.
"""

import numpy as np
import pytest

from toonmotion.errors import SceneError
from toonmotion.proxy3d.camera import PerspectiveCamera, rotations
from toonmotion.render.cloth import draw_cloth, render_cloth
from toonmotion.render.depth_composite import composite
from toonmotion.render.zbuffer import cast_primitives, layer_passes, render_primitives, window_of

SPHERE = np.array([[0.1, -0.05, 0.2, 0.6]])
RED = [[200, 30, 10]]


def _camera(width=48, height=36, azimuth=15.0, elevation=5.0):
    """A camera looking at the origin from 4 m, focal 50 pixels."""
    angles = np.radians([azimuth, elevation, 0.0])
    forward = rotations([angles])[0][2]
    return PerspectiveCamera(50.0, width, height, [[*angles, *(-4.0 * forward)]])


def _rays(cam, k):
    """Every pixel's ``k x k`` rays, ``(H, W, k * k, 3)``, world directions at unit depth."""
    offsets = (np.arange(k) - (k - 1) / 2) / k
    i, j, di, dj = np.meshgrid(np.arange(cam.height), np.arange(cam.width), offsets, offsets, indexing="ij")
    points = np.stack([j + dj, i + di], axis=-1).reshape(1, -1, 2)
    return cam.rays(points)[0].reshape(cam.height, cam.width, k * k, 3)


def _sphere_hits(cam, k, sphere):
    """Per ray: whether it meets the sphere, and whether it passes within rounding of its edge."""
    d, o = _rays(cam, k), cam.centres[0]
    m, r = sphere[:3] - o, sphere[3]
    along = d @ m / (d * d).sum(-1)
    gap = np.linalg.norm(along[..., None] * d - m, axis=-1)  # the ray's distance from the centre
    return gap < r, np.abs(gap - r) < 1e-9


@pytest.mark.parametrize("k", [2, 3, 4])
def test_a_spheres_alpha_is_the_fraction_of_its_rays_that_meet_it(k):
    cam = _camera()
    layer = render_primitives(cam, 0, spheres=SPHERE, colours=RED, shading="flat", antialias=k)
    hit, unsure = _sphere_hits(cam, k, SPHERE[0])
    sure = ~unsure.any(axis=-1)
    np.testing.assert_array_equal(layer.alpha[sure], hit.mean(axis=-1)[sure])
    edge = (layer.alpha > 0) & (layer.alpha < 1)
    assert edge.sum() > 30  # the outline is anti-aliased all round
    assert (layer.coverage == (layer.alpha > 0)).all()
    # One flat colour: every pixel it covers, wholly or partly, is that colour.
    assert (layer.colour[layer.coverage] == RED[0]).all() and (layer.colour[~layer.coverage] == 0).all()


def test_a_spheres_alpha_adds_up_to_its_area_on_the_picture():
    """A sphere centred on the camera's axis at distance D is a disc of radius f r / sqrt(D^2 - r^2)."""
    cam = PerspectiveCamera(50.0, 60, 40, [[0, 0, 0, 0, 0, 5]])  # pixel (20, 30)'s ray is the axis
    r = 0.7
    disc = np.pi * (50.0 * r / np.sqrt(5.0 ** 2 - r ** 2)) ** 2
    errors = {k: abs(render_primitives(cam, 0, spheres=[[0, 0, 0, r]], antialias=k).alpha.sum() / disc - 1)
              for k in (1, 4)}
    assert errors[4] < 0.005
    assert errors[4] < errors[1]


def test_one_ray_a_pixel_is_all_or_nothing():
    layer = render_primitives(_camera(), 0, spheres=SPHERE, antialias=1)
    np.testing.assert_array_equal(layer.alpha, layer.coverage.astype(float))


def test_where_two_elements_meet_in_a_pixel_the_nearest_gives_depth_and_id_and_the_colours_blend():
    cam = PerspectiveCamera(50.0, 40, 30, [[0, 0, 0, 0, 0, 5]])
    spheres = [[0.0, 0.0, 0.0, 0.8], [0.5, 0.0, 1.0, 0.6]]  # the second nearer, overlapping on the picture
    colours = [[200, 0, 0], [0, 0, 200]]
    one = render_primitives(cam, 0, spheres=spheres, colours=colours, shading="flat", antialias=1)
    four = render_primitives(cam, 0, spheres=spheres, colours=colours, shading="flat", antialias=4)
    both = (four.alpha == 1) & (four.colour[..., 0] > 0) & (four.colour[..., 2] > 0)
    assert both.sum() > 3  # pixels split between the two
    # There the nearest ray is the nearer sphere's, whose depth is below the far one's everywhere.
    assert (four.ids[both] == 1).all()
    assert (four.depth[both] <= one.depth[both] + 0.2).all()
    red, blue = four.colour[both, 0].astype(int), four.colour[both, 2].astype(int)
    assert (np.abs(red + blue - 200) <= 1).all()  # the mean of the rays' colours


def _triangle_hits(cam, k, V, F):
    """Per ray: whether it meets a triangle (Moller-Trumbore), and whether it is within rounding of
    an edge."""
    d, o = _rays(cam, k).reshape(-1, 3), cam.centres[0]
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1, e2 = b - a, c - a
    p = np.cross(d[:, None], e2[None])
    det = (p * e1[None]).sum(-1)
    s = o - a
    w1 = (p * s[None]).sum(-1) / det
    q = np.cross(s, e1)
    w2 = (d @ q.T) / det
    w0 = 1 - w1 - w2
    inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
    unsure = np.abs(np.stack([w0, w1, w2])).min(axis=0) < 1e-7
    shape = (cam.height, cam.width, k * k)
    return inside.any(axis=1).reshape(shape), unsure.any(axis=1).reshape(shape)


@pytest.mark.parametrize("k", [2, 3])
def test_clothes_alpha_is_the_fraction_of_its_rays_that_meet_a_triangle(k):
    cam = _camera()
    V = np.array([[-0.9, -0.7, 0.0], [0.8, -0.5, 0.2], [0.1, 0.9, -0.1], [-1.0, 0.6, 0.3]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    layer = render_cloth(cam, 0, V, F, RED * 2, shading="flat", antialias=k)
    hit, unsure = _triangle_hits(cam, k, V, F)
    sure = ~unsure.any(axis=-1)
    np.testing.assert_array_equal(layer.alpha[sure], hit.mean(axis=-1)[sure])
    assert ((layer.alpha > 0) & (layer.alpha < 1)).sum() > 30
    assert (layer.colour[layer.coverage] == RED[0]).all()


def test_cloth_drawn_into_the_primitives_rays_is_anti_aliased_with_them():
    cam = _camera()
    V = np.array([[-0.9, -0.7, 1.0], [0.8, -0.5, 1.0], [0.1, 0.9, 1.0]])  # in front of the sphere
    with pytest.raises(SceneError, match="outside the rays' window"):  # cast for the sphere alone
        draw_cloth(cast_primitives(cam, 0, spheres=SPHERE, antialias=3), cam, 0, V, [[0, 1, 2]], RED)
    window = window_of(cam, 0, spheres=SPHERE, points=V)
    rays = cast_primitives(cam, 0, spheres=SPHERE, colours=RED, shading="flat", antialias=3, window=window)
    draw_cloth(rays, cam, 0, V, [[0, 1, 2]], [[0, 0, 250]], shading="flat", first_id=1)
    layer = rays.layer()
    alone = render_cloth(cam, 0, V, [[0, 1, 2]], [[0, 0, 250]], shading="flat", antialias=3)
    sphere = render_primitives(cam, 0, spheres=SPHERE, antialias=3)
    # Every pixel is covered at least as much as by either alone, and the cloth wins where it is.
    assert (layer.alpha >= np.maximum(alone.alpha, sphere.alpha)).all()
    assert (layer.ids[alone.alpha == 1] == 1).all()


def test_a_partly_covered_pixel_shows_the_element_in_proportion():
    cam = _camera()
    layer = render_primitives(cam, 0, spheres=SPHERE, colours=RED, shading="flat", antialias=4)
    white = np.full((cam.height, cam.width, 3), 255, np.uint8)
    nothing = np.zeros((cam.height, cam.width))
    out = composite(white, layer, np.full(nothing.shape, np.inf), alpha=nothing, figure=nothing)
    edge = (layer.alpha > 0) & (layer.alpha < 1)
    expected = (1 - layer.alpha[edge, None]) * 255 + layer.alpha[edge, None] * np.array(RED[0])
    assert np.abs(out[edge] - expected).max() <= 0.5 + 1e-9
    np.testing.assert_array_equal(out[layer.alpha == 1], np.broadcast_to(RED[0], out[layer.alpha == 1].shape))
    np.testing.assert_array_equal(out[layer.alpha == 0], white[layer.alpha == 0])


def test_the_passes_carry_the_coverage_as_their_alpha():
    layer = render_primitives(_camera(), 0, spheres=SPHERE, antialias=3)
    beauty, depth, matte = layer_passes(layer)
    np.testing.assert_array_equal(beauty[..., 3], np.rint(layer.alpha * 255))
    np.testing.assert_array_equal(matte, beauty[..., 3])
    assert ((matte > 0) == (depth > 0)).all()


@pytest.mark.parametrize("bad", [0, 5, -1, 2.0, True, "2"])
def test_antialias_out_of_range_is_refused_in_one_line(bad):
    with pytest.raises(SceneError, match="antialias must be a whole number of rays per pixel side") as caught:
        render_primitives(_camera(), 0, spheres=SPHERE, antialias=bad)
    assert "\n" not in str(caught.value)


def test_cloth_over_an_anti_aliased_layer_is_refused():
    cam = _camera()
    under = render_primitives(cam, 0, spheres=SPHERE, antialias=2)
    with pytest.raises(SceneError, match="draw_cloth"):
        render_cloth(cam, 0, np.eye(3), [[0, 1, 2]], RED, under=under)
    with pytest.raises(SceneError, match="draw_cloth"):
        render_cloth(cam, 0, np.eye(3), [[0, 1, 2]], RED, under=render_primitives(cam, 0), antialias=2)


@pytest.mark.parametrize("k", [1, 3])
def test_casting_only_the_window_the_elements_may_cover_changes_nothing(k):
    cam = _camera()
    rng = np.random.default_rng(4)
    spheres = np.concatenate([rng.normal(0, 0.6, (5, 3)), rng.uniform(0.05, 0.3, (5, 1))], axis=1)
    capsules = np.concatenate([rng.normal(0, 0.6, (4, 6)), rng.uniform(0.02, 0.2, (4, 1))], axis=1)
    V, F = np.array([[-0.9, -0.7, 1.0], [0.8, -0.5, 1.2], [0.1, 0.9, 0.9]]), [[0, 1, 2]]
    layers = []
    fitted = window_of(cam, 0, spheres=spheres, capsules=capsules, points=V)
    for window in (fitted, (0, cam.height, 0, cam.width)):
        rays = cast_primitives(cam, 0, spheres=spheres, capsules=capsules, antialias=k, window=window)
        draw_cloth(rays, cam, 0, V, F, [[0, 0, 250]], first_id=9)
        layers.append(rays.layer())
    assert layers[0].coverage.sum() > 100 and not layers[0].coverage.all()
    for name in ("colour", "depth", "ids", "alpha"):
        np.testing.assert_array_equal(getattr(layers[0], name), getattr(layers[1], name))
