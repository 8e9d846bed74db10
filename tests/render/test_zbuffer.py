"""Tests for toonmotion.render.zbuffer: spheres and capsules ray-cast through a perspective camera.

The references here do not share the renderer's arithmetic: spheres are solved in the world with
the textbook quadratic on ``camera.rays``; capsules are checked by the distance from points to
their segment (a ray meets a capsule where that distance, convex along the ray, reaches r).
"""

import numpy as np
import pytest

from toonmotion.errors import SceneError
from toonmotion.proxy3d.camera import PerspectiveCamera, rotations
from toonmotion.render.zbuffer import GREY, Layer, render_primitives

# Discriminants (relative to |d|^2 r^2) or distances (relative to r) within this of a tangency are
# rounding's to decide: neither answer is wrong there.
TANGENT = 1e-9


def _pixels(cam):
    """Every pixel's centre ``(1, H * W, 2)``, rows then columns: ``(j, i)``."""
    i, j = np.mgrid[0:cam.height, 0:cam.width]
    return np.stack([j, i], axis=-1).reshape(1, -1, 2).astype(float)


def _rays(cam):
    """The camera's centre and every pixel's ray (unit depth), ``(H * W, 3)``; one-frame cameras."""
    return cam.centres[0], cam.rays(_pixels(cam))[0]


def _sphere_reference(cam, centre, r):
    """Per pixel: the nearest hit in front (depth), NaN where none, and the relative discriminant."""
    o, d = _rays(cam)
    oc = o - np.asarray(centre, float)
    A, B, C = np.sum(d * d, axis=1), d @ oc, oc @ oc - r * r
    disc = B * B - A * C
    s = np.sqrt(np.maximum(disc, 0))
    near, far = (-B - s) / A, (-B + s) / A
    depth = np.where(disc < 0, np.nan, np.where(near > 0, near, np.where(far > 0, far, np.nan)))
    shape = (cam.height, cam.width)
    return depth.reshape(shape), (disc / (A * r * r)).reshape(shape)


def _segment_distance(P, a, b):
    """Distance from points ``(..., 3)`` to the segment ab."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ab = b - a
    s = np.clip((P - a) @ ab / (ab @ ab), 0, 1) if ab @ ab > 0 else np.zeros(P.shape[:-1])
    return np.linalg.norm(P - a - s[..., None] * ab, axis=-1)


def _nearest_approach(cam, a, b, t_max=100.0):
    """Per pixel, the least distance from its ray (depths 0 to t_max) to the segment ab: a convex
    function of depth, minimised by golden-section search."""
    o, d = _rays(cam)
    lo, hi = np.zeros(len(d)), np.full(len(d), t_max)
    g = (np.sqrt(5) - 1) / 2

    def dist(t):
        return _segment_distance(o + t[:, None] * d, a, b)

    for _ in range(120):
        t1, t2 = hi - g * (hi - lo), lo + g * (hi - lo)
        nearer = dist(t1) < dist(t2)
        hi, lo = np.where(nearer, t2, hi), np.where(nearer, lo, t1)
    return dist((lo + hi) / 2).reshape(cam.height, cam.width)


def _surface_points(cam, layer):
    """The world points seen at the covered pixels, ``(n, 3)``, and the pixels' centres ``(n, 2)``."""
    px = _pixels(cam)[0].reshape(cam.height, cam.width, 2)[layer.coverage]
    return cam.at(px[None], layer.depth[layer.coverage][None])[0], px


def _camera_on(T, frame):
    """A one-frame camera with the extrinsics of ``T``'s frame ``frame``."""
    return PerspectiveCamera(T.focal, T.width, T.height, T.extrinsics[frame:frame + 1])


# 1. A sphere straight ahead.

@pytest.mark.parametrize("extrinsics", [[0, 0, 0, 0.2, 1.0, 6.0], [0.7, 0.3, -0.2, 3.1, 2.5, 4.0]])
def test_a_sphere_ahead_covers_exactly_the_pixels_whose_rays_meet_it(extrinsics):
    cam = PerspectiveCamera(400.0, 160, 120, [extrinsics])  # even sizes: pixel (60, 80)'s ray is the axis
    forward = rotations([extrinsics[:3]])[0][2]
    distance, r = 5.5, 0.83
    centre = cam.centres[0] + distance * forward
    layer = render_primitives(cam, 0, spheres=[[*centre, r]])
    assert layer.depth[60, 80] == pytest.approx(distance - r, abs=1e-9)

    reference, disc = _sphere_reference(cam, centre, r)
    clear = np.abs(disc) > TANGENT
    assert np.count_nonzero(~clear) <= 2
    np.testing.assert_array_equal(layer.coverage[clear], np.isfinite(reference)[clear])
    assert 0.05 < layer.coverage.mean() < 0.9  # the test sees a silhouette, not all or nothing
    covered = layer.coverage & clear
    np.testing.assert_allclose(layer.depth[covered], reference[covered], rtol=0, atol=1e-9)
    assert np.all(layer.ids[layer.coverage] == 0)


def test_a_sphere_across_the_image_border_is_clipped_not_lost():
    cam = PerspectiveCamera(300.0, 120, 90, [[0, 0, 0, 0, 0, 5]])
    centre, r = [-1.1, 0.35, 0.2], 0.5  # its silhouette crosses the left and top edges
    layer = render_primitives(cam, 0, spheres=[[*centre, r]])
    reference, disc = _sphere_reference(cam, centre, r)
    clear = np.abs(disc) > TANGENT
    np.testing.assert_array_equal(layer.coverage[clear], np.isfinite(reference)[clear])
    assert layer.coverage[:, 0].any() and layer.coverage[0].any()


def test_each_frame_is_rendered_from_that_frame_s_camera():
    cam = PerspectiveCamera(250.0, 64, 48, [[0, 0, 0, 0, 1, 5], [0.4, 0.1, 0.05, 1.5, 1.3, 4.0]])
    spheres, capsules = [[0.2, 1.1, 0.0, 0.6]], [[-0.8, 0.5, 0.3, 0.9, 1.6, -0.4, 0.15]]
    for frame in (0, 1):
        layer = render_primitives(cam, frame, spheres=spheres, capsules=capsules)
        alone = render_primitives(_camera_on(cam, frame), 0, spheres=spheres, capsules=capsules)
        np.testing.assert_array_equal(layer.depth, alone.depth)
        np.testing.assert_array_equal(layer.colour, alone.colour)
    assert not np.array_equal(render_primitives(cam, 0, spheres=spheres).coverage,
                              render_primitives(cam, 1, spheres=spheres).coverage)


# 2. Nearest wins, whatever the order.

def test_where_two_spheres_overlap_the_nearer_is_seen_in_either_order():
    cam = PerspectiveCamera(300.0, 120, 90, [[0.1, -0.05, 0, 0, 1, 5]])
    near, far = [0.15, 1.1, 1.5, 0.4], [-0.3, 0.9, -1.0, 0.9]
    colours = np.array([[200, 40, 40], [40, 40, 200]], np.uint8)
    layer = render_primitives(cam, 0, spheres=[near, far], colours=colours, shading="flat")
    each = [render_primitives(cam, 0, spheres=[s]).coverage for s in (near, far)]
    both = each[0] & each[1]
    assert both.sum() > 200
    assert np.all(layer.ids[both] == 0)
    assert np.all(layer.ids[each[1] & ~each[0]] == 1)
    np.testing.assert_array_equal(layer.coverage, each[0] | each[1])

    swapped = render_primitives(cam, 0, spheres=[far, near], colours=colours[::-1], shading="flat")
    np.testing.assert_array_equal(swapped.depth, layer.depth)
    np.testing.assert_array_equal(swapped.colour, layer.colour)
    np.testing.assert_array_equal(swapped.ids, np.where(layer.coverage, 1 - layer.ids, -1))


@pytest.mark.parametrize("capsule_in_front", [True, False])
def test_spheres_and_capsules_are_depth_tested_against_each_other(capsule_in_front):
    cam = PerspectiveCamera(300.0, 120, 90, [[0, 0, 0, 0, 1, 5]])
    z_capsule, z_sphere = (1.0, -1.0) if capsule_in_front else (-1.0, 1.0)
    sphere = [0.0, 1.0, z_sphere, 0.5]
    capsule = [-1.0, 1.0, z_capsule, 1.0, 1.1, z_capsule, 0.15]
    layer = render_primitives(cam, 0, spheres=[sphere], capsules=[capsule])
    both = (render_primitives(cam, 0, spheres=[sphere]).coverage
            & render_primitives(cam, 0, capsules=[capsule]).coverage)
    assert both.sum() > 100
    assert np.all(layer.ids[both] == (1 if capsule_in_front else 0))


# 3. Capsules.

def test_a_capsule_seen_from_the_side_covers_its_segment_and_caps():
    cam = PerspectiveCamera(350.0, 160, 120, [[0, 0, 0, 0, 0, 5]])
    a, b, r = np.array([-0.8, 0.0, 0.0]), np.array([0.9, 0.0, 0.0]), 0.2
    layer = render_primitives(cam, 0, capsules=[[*a, *b, r]])

    # Row 60's rays have y = 0 and cross the axis: there the hit is r nearer than the axis.
    on_axis = layer.coverage[60]
    x = (np.arange(160) - 80.0) / 350.0
    between_ends = (x * 5 > a[0]) & (x * 5 < b[0])
    assert np.all(on_axis[between_ends])
    np.testing.assert_allclose(layer.depth[60][between_ends], 5 - r, rtol=0, atol=1e-9)

    # The caps: the ends' pixels are covered, and the rounded ends reach r beyond them, no further.
    ends = cam.project([[a, b, a - [r + 0.02, 0, 0], b + [r + 0.02, 0, 0]]])[0]
    seen = [bool(layer.coverage[round(v), round(u)]) for u, v in ends]
    assert seen == [True, True, False, False]
    nearest = _nearest_approach(cam, a, b)
    clear = np.abs(nearest - r) > TANGENT * r
    np.testing.assert_array_equal(layer.coverage[clear], (nearest < r)[clear])


def test_a_slanted_capsule_s_depth_where_a_ray_crosses_its_axis():
    cam = PerspectiveCamera(420.0, 200, 150, [[0.3, 0.2, 0.1, 0.5, 1.5, 4.0]])
    i, j, D, r = 61, 117, 4.3, 0.12
    ray = cam.rays([[[j, i]]])[0, 0]
    P = cam.centres[0] + D * ray  # an axis point on pixel (i, j)'s ray, at depth D
    u = np.array([0.6, -0.3, 0.74])
    u /= np.linalg.norm(u)
    a, b = P - 0.7 * u, P + 0.9 * u
    layer = render_primitives(cam, 0, capsules=[[*a, *b, r]])
    # Across the axis the ray closes in at |d x u| per unit depth, so it meets the side r / |d x u| early.
    assert layer.depth[i, j] == pytest.approx(D - r / np.linalg.norm(np.cross(ray, u)), abs=1e-9)

    nearest = _nearest_approach(cam, a, b)
    clear = np.abs(nearest - r) > TANGENT * r
    np.testing.assert_array_equal(layer.coverage[clear], (nearest < r)[clear])


def test_a_capsule_whose_ends_coincide_renders_exactly_as_the_sphere():
    cam = PerspectiveCamera(300.0, 97, 71, [[0.2, -0.1, 0.3, 0.4, 1.2, 4.5]])
    centre, r = [0.1, 1.0, -0.3], 0.45
    for shading in ("flat", "smooth", "toon"):
        sphere = render_primitives(cam, 0, spheres=[[*centre, r]], shading=shading)
        capsule = render_primitives(cam, 0, capsules=[[*centre, *centre, r]], shading=shading)
        for name in ("colour", "depth", "coverage", "ids"):
            np.testing.assert_array_equal(getattr(capsule, name), getattr(sphere, name))
        assert sphere.coverage.sum() > 100


def test_a_capsule_seen_end_on_shows_its_nearer_cap():
    # The axis runs along the camera's axis (the centre pixel's ray runs down it), far end listed first.
    cam = PerspectiveCamera(200.0, 40, 30, [[0, 0, 0, 0, 0, 5]])
    r = 0.3
    layer = render_primitives(cam, 0, capsules=[[0, 0, -2.0, 0, 0, 1.0, r]])
    assert layer.depth[15, 20] == pytest.approx(5 - 1.0 - r, abs=1e-12)
    points, _ = _surface_points(cam, layer)
    np.testing.assert_allclose(_segment_distance(points, [0, 0, -2.0], [0, 0, 1.0]), r, atol=1e-9)
    assert np.all(points[:, 2] > 1.0 - 1e-9)  # all on the near cap


# 4. Behind the camera.

def test_primitives_behind_the_camera_are_not_seen():
    cam = PerspectiveCamera(300.0, 80, 60, [[0, 0, 0, 0, 0, 0]])  # looks along -Z from the origin
    layer = render_primitives(cam, 0, spheres=[[0, 0, 3.0, 1.0], [0.5, 0.2, 1.2, 1.0]],
                              capsules=[[-1, 0, 2, 1, 0.3, 4, 0.5]])
    assert not layer.coverage.any()
    assert np.all(np.isinf(layer.depth)) and np.all(layer.ids == -1) and not layer.colour.any()


def test_a_sphere_cut_by_the_camera_s_plane_shows_only_its_front():
    cam = PerspectiveCamera(60.0, 120, 90, [[0, 0, 0, 0, 0, 0]])  # wide: the front part is off to the side
    centre, r = [1.2, 0.0, 0.3], 1.15  # the camera is just outside it; it reaches both sides of the camera
    layer = render_primitives(cam, 0, spheres=[[*centre, r]])
    reference, disc = _sphere_reference(cam, centre, r)
    clear = np.abs(disc) > TANGENT
    np.testing.assert_array_equal(layer.coverage[clear], np.isfinite(reference)[clear])
    assert layer.coverage.any() and not layer.coverage.all()
    covered = layer.coverage & clear
    np.testing.assert_allclose(layer.depth[covered], reference[covered], rtol=0, atol=1e-9)
    assert np.all(layer.depth[layer.coverage] > 0)


def test_a_capsule_cut_by_the_camera_s_plane_shows_only_its_front():
    cam = PerspectiveCamera(300.0, 120, 90, [[0, 0, 0, 0, 0, 0]])
    a, b, r = [1.0, -0.2, 2.0], [0.3, 0.25, -3.0], 0.25  # from behind the camera to 3 m ahead
    layer = render_primitives(cam, 0, capsules=[[*a, *b, r]])
    assert layer.coverage.any() and not layer.coverage.all()
    nearest = _nearest_approach(cam, a, b)
    clear = np.abs(nearest - r) > TANGENT * r
    np.testing.assert_array_equal(layer.coverage[clear], (nearest < r)[clear])
    points, _ = _surface_points(cam, layer)
    np.testing.assert_allclose(_segment_distance(points, a, b), r, rtol=0, atol=1e-9)
    assert np.all(layer.depth[layer.coverage] > 0)


@pytest.mark.parametrize("kind", ["sphere", "capsule"])
def test_a_camera_inside_a_primitive_sees_its_inside_everywhere(kind):
    cam = PerspectiveCamera(200.0, 60, 40, [[0.3, 0.1, 0, 0.1, 1.0, 0.2]])
    a, b, r = [0.0, 1.0, 0.0], [0.4, 1.1, -0.6], 0.5
    if kind == "sphere":
        layer = render_primitives(cam, 0, spheres=[[*a, r]])
    else:
        layer = render_primitives(cam, 0, capsules=[[*a, *b, r]])
    assert layer.coverage.all()
    points, _ = _surface_points(cam, layer)
    np.testing.assert_allclose(_segment_distance(points, a, a if kind == "sphere" else b), r, atol=1e-9)


# 5. Depth is the camera's depth, on the surface, the first one along the ray.

def test_every_covered_pixel_s_depth_puts_it_on_its_primitive_s_surface():
    cam = PerspectiveCamera(380.0, 160, 120, [[0.25, 0.15, -0.1, 1.0, 1.6, 4.5]])
    spheres = np.array([[0.0, 1.0, 0.0, 0.5], [0.9, 1.4, -0.8, 0.35], [-0.6, 0.6, 0.4, 0.25]])
    capsules = np.array([[-1.0, 0.2, -0.5, 1.2, 1.9, 0.3, 0.12], [0.5, 0.0, 0.8, 0.4, 2.0, -1.0, 0.06],
                         [-0.2, 1.3, 1.5, 0.5, 1.8, 1.0, 0.1]])
    layer = render_primitives(cam, 0, spheres=spheres, capsules=capsules)
    points, px = _surface_points(cam, layer)
    ids = layer.ids[layer.coverage]
    ends = np.concatenate([np.repeat(spheres[:, :3], 2, axis=0).reshape(-1, 6), capsules[:, :6]])
    radii = np.concatenate([spheres[:, 3], capsules[:, 6]])
    assert set(ids.tolist()) == set(range(6))
    for k in range(6):
        mine = ids == k
        np.testing.assert_allclose(_segment_distance(points[mine], ends[k, :3], ends[k, 3:]), radii[k],
                                   rtol=0, atol=1e-9)
    # The depth is what camera.depth gives for the point seen.
    np.testing.assert_allclose(cam.depth(points[None])[0], layer.depth[layer.coverage], rtol=0, atol=1e-9)
    # And the first surface along the ray: a little nearer, the ray is outside every primitive.
    nearer = cam.at(px[None], layer.depth[layer.coverage][None] - 1e-6)[0]
    gaps = [_segment_distance(nearer, e[:3], e[3:]) - rad for e, rad in zip(ends, radii, strict=True)]
    assert np.all(np.min(gaps, axis=0) > 0)


# 6. Bad input.

@pytest.mark.parametrize(("kwargs", "match"), [
    (dict(spheres=[[0, 0, 0]]), r"spheres must be an array of shape \(S, 4\)"),
    (dict(spheres=[0, 0, 0, 1]), r"spheres must be an array of shape \(S, 4\)"),
    (dict(capsules=[[0, 0, 0, 1, 1, 1]]), r"capsules must be an array of shape \(C, 7\)"),
    (dict(spheres=[[0, 0, np.nan, 1]]), "non-finite"),
    (dict(capsules=[[0, 0, 0, 1, np.inf, 1, 0.1]]), "non-finite"),
    (dict(spheres=[["a", 0, 0, 1]]), "must hold numbers"),
    (dict(spheres=[[0, 0, 0, 1], [0, 0, 0, -0.5]]), "radii >= 0; number 1 has radius -0.5"),
    (dict(capsules=[[0, 0, 0, 1, 1, 1, -1]]), "radii >= 0"),
    (dict(spheres=[[0, 0, 0, 1]], shading="phong"), "shading must be one of flat, smooth, toon"),
    (dict(spheres=[[0, 0, 0, 1]], colours=[[1, 2, 3], [4, 5, 6]]), r"colours must be an \(S \+ C, 3\)"),
    (dict(spheres=[[0, 0, 0, 1]], colours=[[256, 0, 0]]), "whole numbers that fit uint8"),
    (dict(spheres=[[0, 0, 0, 1]], colours=[[0.5, 0, 0]]), "whole numbers that fit uint8"),
    (dict(light=[0, 0, 0]), "non-zero direction"),
    (dict(light=[0, 1]), "light must be a direction"),
])
def test_bad_input_is_refused_with_a_project_error(kwargs, match):
    cam = PerspectiveCamera(100.0, 20, 10, [[0, 0, 0, 0, 0, 5]])
    with pytest.raises(SceneError, match=match):
        render_primitives(cam, 0, **kwargs)


@pytest.mark.parametrize("frame", [-1, 2, 1.0, True, "0", None])
def test_a_frame_the_camera_does_not_have_is_refused(frame):
    cam = PerspectiveCamera(100.0, 20, 10, [[0, 0, 0, 0, 0, 5], [0, 0, 0, 0, 0, 4]])
    with pytest.raises(SceneError, match=r"frame must be a whole number from 0 to 1 \(the camera has 2"):
        render_primitives(cam, frame, spheres=[[0, 0, 0, 1]])
    assert render_primitives(cam, np.int64(1), spheres=[[0, 0, 0, 1]]).coverage.any()


# 7. Shading, and what nothing looks like.

def _two_balls_and_a_stick(shading, colours=None):
    cam = PerspectiveCamera(300.0, 120, 90, [[0, 0, 0, 0, 1, 5]])
    return render_primitives(cam, 0, spheres=[[-0.6, 1.0, 0, 0.5], [0.7, 1.2, -0.5, 0.5]],
                             capsules=[[-1.0, 0.3, 0.5, 1.0, 0.4, 0.5, 0.12]], colours=colours,
                             shading=shading)


def test_flat_shading_gives_each_primitive_its_colour_exactly():
    colours = np.array([[250, 10, 10], [10, 250, 10], [30, 60, 220]], np.uint8)
    layer = _two_balls_and_a_stick("flat", colours)
    for k in range(3):
        mine = layer.colour[layer.ids == k]
        assert len(mine) > 50
        assert np.all(mine == colours[k])
    default = _two_balls_and_a_stick("flat")
    assert np.all(default.colour[default.coverage] == GREY)


def test_toon_shading_gives_at_most_three_tones_per_primitive_lit_from_the_light():
    colours = np.array([[250, 10, 10], [10, 250, 10], [30, 60, 220]], np.uint8)
    layer = _two_balls_and_a_stick("toon", colours)
    for k in range(3):
        tones = np.unique(layer.colour[layer.ids == k], axis=0)
        assert 2 <= len(tones) <= 3
        assert np.all(tones <= colours[k])
    # The light comes from above (and the left): down a column through ball 0, top brighter than bottom.
    j = int(np.median(np.flatnonzero((layer.ids == 0).any(axis=0))))
    rows = np.flatnonzero(layer.ids[:, j] == 0)
    brightness = layer.colour[rows, j].astype(int).sum(axis=1)
    assert brightness[2] > brightness[-3]


def test_smooth_shading_stays_between_the_ambient_and_the_full_colour():
    colours = np.array([[250, 10, 10], [10, 250, 10], [30, 60, 220]], np.uint8)
    layer = _two_balls_and_a_stick("smooth", colours)
    for k in range(3):
        seen = layer.colour[layer.ids == k].astype(float)
        assert len(np.unique(seen, axis=0)) > 3
        assert np.all(seen <= colours[k]) and np.all(seen >= np.floor(0.35 * colours[k]))


@pytest.mark.parametrize("inside", [None, 0, 1])
def test_smooth_shading_is_lambert_with_ambient_on_the_normal_facing_the_camera(inside):
    # A ball and two sticks; the camera may be inside the ball or the first stick, made big.
    cam = PerspectiveCamera(200.0, 80, 60, [[0.3, 0.2, 0.1, 0.2, 1.1, 3.0]])
    ends = np.array([[0.0, 1.0, 0.0, 0.0, 1.0, 0.0], [-0.8, 0.4, 0.2, 0.9, 1.5, -0.3],
                     [0.5, 0.2, 0.6, 0.3, 1.6, -0.4]])
    radii = np.array([0.5, 0.12, 0.1])
    if inside is not None:
        radii[inside] = 3.5
    colours = np.array([[240, 200, 120], [90, 160, 250], [250, 250, 250]], np.uint8)
    light = np.array([-0.3, 0.9, 0.5])
    layer = render_primitives(cam, 0, spheres=[[*ends[0, :3], radii[0]]],
                              capsules=np.hstack([ends[1:], radii[1:, None]]), colours=colours,
                              shading="smooth", light=light)
    assert layer.coverage.all() == (inside is not None)
    points, _ = _surface_points(cam, layer)
    ids = layer.ids[layer.coverage]
    a, b = ends[ids, :3], ends[ids, 3:]
    ab = b - a
    along = np.clip(np.sum((points - a) * ab, axis=1) / np.maximum(np.sum(ab * ab, axis=1), 1e-300), 0, 1)
    n = (points - a - along[:, None] * ab) / radii[ids, None]
    n *= np.where(np.sum(n * (points - cam.centres[0]), axis=1) > 0, -1, 1)[:, None]  # facing the camera
    value = 0.35 + 0.65 * np.maximum(n @ (light / np.linalg.norm(light)), 0)
    expected = colours[ids] * value[:, None]
    assert np.all(np.abs(layer.colour[layer.coverage] - expected) <= 0.5 + 1e-6)


@pytest.mark.parametrize("shading", ["flat", "smooth", "toon"])
def test_where_nothing_is_seen_the_layer_is_black_infinitely_deep_and_unclaimed(shading):
    layer = _two_balls_and_a_stick(shading)
    assert isinstance(layer, Layer)
    H, W = 90, 120
    assert layer.colour.shape == (H, W, 3) and layer.colour.dtype == np.uint8
    assert layer.depth.shape == (H, W) and layer.depth.dtype == np.float64
    assert layer.coverage.dtype == bool and layer.ids.dtype == np.int32
    empty = ~layer.coverage
    assert 0 < empty.sum() < H * W
    assert not layer.colour[empty].any()
    assert np.all(np.isinf(layer.depth[empty])) and np.all(layer.ids[empty] == -1)
    assert np.all(np.isfinite(layer.depth[layer.coverage])) and np.all(layer.ids[layer.coverage] >= 0)
    assert not any(a.flags.writeable for a in (layer.colour, layer.depth, layer.coverage, layer.ids))


def test_no_primitives_or_zero_radii_render_an_empty_layer():
    cam = PerspectiveCamera(100.0, 20, 10, [[0, 0, 0, 0, 0, 5]])
    for kwargs in (dict(), dict(spheres=np.zeros((0, 4)), capsules=[]),
                   dict(spheres=[[0, 0, 0, 0]], capsules=[[0, 0, 0, 1, 0, 0, 0]])):
        layer = render_primitives(cam, 0, **kwargs)
        assert not layer.coverage.any() and np.all(layer.ids == -1)
