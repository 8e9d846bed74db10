"""The motion model (Bregler et al. 2002, eq. 1-2, 6): an affine map of a weighted sum of key-shapes.

``theta`` is an affine ``A`` (2, 3) — ``[[a1, a2, dx], [a3, a4, dy]]`` acting on points in
homogeneous form — and K key weights ``w``. ``warp(A, w, S) = A @ [sum_k w_k S_k ; 1]``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.geometry.arrays import MAX_COORDINATE
from toonmotion.geometry.polygon import signed_area

FloatArray = NDArray[np.float64]


def check_shapes(shapes: ArrayLike, *, what: str = "key-shapes", allow_straight: bool = False) -> FloatArray:
    """``shapes`` as a (K, N, 2) float array; :class:`KeyShapeError` unless every shape has the
    same N >= 3 finite points within the coordinate bound and is not collinear.

    ``allow_straight`` lets a shape's points lie on one line (not all on one point): an open line
    of action drawn straight (:mod:`~toonmotion.keyshape.line_of_action`). Its affine is then not
    unique across the line; :func:`fit_affine` gives the least-norm one.

    Examples
    --------
    >>> check_shapes([[(0, 0), (1, 0), (0, 1)]]).shape
    (1, 3, 2)
    >>> check_shapes([[(0, 0), (0, 5), (0, 10)]], allow_straight=True).shape
    (1, 3, 2)
    """
    try:
        array = np.array(shapes, dtype=float)
    except (TypeError, ValueError):
        raise KeyShapeError(f"{what} must be lists of [x, y] points with the same count in each") from None
    if array.ndim == 2:
        array = array[None]
    if array.ndim != 3 or array.shape[2] != 2 or array.shape[0] < 1:
        raise KeyShapeError(f"{what} must be lists of [x, y] points with the same count in each")
    if array.shape[1] < 3:
        raise KeyShapeError(f"{what} need at least 3 points each, got {array.shape[1]}")
    if not np.isfinite(array).all():
        raise KeyShapeError(f"{what} have a point that is not a finite number")
    if np.abs(array).max() > MAX_COORDINATE:
        raise KeyShapeError(f"{what} have a point beyond {MAX_COORDINATE:,.0f} px from the origin")
    for k, shape in enumerate(array):
        centred = shape - shape.mean(axis=0)
        singular = np.linalg.svd(centred, compute_uv=False)
        if allow_straight and singular[0] <= 1e-9 * max(np.abs(shape).max(), 1.0):
            raise KeyShapeError(f"{what}: shape {k + 1} is degenerate (its points are all one point)")
        if not allow_straight and singular[1] <= 1e-9 * max(singular[0], 1e-300):
            raise KeyShapeError(f"{what}: shape {k + 1} is degenerate (its points lie on one line)")
    return array


def warp(affine: ArrayLike, weights: ArrayLike, shapes: ArrayLike) -> FloatArray:
    """The model's shape (eq. 2): ``affine`` (2, 3) applied to ``sum_k weights[k] * shapes[k]``.

    Examples
    --------
    >>> S = np.array([[(0.0, 0), (2, 0), (0, 2)], [(0.0, 0), (4, 0), (0, 4)]])
    >>> warp([[1, 0, 10], [0, 1, 0]], [0.5, 0.5], S).tolist()
    [[10.0, 0.0], [13.0, 0.0], [10.0, 3.0]]
    """
    A = np.asarray(affine, dtype=float)
    blend = np.tensordot(np.asarray(weights, dtype=float), np.asarray(shapes, dtype=float), axes=1)
    return blend @ A[:, :2].T + A[:, 2]


def fit_affine(target: ArrayLike, source: ArrayLike) -> FloatArray:
    """The affine (2, 3) that best maps ``source`` onto ``target`` (N, 2) in least squares (eq. 6).

    Examples
    --------
    >>> S = np.array([(0.0, 0), (1, 0), (0, 1), (1, 1)])
    >>> (fit_affine(S * 2 + [3, 4], S).round(12) + 0.0).tolist()
    [[2.0, 0.0, 3.0], [0.0, 2.0, 4.0]]
    """
    S = np.asarray(source, dtype=float)
    V = np.asarray(target, dtype=float)
    homogeneous = np.column_stack([S, np.ones(len(S))])
    solution, *_ = np.linalg.lstsq(homogeneous, V, rcond=None)  # (3, 2): V = [S 1] @ solution
    return solution.T


def resample_contour(polyline: ArrayLike, count: int, *, start: ArrayLike | None = None) -> FloatArray:
    """A closed polyline resampled to ``count`` points evenly spaced by arc length (3.2's
    contours in correspondence), counter-clockwise on screen, from the point nearest ``start``
    (default: its first point).

    Examples
    --------
    >>> square = [(0, 0), (4, 0), (4, 4), (0, 4)]  # clockwise on screen (y down)
    >>> resample_contour(square, 8, start=(4, 4)).tolist()
    [[4.0, 4.0], [4.0, 2.0], [4.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 2.0], [0.0, 4.0], [2.0, 4.0]]
    """
    P = check_shapes(polyline, what="a contour")[0]
    if not (isinstance(count, int) and 3 <= count <= 100_000):
        raise KeyShapeError(f"a contour is resampled to 3 to 100,000 points, not {count!r}")
    if signed_area(P) < 0:  # clockwise on screen
        P = P[::-1]
    closed = np.vstack([P, P[:1]])
    steps = np.hypot(*np.diff(closed, axis=0).T)
    run = np.concatenate([[0.0], np.cumsum(steps)])
    at = 0.0
    if start is not None:
        s = np.asarray(start, dtype=float)
        ab = closed[1:] - closed[:-1]
        span = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
        t = np.clip(np.einsum("ij,ij->i", s - closed[:-1], ab) / span, 0, 1)
        near = closed[:-1] + ab * t[:, None]
        k = int(np.argmin(np.hypot(*(near - s).T)))
        at = run[k] + t[k] * steps[k]
    where = (at + run[-1] * np.arange(count) / count) % run[-1]
    return np.stack([np.interp(where, run, closed[:, 0]), np.interp(where, run, closed[:, 1])], axis=1)
