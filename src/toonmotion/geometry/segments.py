"""Points against line segments: closest points and distances, batched."""

import numpy as np


def closest_points_on_segments(points, A, B):
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
