"""Tests for toonmotion.render.raster."""

import numpy as np
import pytest
from scipy.spatial import Delaunay

from toonmotion.errors import SettingsError
from toonmotion.render.raster import render_mesh, view_transform
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character

SQUARE_F = np.array([[0, 1, 2], [0, 2, 3]])


@pytest.fixture(scope="module")
def sample():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    return character.texture, character.mesh.V, character.mesh.F, character.mask


def _random_texture(h, w, seed=0):
    texture = np.random.default_rng(seed).integers(0, 256, (h, w, 4), dtype=np.uint8)
    texture[..., 3] = np.maximum(texture[..., 3], 1)  # every texel visible
    return texture


def _square(x0, y0, x1, y1):
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def _coverage(U, F, shape, *, strict):
    """Pixel centres inside (strictly, or within 1e-9) at least one triangle, by brute force."""
    h, w = shape
    inside = np.zeros((h, w), bool)
    for a, b, c in U[F]:
        d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        lo = np.maximum(np.floor(np.minimum(np.minimum(a, b), c)), 0).astype(int)
        hi = np.minimum(np.ceil(np.maximum(np.maximum(a, b), c)), [w - 1, h - 1]).astype(int)
        if d == 0 or np.any(hi < lo):
            continue
        ys, xs = np.mgrid[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1].astype(float)
        # Edge functions over |d|: positive inside for either winding, in units of pixels.
        e = [((q[0] - o[0]) * (ys - o[1]) - (q[1] - o[1]) * (xs - o[0])) * np.sign(d) / np.sqrt(abs(d))
             for o, q in ((a, b), (b, c), (c, a))]
        ok = np.all(np.stack(e) > (1e-9 if strict else -1e-9), axis=0)
        inside[lo[1]:hi[1] + 1, lo[0]:hi[0] + 1] |= ok
    return inside


# --- view_transform ------------------------------------------------------------------------


def test_view_transform_is_identity_for_the_canvas():
    scale, offset = view_transform((-0.5, -0.5, 31.5, 19.5), (32, 20))
    assert scale == 1.0
    assert np.array_equal(offset, [0.0, 0.0])


def test_view_transform_fits_centres_and_letterboxes():
    view = (10.0, 20.0, 30.0, 30.0)  # 20 x 10 drawing pixels into a 100 x 100 output
    scale, offset = view_transform(view, (100, 100))
    assert scale == pytest.approx(5.0)
    corners = np.array([[10.0, 20.0], [30.0, 30.0]]) * scale + offset
    # The view's edges are pixel edges: x spans [-0.5, 99.5], y is centred in [24.5, 74.5].
    assert np.allclose(corners, [[-0.5, 24.5], [99.5, 74.5]])


@pytest.mark.parametrize(
    "view, size, match",
    [
        ((0, 0, 0, 5), (10, 10), "x1 > x0"),
        ((0, 0, 5, np.nan), (10, 10), "finite"),
        ((0, 0, 5), (10, 10), "view must be"),
        ((0, 0, 5, 5), (0, 10), "positive integers"),
        ((0, 0, 5, 5), (10.5, 10), "positive integers"),
        ((0, 0, 5, 5), (10,), "size must be"),
    ],
)
def test_view_transform_rejects_bad_input(view, size, match):
    with pytest.raises(SettingsError, match=match):
        view_transform(view, size)


# --- exactness and coverage ----------------------------------------------------------------


def test_two_triangle_square_reproduces_the_texture_exactly():
    h, w = 9, 13
    texture = _random_texture(h, w)
    texture[4, 6] = 0  # a fully transparent texel stays (0, 0, 0, 0)
    V = _square(-0.5, -0.5, w - 0.5, h - 0.5)
    out = render_mesh(texture, V, V, SQUARE_F, size=(w, h))
    assert out.dtype == np.uint8 and out.shape == (h, w, 4)
    assert np.array_equal(out, texture)


def test_sample_character_identity_is_bit_exact_inside_the_mesh(sample):
    texture, V, F, _ = sample
    h, w = texture.shape[:2]
    out = render_mesh(texture, V, V, F, size=(w, h))
    inside = _coverage(V, F, (h, w), strict=True)
    assert inside.sum() > 100_000
    assert np.array_equal(out[inside], texture[inside])
    outside = ~_coverage(V, F, (h, w), strict=False)
    assert not out[outside].any()


def test_shared_edges_through_pixel_centres_leave_no_cracks():
    # Vertices on pixel centres: many centres lie exactly on shared and outer edges.
    xs, ys = np.meshgrid(np.arange(2, 23, 4.0), np.arange(3, 20, 4.0))
    V = np.stack([xs.ravel(), ys.ravel()], axis=1)
    F = Delaunay(V).simplices
    texture = _random_texture(24, 26, seed=1)
    out = render_mesh(texture, V, V, F, size=(26, 24))
    covered = out[..., 3] > 0
    inner = np.zeros_like(covered)
    inner[4:19, 3:22] = True  # centres strictly inside the hull [2, 22] x [3, 19]
    assert covered[inner].all()
    assert not covered[~_coverage(V, F, (24, 26), strict=False)].any()
    assert np.array_equal(out[covered], texture[covered])


def test_irregular_mesh_covers_every_centre_of_its_rectangle():
    rng = np.random.default_rng(3)
    corners = _square(3.3, 2.7, 57.6, 41.2)
    interior = rng.uniform([3.3, 2.7], [57.6, 41.2], (150, 2))
    edges = np.concatenate([np.linspace(corners[i], corners[(i + 1) % 4], 9)[1:-1] for i in range(4)])
    V = np.concatenate([corners, edges, interior])
    F = Delaunay(V).simplices
    U = V * 1.7 + [5.25, 3.5]  # not axis-aligned with the pixel grid either
    texture = _random_texture(45, 60)
    out = render_mesh(texture, V, U, F, size=(110, 80), view=(-0.5, -0.5, 109.5, 79.5))
    covered = out[..., 3] > 0
    assert covered[_coverage(U, F, (80, 110), strict=True)].all()
    assert not covered[~_coverage(U, F, (80, 110), strict=False)].any()


def test_integer_translation_shifts_the_image_exactly(sample):
    texture, V, F, _ = sample
    h, w = texture.shape[:2]
    still = render_mesh(texture, V, V, F, size=(w, h))
    moved = render_mesh(texture, V, V + [7.0, -5.0], F, size=(w, h))
    assert np.array_equal(moved[: h - 5, 7:], still[5:, : w - 7])


def test_doubling_the_scale_quadruples_the_covered_area(sample):
    texture, V, F, _ = sample
    h, w = texture.shape[:2]
    opaque = texture.copy()
    opaque[..., 3] = 255
    one = (render_mesh(opaque, V, V, F, size=(w, h))[..., 3] > 0).sum()
    # The same view into an output twice as large: scale 2.
    two = (render_mesh(opaque, V, V, F, size=(2 * w, 2 * h))[..., 3] > 0).sum()
    assert two / one == pytest.approx(4.0, rel=0.02)
    # A view half the canvas wide around the middle, into the original size: also scale 2.
    view = (w / 4 - 0.5, h / 4 - 0.5, 3 * w / 4 - 0.5, 3 * h / 4 - 0.5)
    zoomed = render_mesh(opaque, V, V, F, size=(w, h), view=view)
    inner = render_mesh(opaque, V, V, F, size=(w, h))[h // 4: 3 * h // 4, w // 4: 3 * w // 4]
    assert (zoomed[..., 3] > 0).sum() / (inner[..., 3] > 0).sum() == pytest.approx(4.0, rel=0.03)


def test_mirrored_mesh_inverts_triangles_and_still_draws_them(sample):
    texture, V, F, _ = sample
    h, w = texture.shape[:2]
    U = np.column_stack([(w - 1) - V[:, 0], V[:, 1]])
    straight = render_mesh(texture, V, V, F, size=(w, h))
    mirrored = render_mesh(texture, V, U, F, size=(w, h))[:, ::-1]
    both = (straight[..., 3] > 0) & (mirrored[..., 3] > 0)
    assert np.array_equal(straight[both], mirrored[both])
    assert abs(int((mirrored[..., 3] > 0).sum()) - int((straight[..., 3] > 0).sum())) < 0.005 * both.sum()


def test_degenerate_triangles_are_skipped():
    texture = _random_texture(10, 10)
    V = np.concatenate([_square(-0.5, -0.5, 9.5, 9.5), [[4.0, 4.0]]])
    F = np.concatenate([SQUARE_F, [[0, 4, 4], [1, 3, 4]]])
    U = V.copy()
    U[4] = (U[1] + U[3]) / 2  # triangle 3 collapses onto the diagonal; triangle 2 has a repeated vertex
    out = render_mesh(texture, V, U, F, size=(10, 10))
    assert np.array_equal(out, render_mesh(texture, V, V, SQUARE_F, size=(10, 10)))


def test_vertices_absurdly_far_away_skip_their_triangles():
    texture = _random_texture(10, 10)
    V = np.concatenate([_square(-0.5, -0.5, 9.5, 9.5), [[5.0, 5.0]]])
    F = np.concatenate([SQUARE_F, [[0, 1, 4]]])
    U = V.copy()
    U[4] = (1e30, -1e30)  # only the extra triangle uses it
    assert np.array_equal(render_mesh(texture, V, U, F, size=(10, 10)), texture)
    U[1] = (1e30, 1e30)  # now the first triangle too
    expected = render_mesh(texture, V, V, SQUARE_F[1:], size=(10, 10))
    assert np.array_equal(render_mesh(texture, V, U, F, size=(10, 10)), expected)


# --- draw order, background, mask ------------------------------------------------------------


def _two_colour_triangles():
    """Two rest triangles, one on a red half and one on a blue half, deformed onto one place."""
    texture = np.zeros((20, 40, 4), np.uint8)
    texture[:, :20] = (255, 0, 0, 255)
    texture[:, 20:] = (0, 0, 255, 255)
    V = np.array([[2, 2], [17, 2], [2, 17], [22, 2], [37, 2], [22, 17]], float)
    U = np.array([[5, 5], [30, 5], [5, 15], [10, 3], [30, 12], [10, 17]], float)
    return texture, V, U, np.array([[0, 1, 2], [3, 4, 5]])


def test_later_triangles_in_order_are_drawn_on_top():
    texture, V, U, F = _two_colour_triangles()
    on_top_blue = render_mesh(texture, V, U, F, size=(40, 20), order=[0, 1])
    on_top_red = render_mesh(texture, V, U, F, size=(40, 20), order=[1, 0])
    assert tuple(on_top_blue[8, 12]) == (0, 0, 255, 255)
    assert tuple(on_top_red[8, 12]) == (255, 0, 0, 255)
    # Away from the overlap each triangle shows its own colour whatever the order.
    for out in (on_top_blue, on_top_red):
        assert tuple(out[13, 6]) == (255, 0, 0, 255)
        assert tuple(out[4, 28]) == (0, 0, 0, 0)
        assert tuple(out[16, 10]) == (0, 0, 255, 255)


def test_overlap_resolution_matches_painting_triangles_one_by_one():
    rng = np.random.default_rng(5)
    V = rng.uniform(0, 40, (40, 2))
    F = Delaunay(V).simplices
    U = V + rng.normal(0, 4.0, V.shape)  # folds: many overlapping triangles
    order = rng.permutation(len(F))
    texture = _random_texture(40, 40)
    out = render_mesh(texture, V, U, F, size=(40, 40), order=order)
    painted = np.zeros_like(out)
    overdrawn = 0
    for k in order:
        one = render_mesh(texture, V, U, F[k:k + 1], size=(40, 40))
        drawn = _coverage(U, F[k:k + 1], (40, 40), strict=True)
        overdrawn += int((drawn & (painted[..., 3] > 0)).sum())
        painted[drawn] = one[drawn]
    assert overdrawn > 100
    decided = _coverage(U, F, (40, 40), strict=True)
    assert decided.sum() > 800
    # A pixel centre exactly on an edge may go to either neighbour; none lies on one here.
    assert np.array_equal(out[decided], painted[decided])


def test_background_is_composited_under_the_figure():
    texture = np.zeros((10, 10, 4), np.uint8)
    texture[..., :3] = (200, 100, 0)
    texture[:, :5, 3] = 255
    texture[:, 5:, 3] = 128
    V = _square(1.5, 1.5, 7.5, 7.5)
    clear = render_mesh(texture, V, V, SQUARE_F, size=(10, 10))
    assert not clear[0].any() and not clear[:, 9].any()
    assert np.array_equal(clear[2:8, 2:8], texture[2:8, 2:8])
    white = render_mesh(texture, V, V, SQUARE_F, size=(10, 10), background=(255, 255, 255))
    assert np.all(white[..., 3] == 255)
    assert tuple(white[0, 0]) == (255, 255, 255, 255)
    assert tuple(white[4, 3]) == (200, 100, 0, 255)
    # Half-transparent texel over white: halfway between.
    assert np.allclose(white[4, 6, :3], [227, 177, 127], atol=1)
    tinted = render_mesh(texture, V, V, SQUARE_F, size=(10, 10), background=(0, 0, 255, 100))
    assert tuple(tinted[0, 0]) == (0, 0, 255, 100)
    assert tuple(tinted[4, 3]) == (200, 100, 0, 255)
    assert tinted[4, 6, 3] == round(255 * (128 / 255 + 100 / 255 * (1 - 128 / 255)))


def test_mask_multiplies_the_alpha(sample):
    texture, V, F, mask = sample
    h, w = texture.shape[:2]
    plain = render_mesh(texture, V, V, F, size=(w, h))
    masked = render_mesh(texture, V, V, F, size=(w, h), mask=mask)
    assert np.array_equal(masked[mask], plain[mask])
    assert not masked[~mask, 3].any()
    half = render_mesh(texture, V, V, F, size=(w, h), mask=np.full((h, w), 0.5))
    visible = plain[..., 3] > 100
    assert np.allclose(half[visible, 3], plain[visible, 3] / 2, atol=1)
    assert np.abs(half[visible, :3].astype(int) - plain[visible, :3]).max() <= 2


def test_scaled_up_edges_are_soft_and_not_darkened():
    # An opaque white square on transparent black: bilinear edges must fade in alpha only.
    texture = np.zeros((10, 10, 4), np.uint8)
    texture[3:7, 3:7] = 255
    V = _square(-0.5, -0.5, 9.5, 9.5)
    out = render_mesh(texture, V, V, SQUARE_F, size=(80, 80))
    partial = (out[..., 3] > 0) & (out[..., 3] < 255)
    assert partial.any()
    assert np.all(out[partial, :3] == 255)


def test_input_arrays_are_not_modified(sample):
    texture, V, F, mask = sample
    copies = [a.copy() for a in (texture, V, F, mask)]
    render_mesh(texture, V, V + 1.0, F, size=(100, 120), mask=mask, background=(1, 2, 3))
    assert all(np.array_equal(a, b) for a, b in zip((texture, V, F, mask), copies, strict=True))


def test_mesh_entirely_outside_the_view_gives_background():
    texture = _random_texture(10, 10)
    V = _square(-0.5, -0.5, 9.5, 9.5)
    out = render_mesh(texture, V, V + 100.0, SQUARE_F, size=(10, 10), background=(9, 8, 7))
    assert np.all(out == (9, 8, 7, 255))


# --- validation ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(texture=np.zeros((10, 10, 3), np.uint8)), "texture must be"),
        (dict(texture=np.zeros((10, 10, 4), np.float32)), "texture must be"),
        (dict(U=np.zeros((3, 2))), "one position per vertex"),
        (dict(U=np.full((4, 2), np.nan)), "NaN"),
        (dict(V=np.zeros((4, 3)), U=np.zeros((4, 3))), r"shape \(n, 2\)"),
        (dict(F=np.array([[0, 1, 4]])), "index vertices"),
        (dict(F=np.array([[0.0, 1.0, 2.0]])), "integer"),
        (dict(size=(0, 10)), "positive integers"),
        (dict(size=(10.0, 10)), "positive integers"),
        (dict(order=[0, 0]), "permutation"),
        (dict(order=[0]), "permutation"),
        (dict(view=(0, 0, -1, 5)), "x1 > x0"),
        (dict(background=(255, 255)), "background"),
        (dict(background=(0, 0, 300)), "background"),
        (dict(mask=np.ones((5, 5), bool)), "mask has shape"),
        (dict(mask=np.full((10, 10), 2.0)), r"\[0, 1\]"),
    ],
)
def test_bad_input_is_a_settings_error(change, match):
    args = dict(texture=_random_texture(10, 10), V=_square(-0.5, -0.5, 9.5, 9.5), F=SQUARE_F)
    args["U"] = args["V"]
    options = dict(size=(10, 10))
    for name, value in change.items():
        (args if name in ("texture", "V", "U", "F") else options)[name] = value
    with pytest.raises(SettingsError, match=match):
        render_mesh(args["texture"], args["V"], args["U"], args["F"], **options)
