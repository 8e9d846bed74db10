"""Triangle mesh of a silhouette (thesis 3.2).

The outline is resampled so no edge is longer than the spacing ``h`` (the silhouette's own
vertices are kept, so the mesh outline *is* the silhouette); the interior is sampled on a
hexagonal lattice of spacing ``h`` (the uniform sampling that gives near-equilateral
triangles); everything is Delaunay-triangulated and the triangles outside the silhouette are
deleted. To make that deletion exact, the triangulation is made to *conform* to the outline
first: lattice points inside an outline edge's diametral circle are dropped and outline edges
that Delaunay still misses are split at their midpoints until every one is a triangle edge.
The result equals a constrained Delaunay triangulation of the samples, without the
non-commercial ``triangle`` package.

Vertices are ordered outline first, loop after loop, then the interior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import Delaunay, cKDTree
from skimage.draw import polygon as skimage_polygon

from toonmotion.errors import MeshError, SettingsError
from toonmotion.geometry.arrays import finite_float, frozen_array, frozen_arrays
from toonmotion.geometry.polygon import subdivide_loop, triangle_areas
from toonmotion.shape.silhouette import Silhouette


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangulated silhouette.

    Attributes
    ----------
    V : (n, 2) float
        Vertices, (x, y) pixels, y down. Outline vertices come first.
    F : (m, 3) int
        Triangles, counter-clockwise on screen.
    boundary : tuple of (k,) int
        Outline loops as ordered vertex indices: outer loops counter-clockwise on screen,
        holes clockwise, in the silhouette's loop order.
    spacing : float
        The sampling spacing ``h`` in pixels.

    Construction copies the arrays (read-only) and raises :class:`MeshError` unless ``V`` is
    finite ``(n, 2)``, ``F`` is ``(m, 3)`` and ``boundary`` loops are ``(k,)``, all with vertex
    indices below ``n``, and ``spacing`` is a finite number > 0. Whether the triangles are
    sound is :func:`check_mesh`'s business.
    """

    V: NDArray[np.float64]
    F: NDArray[np.int64]
    boundary: tuple[NDArray[np.int64], ...]
    spacing: float

    def __post_init__(self) -> None:
        V = frozen_array(self.V, dtype=np.float64, shape=(None, 2), name="a mesh's V", error=MeshError,
                         coordinates=True)
        F = frozen_array(self.F, dtype=np.int64, shape=(None, 3), name="a mesh's F", error=MeshError)
        boundary = frozen_arrays(self.boundary, dtype=np.int64, shape=(None,), name="a mesh's boundary",
                                 error=MeshError)
        for what, index in (("F", F), *(("boundary", loop) for loop in boundary)):
            if index.size and (index.min() < 0 or index.max() >= len(V)):
                raise MeshError(f"a mesh's {what} names a vertex that does not exist (it has {len(V)})")
        spacing = finite_float(self.spacing, name="a mesh's spacing", error=MeshError, minimum=0, strict=True)
        object.__setattr__(self, "V", V)
        object.__setattr__(self, "F", F)
        object.__setattr__(self, "boundary", boundary)
        object.__setattr__(self, "spacing", spacing)

    @property
    def pick_reach(self) -> float:
        """How far (px) a point may lie from the vertex it picks (a drag's start, a click on a
        region): two spacings, at least 3 px; farther, the point is off the drawing."""
        return max(2.0 * self.spacing, 3.0)

    @property
    def n_outline(self) -> int:
        """Number of outline vertices; they are ``V[:n_outline]``."""
        return sum(len(loop) for loop in self.boundary)

    @property
    def edges(self) -> NDArray[np.int64]:
        """Unique undirected edges ``(e, 2)``, smaller index first."""
        return unique_edges(self.F)


def triangulate(
    silhouette: Silhouette,
    *,
    spacing: float | None = None,
    vertices: int | None = None,
    refine_points: ArrayLike | None = None,
    refine_factor: float = 0.5,
) -> Mesh:
    """Mesh a silhouette.

    Parameters
    ----------
    silhouette : Silhouette
    spacing : float, optional
        Sampling spacing ``h`` in pixels.
    vertices : int, optional
        Target vertex count; the spacing is chosen to come close (within a few percent).
        Give ``spacing`` or ``vertices``, not both; with neither, 1,500 vertices.
    refine_points : (k, 2) float, optional
        Points (typically joints) around which to sample denser (thesis 7.2 item 4).
    refine_factor : float
        Spacing near ``refine_points`` as a fraction of ``h``.

    Returns
    -------
    Mesh
    """
    if spacing is not None and vertices is not None:
        raise SettingsError("give either a spacing or a vertex count, not both")
    if not silhouette.parts:
        raise MeshError("the silhouette is empty: there is nothing to mesh")
    if not 0.1 <= refine_factor <= 1.0:
        raise SettingsError(f"refine factor must be between 0.1 and 1, got {refine_factor}")
    sampler = _Sampler(silhouette, refine_points, refine_factor)
    if spacing is None:
        spacing = sampler.spacing_for(1500 if vertices is None else vertices)
    elif not np.isfinite(spacing) or spacing < 1.0:
        raise SettingsError(f"spacing must be at least 1 pixel, got {spacing}")
    return _mesh(sampler, float(spacing))


def choose_spacing(
    silhouette: Silhouette,
    vertices: int,
    *,
    refine_points: ArrayLike | None = None,
    refine_factor: float = 0.5,
) -> float:
    """The spacing at which :func:`triangulate` gives about ``vertices`` vertices."""
    if not silhouette.parts:
        raise MeshError("the silhouette is empty: there is nothing to mesh")
    return _Sampler(silhouette, refine_points, refine_factor).spacing_for(vertices)


def unique_edges(F: NDArray[np.integer]) -> NDArray[np.int64]:
    """Unique undirected edges of triangles, ``(e, 2)`` int, smaller index first."""
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return np.unique(np.sort(E, axis=1), axis=0)


def check_mesh(mesh: Mesh, *, min_area: float = 1e-9) -> list[str]:
    """Return a list of broken mesh invariants (empty when the mesh is sound).

    Checks that triangles are counter-clockwise with area above ``min_area``, that every
    outline edge belongs to exactly one triangle and every other edge to exactly two, and that
    every vertex is used.
    """
    problems = []
    V, F = mesh.V, mesh.F
    areas = triangle_areas(V, F)
    if np.any(areas <= min_area):
        problems.append(f"{int(np.sum(areas <= min_area))} triangles are degenerate or clockwise")
    if len(np.unique(F)) != len(V):
        problems.append("some vertices belong to no triangle")
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    edges, uses = np.unique(E, axis=0, return_counts=True)
    outline = {tuple(sorted(e)) for loop in mesh.boundary for e in zip(loop, np.roll(loop, -1), strict=True)}
    for edge, count in zip(map(tuple, edges), uses, strict=True):
        if count != (1 if edge in outline else 2):
            problems.append(f"edge {edge} is used by {count} triangles")
            break
    if not outline <= set(map(tuple, edges)):
        problems.append("some outline edges are not mesh edges")
    return problems



def left_out(mesh: Mesh, mask: ArrayLike) -> float:
    """The fraction of the figure's pixels (``mask``, ``(h, w)`` bool) that the mesh's outline
    leaves out: parts thinner than a coarse mesh's spacing are cut off by its outline.

    A mesh of a square, and the square's figure with a tail of 20% of its pixels besides:

    >>> from toonmotion.shape.silhouette import trace_silhouette
    >>> square = np.zeros((60, 60), bool); square[10:50, 10:50] = True
    >>> mesh = triangulate(trace_silhouette(square), spacing=5.0)
    >>> tailed = square.copy(); tailed[10:50, 50:58] = True
    >>> round(left_out(mesh, square), 3), round(left_out(mesh, tailed), 3)
    (0.0, 0.167)
    """
    figure = np.asarray(mask, dtype=bool)
    if not figure.any():
        return 0.0
    inside = np.zeros(figure.shape, dtype=bool)
    for loop in mesh.boundary:  # holes are loops inside loops: even-odd
        rows, cols = skimage_polygon(mesh.V[loop, 1], mesh.V[loop, 0], figure.shape)
        layer = np.zeros(figure.shape, dtype=bool)
        layer[rows, cols] = True
        inside ^= layer
    return float(np.count_nonzero(figure & ~inside)) / float(np.count_nonzero(figure))

# Interior samples keep at least this fraction of the local spacing from the outline.
_CLEARANCE = 0.5
# Rounds of splitting outline edges the triangulation missed before giving up.
_MAX_CONFORM_ROUNDS = 40


class _Sampler:
    """Samples the outline and interior of a silhouette for a given spacing."""

    def __init__(self, silhouette, refine_points, refine_factor):
        self.loops = silhouette.loops
        self.polygon = silhouette.to_shapely()
        shapely.prepare(self.polygon)
        self.area = silhouette.area
        dense = np.concatenate([subdivide_loop(loop, 1.0) for loop in self.loops])
        self.outline_tree = cKDTree(dense)
        self.lo = dense.min(axis=0)
        self.hi = dense.max(axis=0)
        self.factor = refine_factor
        if refine_points is None or len(refine_points) == 0:
            self.refine = np.zeros((0, 2))
            self.refine_thickness = np.zeros(0)
        else:
            self.refine = np.asarray(refine_points, dtype=float).reshape(-1, 2)
            self.refine_thickness = self.outline_tree.query(self.refine)[0]

    def local_spacing(self, points, h):
        """Spacing at each point: ``h``, or ``factor * h`` within a joint's refine radius."""
        out = np.full(len(points), h)
        if len(self.refine):
            radius = self._refine_radius(h)
            d = np.linalg.norm(points[:, None, :] - self.refine[None], axis=2)
            out[np.any(d < radius[None], axis=1)] = self.factor * h
        return out

    def _refine_radius(self, h):
        return np.maximum(1.5 * self.refine_thickness, 3.0 * h)

    def outline(self, h):
        """Outline loops, each edge no longer than the local spacing."""
        out = []
        for loop in self.loops:
            if len(self.refine):
                # Subdivide finely, then keep the original corners and a sample every local h.
                fine = subdivide_loop(loop, 0.25 * self.factor * h)
                out.append(_resample_by_density(fine, loop, self.local_spacing(fine, h)))
            else:
                out.append(subdivide_loop(loop, h))
        return out

    def interior(self, h):
        """Interior lattice points, away from the outline by a fraction of the local spacing."""
        points = _hex_lattice(self.lo, self.hi, h)
        if len(self.refine):
            radius = self._refine_radius(h)
            fine = _hex_lattice(self.lo, self.hi, self.factor * h)
            near = np.linalg.norm(fine[:, None] - self.refine[None], axis=2) < radius[None]
            d_coarse = np.linalg.norm(points[:, None] - self.refine[None], axis=2)
            far = np.all(d_coarse >= radius[None] + 0.5 * h, axis=1)
            points = np.concatenate([points[far], fine[np.any(near, axis=1)]])
        if len(points) == 0:
            return points
        inside = shapely.contains_xy(self.polygon, points[:, 0], points[:, 1])
        points = points[inside]
        clearance = self.outline_tree.query(points)[0]
        return points[clearance >= _CLEARANCE * self.local_spacing(points, h)]

    def count(self, h):
        return sum(len(loop) for loop in self.outline(h)) + len(self.interior(h))

    def spacing_for(self, target):
        if not target >= 3:
            raise SettingsError(f"the vertex count must be at least 3, got {target}")
        h = max(1.0, float(np.sqrt(max(self.area, 1.0) / (0.866 * target))))
        for _ in range(8):
            n = self.count(h)
            if abs(n - target) <= 0.02 * target:
                break
            h = max(1.0, h * float(np.sqrt(n / target)))
        return h


def _hex_lattice(lo, hi, h):
    """Points of a hexagonal lattice of spacing ``h`` covering the box [lo, hi]."""
    dy = h * np.sqrt(3.0) / 2.0
    ys = np.arange(lo[1] + dy / 2, hi[1], dy)
    xs = np.arange(lo[0] + h / 2, hi[0] + h / 2, h)
    X, Y = np.meshgrid(xs, ys)
    X = X + (np.arange(len(ys)) % 2)[:, None] * (h / 2)
    return np.stack([X.ravel(), Y.ravel()], axis=1)


def _resample_by_density(fine, corners, spacing):
    """Pick points of a finely sampled loop about ``spacing`` apart, keeping the corners."""
    step = np.linalg.norm(np.roll(fine, -1, axis=0) - fine, axis=1)
    budget = np.concatenate([[0.0], np.cumsum(step / spacing)[:-1]])
    is_corner = cKDTree(corners).query(fine)[0] < 1e-9
    keep = np.diff(np.floor(budget), prepend=-1.0) > 0
    return fine[keep | is_corner]


def _mesh(sampler, h):
    loops = sampler.outline(h)
    interior = sampler.interior(h)
    for _ in range(_MAX_CONFORM_ROUNDS):
        interior = _drop_encroaching(loops, interior)
        outline = np.concatenate(loops)
        points = np.concatenate([outline, interior])
        simplices = Delaunay(points).simplices
        missing = _missing_outline_edges(loops, simplices, len(points))
        if not any(m.any() for m in missing):
            break
        loops = [_split_edges(loop, m) for loop, m in zip(loops, missing, strict=True)]
    else:
        raise MeshError(
            f"could not fit a mesh to the outline at spacing {h:.2f} px; "
            "try a smaller spacing or a larger simplification tolerance"
        )
    F = _inside_triangles(points, simplices, sampler.polygon)
    used = np.zeros(len(points), dtype=bool)
    used[F.ravel()] = True
    n_outline = len(outline)
    if not used[:n_outline].all():
        raise MeshError("part of the outline is too thin to mesh; try a smaller spacing")
    # Interior points that fell outside (on a hole's edge, say) are dropped; renumber.
    new_index = np.cumsum(used) - 1
    starts = np.cumsum([0] + [len(loop) for loop in loops])
    boundary = tuple(np.arange(a, b) for a, b in zip(starts[:-1], starts[1:], strict=True))
    return Mesh(V=points[used], F=new_index[F], boundary=boundary, spacing=h)


def _drop_encroaching(loops, interior):
    """Remove interior points inside any outline edge's diametral circle."""
    if len(interior) == 0:
        return interior
    tree = cKDTree(interior)
    drop = np.zeros(len(interior), dtype=bool)
    for loop in loops:
        nxt = np.roll(loop, -1, axis=0)
        mid, radius = (loop + nxt) / 2, np.linalg.norm(nxt - loop, axis=1) / 2
        for hits in tree.query_ball_point(mid, radius * 1.0001):
            drop[hits] = True
    return interior[~drop]


def _missing_outline_edges(loops, simplices, n):
    E = np.concatenate([simplices[:, [0, 1]], simplices[:, [1, 2]], simplices[:, [2, 0]]])
    E.sort(axis=1)
    present = np.unique(E[:, 0] * n + E[:, 1])
    out, start = [], 0
    for loop in loops:
        a = np.arange(start, start + len(loop))
        b = np.roll(a, -1)
        keys = np.minimum(a, b) * n + np.maximum(a, b)
        out.append(~np.isin(keys, present, assume_unique=False))
        start += len(loop)
    return out


def _split_edges(loop, split):
    """Insert the midpoint of every edge ``i -> i+1`` where ``split[i]``."""
    nxt = np.roll(loop, -1, axis=0)
    parts = np.stack([loop, (loop + nxt) / 2], axis=1)  # (k, 2, 2)
    keep = np.stack([np.ones(len(loop), bool), split], axis=1)
    return parts[keep]


def _inside_triangles(points, simplices, polygon):
    """Triangles of a conforming triangulation that lie inside the polygon, made CCW."""
    areas = triangle_areas(points, simplices)
    scale = np.median(np.abs(areas)) if len(areas) else 1.0
    F = simplices[np.abs(areas) > 1e-9 * scale]
    centroids = points[F].mean(axis=1)
    F = F[shapely.contains_xy(polygon, centroids[:, 0], centroids[:, 1])]
    clockwise = triangle_areas(points, F) < 0
    F[clockwise] = F[clockwise][:, ::-1]
    return F.astype(np.int64)
