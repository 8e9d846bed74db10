"""Polylines and line segments: closest points and distances (batched), arc length, resampling."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def closest_points_on_segments(points: ArrayLike, A: ArrayLike,
                               B: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Closest point on each segment to each point.

    Parameters
    ----------
    points : (n, 2) float
    A, B : (k, 2) float
        Segment ends. A segment with ``A == B`` is a point.

    Returns
    -------
    closest : (n, k, 2) float
        ``closest[i, j]`` is the point of segment ``j`` nearest to ``points[i]``.
    distance : (n, k) float

    Examples
    --------
    >>> c, d = closest_points_on_segments(np.array([[1.0, 2.0]]), np.array([[0.0, 0.0]]),
    ...                                   np.array([[4.0, 0.0]]))
    >>> c[0, 0].tolist(), float(d[0, 0])
    ([1.0, 0.0], 2.0)
    """
    points = np.asarray(points, dtype=float)
    A, B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
    AB = B - A
    length2 = np.einsum("kd,kd->k", AB, AB)
    AP = points[:, None, :] - A[None, :, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.einsum("nkd,kd->nk", AP, AB) / length2
    t = np.clip(np.nan_to_num(t, nan=0.0), 0.0, 1.0)
    closest = A[None] + t[..., None] * AB[None]
    return closest, np.linalg.norm(points[:, None, :] - closest, axis=2)


def arc_lengths(P: ArrayLike) -> NDArray[np.float64]:
    """Arc length from the first vertex of a polyline to each of its vertices.

    Parameters
    ----------
    P : (n, 2) float
        Vertices in order, (x, y) pixels; the polyline is open (a loop must repeat its first
        vertex at the end to be measured closed).

    Returns
    -------
    (n,) float
        Starts at 0 and never decreases; the last value is the whole length.

    Examples
    --------
    >>> arc_lengths([[0, 0], [3, 4], [3, 6]]).tolist()
    [0.0, 5.0, 7.0]
    """
    P = np.asarray(P, dtype=float)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])


def resample_by_arc_length(P: ArrayLike, at: ArrayLike, *, fraction: bool = False) -> NDArray[np.float64]:
    """Points at given arc lengths along a polyline, linearly between its vertices.

    Parameters
    ----------
    P : (n, 2) float
        Vertices in order, (x, y) pixels, n >= 1.
    at : (m,) float
        Distances along the polyline from its first vertex, pixels; clamped to its ends.
    fraction : bool
        Read ``at`` as fractions of the whole length instead (0 the first vertex, 1 the last).

    Returns
    -------
    (m, 2) float
        Repeated vertices (steps of no length) are allowed.

    Examples
    --------
    >>> P = [[0, 0], [4, 0], [4, 2]]
    >>> resample_by_arc_length(P, [1.0, 5.0, 9.0]).tolist()
    [[1.0, 0.0], [4.0, 1.0], [4.0, 2.0]]
    >>> resample_by_arc_length(P, [0.5], fraction=True).tolist()
    [[3.0, 0.0]]
    """
    P = np.asarray(P, dtype=float)
    s = arc_lengths(P)
    x = np.asarray(at, dtype=float)
    if fraction:
        x = x * s[-1]
    return np.stack([np.interp(x, s, P[:, 0]), np.interp(x, s, P[:, 1])], axis=1)
