"""Tests for toonmotion.shape.mesh."""

from functools import lru_cache

import numpy as np
import pytest
import shapely
import yaml
from PIL import Image

from toonmotion.errors import MeshError, SettingsError
from toonmotion.geometry.polygon import signed_area, triangle_areas, triangle_min_angles
from toonmotion.shape.mesh import Mesh, check_mesh, triangulate, unique_edges
from toonmotion.shape.silhouette import Silhouette, trace_silhouette

# Synthetic shapes -------------------------------------------------------------------------


def _disk_mask(shape, center, radius):
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    return np.hypot(xx - center[0], yy - center[1]) <= radius


def _disk():
    return _disk_mask((100, 100), (50, 50), 40)


def _annulus():
    return _disk() & ~_disk_mask((100, 100), (47, 52), 18)


def _thin_u():
    """A U with 6 px arms 70 px tall and a 2 px gap between them."""
    mask = np.zeros((90, 30), bool)
    mask[8:80, 8:14] = True  # left arm, columns 8-13
    mask[8:80, 16:22] = True  # right arm, columns 16-21: the gap is columns 14-15
    mask[74:80, 8:22] = True  # the bottom joins them
    return mask


def _two_parts():
    mask = _disk_mask((80, 140), (35, 40), 25)
    mask[15:65, 80:130] = True
    return mask


SHAPES = {"disk": _disk, "annulus": _annulus, "thin-u": _thin_u, "two-parts": _two_parts}
# "vertices=1500", or a coarse spacing in pixels: about a tenth of the shape's width.
SYNTHETIC_SETTINGS = {"disk": 8.0, "annulus": 8.0, "thin-u": 4.0, "two-parts": 6.0}


@lru_cache
def _synthetic_silhouette(name):
    return trace_silhouette(SHAPES[name]())


@lru_cache
def _synthetic_mesh(name, setting):
    s = _synthetic_silhouette(name)
    if setting == "vertices=1500":
        return triangulate(s, vertices=1500)
    return triangulate(s, spacing=SYNTHETIC_SETTINGS[name])


# Real drawings ----------------------------------------------------------------------------


def _drawing_mask(folder):
    return np.asarray(Image.open(folder / "mask.png").convert("L")) >= 128


@lru_cache
def _drawing_silhouette(folder):
    return trace_silhouette(_drawing_mask(folder))


@lru_cache
def _drawing_mesh(folder, setting):
    s = _drawing_silhouette(folder)
    fine = triangulate(s, vertices=1500)
    if setting == "vertices=1500":
        return fine
    # Coarse: twice the spacing of the 1,500-vertex mesh, about 500 vertices.
    return triangulate(s, spacing=2.0 * fine.spacing)


def _joints(folder, names):
    cfg = yaml.safe_load((folder / "char_cfg.yaml").read_text())
    return np.array([j["loc"] for j in cfg["skeleton"] if j["name"] in names], float)


# Properties every mesh must have ------------------------------------------------------------


def _is_sound(mesh, silhouette):
    assert check_mesh(mesh) == []
    assert mesh.F.dtype.kind == "i" and mesh.F.min() >= 0 and mesh.F.max() < len(mesh.V)


def _lies_inside(mesh, silhouette):
    region = silhouette.to_shapely().buffer(1e-6)
    triangles = shapely.polygons(mesh.V[mesh.F])
    outside = ~shapely.covers(region, triangles)
    assert not outside.any(), f"{outside.sum()} triangles stick out of the silhouette"


def _covers_area(mesh, silhouette):
    area = triangle_areas(mesh.V, mesh.F)
    assert np.all(area > 0)
    assert area.sum() == pytest.approx(silhouette.area, rel=1e-6)


def _boundary_is_outline(mesh, silhouette):
    assert len(mesh.boundary) == len(silhouette.loops)
    # Outline vertices come first, loop after loop.
    np.testing.assert_array_equal(np.concatenate(mesh.boundary), np.arange(mesh.n_outline))
    edges = {tuple(e) for e in unique_edges(mesh.F)}
    outer = [k == 0 for p in silhouette.parts for k in range(len(p.loops))]
    for loop, original, is_outer in zip(mesh.boundary, silhouette.loops, outer, strict=True):
        P = mesh.V[loop]
        # Each loop edge is a mesh edge.
        for a, b in zip(loop, np.roll(loop, -1), strict=True):
            assert (min(a, b), max(a, b)) in edges
        # Outer loops counter-clockwise, holes clockwise, as in the silhouette.
        assert (signed_area(P) > 0) == is_outer
        assert signed_area(P) == pytest.approx(signed_area(original), rel=1e-9)
        # The loop is the silhouette's loop: its vertices in cyclic order, plus points on it.
        ring = shapely.LinearRing(original)
        assert shapely.distance(ring, shapely.points(P)).max() < 1e-9
        at = [int(np.flatnonzero(np.all(P == v, axis=1))[0]) for v in original]
        assert np.count_nonzero(np.diff(at) < 0) <= 1, "silhouette vertices out of order"
    # Every mesh edge used by one triangle is a loop edge (check_mesh counts the converse).
    E = np.sort(np.concatenate([mesh.F[:, [0, 1]], mesh.F[:, [1, 2]], mesh.F[:, [2, 0]]]), axis=1)
    unique, uses = np.unique(E, axis=0, return_counts=True)
    loop_edges = {
        (min(a, b), max(a, b))
        for loop in mesh.boundary
        for a, b in zip(loop, np.roll(loop, -1), strict=True)
    }
    assert {tuple(e) for e in unique[uses == 1]} == loop_edges


PROPERTIES = [_is_sound, _lies_inside, _covers_area, _boundary_is_outline]
PROPERTY_IDS = ["sound", "inside", "area", "boundary"]


@pytest.mark.parametrize("prop", PROPERTIES, ids=PROPERTY_IDS)
@pytest.mark.parametrize("setting", ["vertices=1500", "coarse"])
@pytest.mark.parametrize("shape", list(SHAPES))
def test_synthetic_mesh(shape, setting, prop):
    prop(_synthetic_mesh(shape, setting), _synthetic_silhouette(shape))


@pytest.mark.parametrize("prop", PROPERTIES, ids=PROPERTY_IDS)
@pytest.mark.parametrize("setting", ["vertices=1500", "coarse"])
def test_drawing_mesh(drawing_dir, setting, prop):
    prop(_drawing_mesh(drawing_dir, setting), _drawing_silhouette(drawing_dir))


@pytest.mark.parametrize("prop", PROPERTIES, ids=PROPERTY_IDS)
def test_drawing_mesh_refined_at_joints(drawing_dir, prop):
    joints = _joints(drawing_dir, {"left_elbow", "right_elbow", "left_knee", "right_knee"})
    s = _drawing_silhouette(drawing_dir)
    prop(triangulate(s, vertices=1500, refine_points=joints), s)


# Sampling -------------------------------------------------------------------------------------


def _median_edge(mesh):
    E = mesh.edges
    return float(np.median(np.linalg.norm(mesh.V[E[:, 0]] - mesh.V[E[:, 1]], axis=1)))


@pytest.mark.parametrize("target", [300, 800, 1500])
@pytest.mark.parametrize("shape", ["disk", "annulus", "two-parts"])
def test_vertex_count_is_close_to_target(shape, target):
    mesh = triangulate(_synthetic_silhouette(shape), vertices=target)
    assert abs(len(mesh.V) - target) <= 0.1 * target


def test_drawing_vertex_count_is_close_to_target(drawing_dir):
    assert abs(len(_drawing_mesh(drawing_dir, "vertices=1500").V) - 1500) <= 150


def test_default_is_about_1500_vertices():
    mesh = triangulate(_synthetic_silhouette("disk"))
    assert abs(len(mesh.V) - 1500) <= 150


@pytest.mark.parametrize("spacing", [2.0, 4.0, 8.0])
@pytest.mark.parametrize("shape", ["disk", "annulus", "two-parts"])
def test_median_edge_length_is_close_to_spacing(shape, spacing):
    mesh = triangulate(_synthetic_silhouette(shape), spacing=spacing)
    assert mesh.spacing == spacing
    assert _median_edge(mesh) == pytest.approx(spacing, rel=0.25)


@pytest.mark.parametrize("setting", ["vertices=1500", "coarse"])
def test_drawing_median_edge_length_is_close_to_spacing(drawing_dir, setting):
    mesh = _drawing_mesh(drawing_dir, setting)
    assert _median_edge(mesh) == pytest.approx(mesh.spacing, rel=0.25)


def test_outline_edges_are_no_longer_than_spacing(drawing_dir):
    mesh = _drawing_mesh(drawing_dir, "coarse")
    for loop in mesh.boundary:
        P = mesh.V[loop]
        assert np.linalg.norm(np.roll(P, -1, axis=0) - P, axis=1).max() <= mesh.spacing + 1e-9


def test_drawing_min_angle_at_1500_vertices(drawing_dir, record_property):
    mesh = _drawing_mesh(drawing_dir, "vertices=1500")
    worst = float(np.degrees(triangle_min_angles(mesh.V, mesh.F).min()))
    record_property("min_angle_deg", round(worst, 2))
    assert worst > 5.0


@pytest.mark.parametrize("shape", list(SHAPES))
def test_synthetic_min_angle_at_1500_vertices(shape):
    mesh = _synthetic_mesh(shape, "vertices=1500")
    assert np.degrees(triangle_min_angles(mesh.V, mesh.F).min()) > 5.0


def test_refine_points_make_the_mesh_denser_near_them(drawing_dir):
    joints = _joints(drawing_dir, {"left_elbow", "right_elbow", "left_knee", "right_knee"})
    assert len(joints) == 4
    s = _drawing_silhouette(drawing_dir)
    h = _drawing_mesh(drawing_dir, "vertices=1500").spacing
    plain = triangulate(s, spacing=h)
    refined = triangulate(s, spacing=h, refine_points=joints, refine_factor=0.5)

    def near(mesh):
        d = np.linalg.norm(mesh.V[:, None] - joints[None], axis=2)
        return np.count_nonzero(d < 2.0 * h, axis=0)

    assert np.all(near(refined) > near(plain)), (near(refined), near(plain))
    # Half the spacing is four times the density; ask for at least twice over all joints.
    assert near(refined).sum() >= 2 * near(plain).sum()

    # Refinement is local: far from the joints the vertex count barely changes.
    def far(mesh):
        d = np.linalg.norm(mesh.V[:, None] - joints[None], axis=2).min(axis=1)
        return np.count_nonzero(d > 8.0 * h)

    assert far(refined) == pytest.approx(far(plain), rel=0.1)


def test_refine_with_no_points_is_the_plain_mesh():
    s = _synthetic_silhouette("annulus")
    plain = triangulate(s, spacing=5.0)
    empty = triangulate(s, spacing=5.0, refine_points=np.zeros((0, 2)))
    np.testing.assert_array_equal(plain.V, empty.V)
    np.testing.assert_array_equal(plain.F, empty.F)


# Errors ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("spacing", [0.5, 0.0, -3.0, float("nan"), float("inf")])
def test_spacing_below_one_pixel_is_rejected(spacing):
    with pytest.raises(SettingsError, match="spacing must be at least 1 pixel"):
        triangulate(_synthetic_silhouette("disk"), spacing=spacing)


def test_spacing_and_vertices_together_are_rejected():
    with pytest.raises(SettingsError, match="either a spacing or a vertex count"):
        triangulate(_synthetic_silhouette("disk"), spacing=4.0, vertices=500)


@pytest.mark.parametrize("vertices", [0, 2, -10])
def test_too_few_vertices_are_rejected(vertices):
    with pytest.raises(SettingsError, match="vertex count must be at least 3"):
        triangulate(_synthetic_silhouette("disk"), vertices=vertices)


@pytest.mark.parametrize("factor", [0.05, 1.5])
def test_refine_factor_out_of_range_is_rejected(factor):
    with pytest.raises(SettingsError, match="refine factor"):
        triangulate(_synthetic_silhouette("disk"), refine_points=[[50, 50]], refine_factor=factor)


def test_empty_silhouette_is_rejected():
    with pytest.raises(MeshError, match="silhouette is empty"):
        triangulate(Silhouette(parts=()))
    with pytest.raises(MeshError, match="silhouette is empty"):
        triangulate(trace_silhouette(np.zeros((10, 10), bool)), spacing=2.0)


# check_mesh -----------------------------------------------------------------------------------


def _square_mesh():
    V = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], float)
    F = np.array([[0, 1, 2], [0, 2, 3]])
    return Mesh(V=V, F=F, boundary=(np.arange(4),), spacing=1.0)


def test_check_mesh_accepts_a_sound_mesh():
    assert check_mesh(_square_mesh()) == []


def test_check_mesh_reports_clockwise_triangles():
    m = _square_mesh()
    bad = Mesh(V=m.V, F=m.F[:, ::-1], boundary=m.boundary, spacing=1.0)
    assert any("clockwise" in p for p in check_mesh(bad))


def test_check_mesh_reports_unused_vertices_and_open_outline():
    m = _square_mesh()
    V = np.concatenate([m.V, [[5.0, 5.0]]])
    assert any("no triangle" in p for p in check_mesh(Mesh(V, m.F, m.boundary, 1.0)))
    half = Mesh(m.V, m.F[:1], m.boundary, 1.0)
    assert check_mesh(half) != []
