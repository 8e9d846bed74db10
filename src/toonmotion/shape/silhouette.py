"""Silhouette: the outline of a mask as closed polygons with holes (thesis 3.2).

The outline is traced by marching squares (scikit-image's ``find_contours`` at the 0.5 level,
foreground 8-connected) and simplified with Douglas-Peucker to a tolerance in pixels, keeping
the topology (no loop crosses itself or another).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage as ndi
from skimage.draw import polygon2mask
from skimage.measure import find_contours

from toonmotion.errors import MeshError
from toonmotion.geometry.arrays import finite_float, frozen_array, frozen_arrays
from toonmotion.geometry.polygon import signed_area

_SQUARE = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True, eq=False)
class Part:
    """One connected piece of a silhouette.

    Attributes
    ----------
    outer : (n, 2) float
        Outline, counter-clockwise on screen, (x, y) pixels, y down, not closed.
    holes : tuple of (k, 2) float
        Hole outlines, clockwise on screen.

    Construction copies the loops (read-only) and raises :class:`MeshError` unless each is a
    finite ``(k, 2)`` array of at least 3 points.
    """

    outer: NDArray[np.float64]
    holes: tuple[NDArray[np.float64], ...] = ()

    def __post_init__(self) -> None:
        what = "a silhouette part's"
        outer = frozen_array(self.outer, dtype=np.float64, shape=(None, 2), name=f"{what} outer loop",
                             error=MeshError, coordinates=True)
        holes = frozen_arrays(self.holes, dtype=np.float64, shape=(None, 2), name=f"{what} holes",
                              error=MeshError, coordinates=True)
        for loop in (outer, *holes):
            if len(loop) < 3:
                raise MeshError(f"a silhouette loop needs at least 3 points, got {len(loop)}")
        object.__setattr__(self, "outer", outer)
        object.__setattr__(self, "holes", holes)

    @property
    def loops(self) -> tuple[NDArray[np.float64], ...]:
        """The outer loop followed by the holes."""
        return (self.outer, *self.holes)

    @property
    def area(self) -> float:
        """Area in square pixels: the outer loop's less the holes'."""
        return sum(signed_area(loop) for loop in self.loops)


@dataclass(frozen=True, eq=False)
class Silhouette:
    """The figure's outline: parts, largest first, and the simplification tolerance used.

    Attributes
    ----------
    parts : tuple of Part
    tolerance : float
        The Douglas-Peucker tolerance in pixels, >= 0.
    """

    parts: tuple[Part, ...]
    tolerance: float = 1.0

    def __post_init__(self) -> None:
        parts = tuple(self.parts)
        if not all(isinstance(p, Part) for p in parts):
            raise TypeError("a silhouette's parts must be Part objects")
        tolerance = finite_float(self.tolerance, name="a silhouette's tolerance", error=MeshError, minimum=0)
        object.__setattr__(self, "parts", parts)
        object.__setattr__(self, "tolerance", tolerance)

    @property
    def loops(self) -> tuple[NDArray[np.float64], ...]:
        """Every closed loop: each part's outer loop then its holes."""
        return tuple(loop for part in self.parts for loop in part.loops)

    @property
    def area(self) -> float:
        """Area in square pixels."""
        return sum(part.area for part in self.parts)

    def to_mask(self, shape: tuple[int, int]) -> NDArray[np.bool_]:
        """Rasterise: True at pixels whose centre lies inside, ``(h, w)`` bool for ``shape``."""
        mask = np.zeros(shape, dtype=bool)
        for part in self.parts:
            inside = polygon2mask(shape, part.outer[:, ::-1])
            for hole in part.holes:
                inside &= ~polygon2mask(shape, hole[:, ::-1])
            mask |= inside
        return mask

    def to_shapely(self) -> shapely.Polygon | shapely.MultiPolygon:
        """The silhouette as a shapely (Multi)Polygon."""
        polygons = [shapely.Polygon(p.outer, p.holes) for p in self.parts]
        return polygons[0] if len(polygons) == 1 else shapely.MultiPolygon(polygons)


def trace_silhouette(mask: ArrayLike, *, tolerance: float = 1.0, min_hole_area: float = 16.0) -> Silhouette:
    """Outline a mask.

    Parameters
    ----------
    mask : (h, w) bool
        Foreground. Each 8-connected region becomes one :class:`Part`.
    tolerance : float
        Douglas-Peucker tolerance in pixels: no outline point moves further than this.
    min_hole_area : float
        Holes smaller than this many square pixels are filled.

    Returns
    -------
    Silhouette

    Examples
    --------
    >>> mask = np.zeros((9, 9), bool); mask[2:7, 2:7] = True; mask[4, 4] = False
    >>> s = trace_silhouette(mask, min_hole_area=0.5)
    >>> len(s.parts), len(s.parts[0].holes), float(s.parts[0].outer[:, 0].min())
    (1, 1, 1.5)
    """
    mask = np.asarray(mask, dtype=bool)
    labels, count = ndi.label(mask, structure=_SQUARE)
    parts = []
    for index, window in enumerate(ndi.find_objects(labels), start=1):
        rows, cols = window
        component = np.pad(labels[window] == index, 1)
        loops = [
            _to_xy(c, cols.start - 1, rows.start - 1)
            for c in find_contours(component.astype(np.float32), 0.5, fully_connected="high")
        ]
        areas = [abs(signed_area(loop)) for loop in loops]
        outer = loops[int(np.argmax(areas))]
        holes = [
            loop
            for loop, area in zip(loops, areas, strict=True)
            if loop is not outer and area >= min_hole_area
        ]
        parts.extend(_simplify(outer, holes, tolerance))
    parts.sort(key=lambda p: -p.area)
    return Silhouette(parts=tuple(parts), tolerance=float(tolerance))


def _to_xy(contour, x0, y0):
    """find_contours gives closed (row, col) paths; make them open (x, y) loops."""
    xy = contour[:-1, ::-1] + np.array([x0, y0], dtype=float)
    return np.ascontiguousarray(xy)


def _simplify(outer, holes, tolerance):
    rings = [outer, *holes]
    if tolerance > 0:
        # Simplify the rings as closed lines, whose first point GEOS keeps. On a polygon's
        # rings GEOS (>= 3.12) may also drop that point, checking it only against the
        # already simplified ring, and the outline then moves up to ~1.6 tolerances.
        closed = shapely.MultiLineString([np.concatenate([r, r[:1]]) for r in rings])
        lines = closed.simplify(tolerance, preserve_topology=True)
        rings = [np.asarray(line.coords) for line in shapely.get_parts(lines)]
    polygon = shapely.Polygon(rings[0], rings[1:])
    pieces = getattr(polygon, "geoms", [polygon])
    return [
        Part(
            outer=_oriented(np.asarray(p.exterior.coords)[:-1], positive=True),
            holes=tuple(_oriented(np.asarray(h.coords)[:-1], positive=False) for h in p.interiors),
        )
        for p in pieces
        if not p.is_empty and len(p.exterior.coords) >= 4
    ]


def _oriented(loop, *, positive):
    loop = np.ascontiguousarray(loop, dtype=float)
    if (signed_area(loop) > 0) != positive:
        loop = loop[::-1].copy()
    return loop
