"""Polygons as ``(n, 2)`` float arrays of (x, y) pixels, y down, not closed (last != first).

Orientation follows the screen: a loop is *counter-clockwise* when it turns that way as seen on
screen with y pointing down. :func:`signed_area` is positive for such loops, so outer
outlines have positive area and holes negative.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray


def signed_area(P: ArrayLike) -> float:
    """Signed area of a closed polygon, positive when counter-clockwise on screen.

    Parameters
    ----------
    P : (n, 2) float
        Vertices, (x, y) pixels, y down; the closing edge is implied.

    Examples
    --------
    >>> square = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], float)  # down, right, up on screen
    >>> float(signed_area(square))
    1.0
    """
    P = np.asarray(P, dtype=float)
    x, y = P[:, 0], P[:, 1]
    # The shoelace sum is positive for counter-clockwise loops in a y-up frame; y down flips it.
    return -0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def triangle_areas(V: NDArray[np.float64], F: NDArray[np.int_]) -> NDArray[np.float64]:
    """Signed areas of triangles, positive when counter-clockwise on screen.

    Parameters
    ----------
    V : (n, 2) float
        Vertices.
    F : (m, 3) int
        Triangles as vertex indices.

    Returns
    -------
    (m,) float
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    ab, ac = b - a, c - a
    return -0.5 * (ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0])


def triangle_min_angles(V: NDArray[np.float64], F: NDArray[np.int_]) -> NDArray[np.float64]:
    """Smallest interior angle of each triangle, in radians, ``(m,)``."""
    P = V[F]  # (m, 3, 2)
    e = np.roll(P, -1, axis=1) - P  # edge i goes from corner i to corner i + 1
    lengths = np.linalg.norm(e, axis=2)
    # The angle at corner i lies between edge i and the reversed edge i - 1.
    u, w = e, -np.roll(e, 1, axis=1)
    cos = np.sum(u * w, axis=2) / np.maximum(lengths * np.roll(lengths, 1, axis=1), 1e-300)
    return np.arccos(np.clip(cos, -1.0, 1.0)).min(axis=1)


def subdivide_loop(P: ArrayLike, max_edge: float) -> NDArray[np.float64]:
    """Insert evenly spaced points on every edge of a closed loop longer than ``max_edge``.

    The loop's own vertices are kept, so the result traces exactly the same polygon.

    Parameters
    ----------
    P : (n, 2) float
        Closed loop, not repeating its first vertex.
    max_edge : float
        Longest edge allowed in the result.

    Returns
    -------
    (k, 2) float, k >= n

    Examples
    --------
    >>> subdivide_loop(np.array([[0, 0], [4, 0], [4, 1]], float), 2.0).tolist()[:3]
    [[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]]
    """
    P = np.asarray(P, dtype=float)
    Q = np.roll(P, -1, axis=0)
    pieces = np.maximum(1, np.ceil(np.linalg.norm(Q - P, axis=1) / max_edge - 1e-9)).astype(int)
    edge = np.repeat(np.arange(len(P)), pieces)
    start = np.cumsum(pieces) - pieces
    t = (np.arange(pieces.sum()) - np.repeat(start, pieces)) / np.repeat(pieces, pieces)
    return P[edge] + t[:, None] * (Q[edge] - P[edge])


def loop_edges(loops: Sequence[NDArray[np.int_]]) -> NDArray[np.int_]:
    """Directed edges ``(k, 2)`` of closed loops given as index arrays."""
    if not loops:
        return np.zeros((0, 2), dtype=np.int64)
    return np.concatenate([np.stack([L, np.roll(L, -1)], axis=1) for L in loops])


def points_in_polygon(points: ArrayLike, loops: Sequence[ArrayLike]) -> NDArray[np.bool_]:
    """Even-odd test of points against a polygon made of closed loops (outers and holes).

    Parameters
    ----------
    points : (n, 2) float
    loops : sequence of (k, 2) float
        Closed loops, not repeating their first vertex. Orientation does not matter, nor do
        crossings: a point is inside when an odd number of loops (or a self-crossing loop an odd
        number of times) surround it.

    Returns
    -------
    (n,) bool
        True for points strictly inside; points on an edge are outside.

    Examples
    --------
    >>> square = np.array([[0, 0], [0, 2], [2, 2], [2, 0]], float)
    >>> points_in_polygon(np.array([[1, 1], [3, 1], [2, 1]], float), [square]).tolist()
    [True, False, False]
    """
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    inside = np.zeros(len(points), dtype=bool)
    for loop in loops:
        ring = np.asarray(loop, dtype=float)
        if len(ring) < 3:  # no area: it holds no point
            continue
        polygon = shapely.Polygon(ring)
        shapely.prepare(polygon)
        inside ^= shapely.contains_xy(polygon, points[:, 0], points[:, 1])
    return inside
