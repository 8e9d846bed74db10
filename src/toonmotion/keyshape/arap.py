"""As-rigid-as-possible shape interpolation (Alexa, Cohen-Or and Levin 2000), between two
shapes in correspondence: the in-betweens of a pair of key-shapes (Bregler et al. 3.1.3).

The first shape's points are Delaunay-triangulated (for a closed contour, the triangles outside
it are dropped; slivers too). Each triangle's affine map from the first shape to the second,
``A = R(angle) S`` by polar decomposition, is interpolated as ``A(t) = R(t angle) ((1 - t) I +
t S)``; the angles are unwrapped from triangle to neighbouring triangle (a breadth-first walk),
so the whole shape turns one way, the short way for the first triangle. The points at ``t``
are the least-squares fit of every triangle edge ``p_j - p_i`` to ``A(t)`` times its rest edge,
with the centroid moving on the straight line between the two shapes' centroids; the system's
factorisation depends on the first shape only, so it is made once per pair
(:class:`ArapPair`) and every in-between is two triangular solves.
"""

from __future__ import annotations

from collections import deque

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_array
from scipy.sparse.linalg import splu
from scipy.spatial import Delaunay

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.model import check_shapes

FloatArray = NDArray[np.float64]


def triangulate_shape(points: ArrayLike, *, closed: bool) -> NDArray[np.int64]:
    """Triangles (m, 3) over the shape's own points, counter-clockwise on screen (y down).

    Examples
    --------
    >>> square = [(0, 0), (10, 0), (10, 10), (0, 10)]
    >>> len(triangulate_shape(square, closed=True))
    2
    """
    P = check_shapes(points, what="a shape")[0]
    try:
        triangles = Delaunay(P).simplices.astype(np.int64)
    except Exception as error:  # qhull refuses a degenerate point set
        raise KeyShapeError(f"the shape cannot be triangulated: {str(error).splitlines()[0][:120]}") from None
    a, b, c = P[triangles[:, 0]], P[triangles[:, 1]], P[triangles[:, 2]]
    area = 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    scale = float(np.ptp(P, axis=0).max()) ** 2
    keep = np.abs(area) > 1e-6 * scale
    if closed:
        centre = (a + b + c) / 3
        keep &= shapely.contains_xy(shapely.Polygon(P).buffer(0), centre[:, 0], centre[:, 1])
    triangles, area = triangles[keep], area[keep]
    flip = area < 0  # y down: counter-clockwise on screen has a positive signed area here
    triangles[flip] = triangles[flip][:, [0, 2, 1]]
    used = np.zeros(len(P), dtype=bool)
    used[triangles.ravel()] = True
    if not used.all():
        raise KeyShapeError(f"point {int(np.flatnonzero(~used)[0]) + 1} of the shape is in no triangle: "
                            "the contour crosses itself, or the points are not in order along it")
    return triangles


class ArapPair:
    """The in-betweens of ``first`` and ``second`` (N, 2), precomputed once per pair.

    ``at(t)`` is the shape at ``t`` (0: ``first``, 1: ``second``; values outside extrapolate).

    Examples
    --------
    >>> square = np.array([(0.0, 0), (10, 0), (10, 10), (0, 10)])
    >>> turned = square @ np.array([[0.0, 1], [-1, 0]])  # a quarter turn
    >>> pair = ArapPair(square, turned, closed=True)
    >>> bool(np.allclose(pair.at(0), square)), bool(np.allclose(pair.at(1), turned))
    (True, True)
    >>> half = pair.at(0.5) - pair.at(0.5).mean(axis=0)
    >>> round(float(np.hypot(*(half[1] - half[0]))), 9)  # rigid all the way: sides stay 10
    10.0
    """

    def __init__(self, first: ArrayLike, second: ArrayLike, *, closed: bool,
                 triangles: ArrayLike | None = None) -> None:
        one, two = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
        if one.shape != two.shape:
            raise KeyShapeError("a pair of shapes must be lists of [x, y] points with the same count in each")
        shapes = check_shapes(np.stack([one, two]), what="a pair of shapes")
        self.first, self.second = shapes
        self.triangles = (triangulate_shape(self.first, closed=closed) if triangles is None
                          else np.asarray(triangles, dtype=np.int64))
        n = len(self.first)
        F = self.triangles
        edges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
        self._edges = edges
        rows = np.repeat(np.arange(len(edges)), 2)
        D = coo_array((np.tile([-1.0, 1.0], len(edges)), (rows, edges.ravel())),
                      shape=(len(edges), n)).tocsc()
        self._D = D[:, 1:]  # the first point pinned; the centroid is set after
        self._solve = splu((self._D.T @ self._D).tocsc())
        rest = self.first[edges[:, 1]] - self.first[edges[:, 0]]
        self._rest = rest
        self._rotation, self._stretch = _polar_parts(self.first, self.second, self.triangles)

    def at(self, t: float) -> FloatArray:
        """The shape at ``t``: (N, 2)."""
        angle = t * self._rotation
        c, s = np.cos(angle), np.sin(angle)
        R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)  # (m, 2, 2)
        A = R @ ((1 - t) * np.eye(2) + t * self._stretch)
        A_edge = np.concatenate([A, A, A])  # triangle i's edges are rows i, i + m and i + 2m
        goal = np.einsum("eij,ej->ei", A_edge, self._rest)
        solved = self._solve.solve(self._D.T @ goal)
        V = np.vstack([np.zeros((1, 2)), solved])
        centroid = (1 - t) * self.first.mean(axis=0) + t * self.second.mean(axis=0)
        return V - V.mean(axis=0) + centroid

    def inbetweens(self, count: int) -> FloatArray:
        """``count`` shapes strictly between the two, evenly in ``t``: (count, N, 2)."""
        return np.stack([self.at(t) for t in np.linspace(0, 1, count + 2)[1:-1]])


def _polar_parts(P: FloatArray, Q: FloatArray, F: NDArray[np.int64]) -> tuple[FloatArray, FloatArray]:
    """Each triangle's rotation angle (unwrapped across neighbours) and symmetric stretch (m, 2, 2)."""
    Pe = np.stack([P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]], axis=-1)  # columns: edges
    Qe = np.stack([Q[F[:, 1]] - Q[F[:, 0]], Q[F[:, 2]] - Q[F[:, 0]]], axis=-1)
    A = _triangle_maps(Pe, Qe, F, float(np.ptp(P, axis=0).max()) ** 2)
    U, sigma, Vt = np.linalg.svd(A)
    flip = np.linalg.det(U @ Vt) < 0  # a mirrored triangle: the closest rotation, a negative stretch
    U[flip, :, 1] *= -1
    sigma[flip, 1] *= -1
    R = U @ Vt
    stretch = np.einsum("mji,mjk->mik", Vt, sigma[:, :, None] * Vt)
    angle = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    return _unwrapped(angle, F), stretch


def _triangle_maps(Pe: FloatArray, Qe: FloatArray, F: NDArray[np.int64], scale: float) -> FloatArray:
    """Each triangle's linear map ``A`` (m, 2, 2) taking its edges ``Pe`` to ``Qe``.

    A triangle flat in the first shape (its corners on a line: a straight run of a traced pixel
    outline, where the triangulation was made on another key) has no such map; its map is the mean
    of its neighbours' (the triangles sharing a corner), changed as little as takes its edges
    where they go: ``A = N + (Qe - N Pe) Pe^+``, which for a proper triangle is ``Qe Pe^-1``.
    """
    det = Pe[:, 0, 0] * Pe[:, 1, 1] - Pe[:, 0, 1] * Pe[:, 1, 0]
    good = np.abs(det) > 1e-9 * max(scale, 1e-300)
    if not good.any():
        raise KeyShapeError("a key shape has no area: its points lie on a line")
    A = np.empty_like(Qe)
    A[good] = Qe[good] @ np.linalg.inv(Pe[good])
    for i in np.flatnonzero(~good):
        near = good & np.isin(F, F[i]).any(axis=1)
        N = A[near].mean(axis=0) if near.any() else A[good].mean(axis=0)
        A[i] = N + (Qe[i] - N @ Pe[i]) @ np.linalg.pinv(Pe[i])
    return A


def _unwrapped(angle: FloatArray, F: NDArray[np.int64]) -> FloatArray:
    """Angles moved by whole turns so that neighbouring triangles differ by less than half a turn."""
    by_edge: dict[tuple[int, int], list[int]] = {}
    for i, (a, b, c) in enumerate(F):
        for u, v in ((a, b), (b, c), (c, a)):
            by_edge.setdefault((min(u, v), max(u, v)), []).append(i)
    neighbours: list[list[int]] = [[] for _ in F]
    for sharing in by_edge.values():
        for i in sharing:
            neighbours[i].extend(j for j in sharing if j != i)
    out = angle.copy()
    seen = np.zeros(len(F), dtype=bool)
    for seed in range(len(F)):
        if seen[seed]:
            continue
        seen[seed] = True
        queue = deque([seed])
        while queue:
            i = queue.popleft()
            for j in neighbours[i]:
                if not seen[j]:
                    out[j] += 2 * np.pi * np.round((out[i] - out[j]) / (2 * np.pi))
                    seen[j] = True
                    queue.append(j)
    return out
