"""Differential coordinates on meshes and curves: mean value and RSI Laplacian (thesis 3.4.3).

Points are handled as complex numbers ``z = x + iy`` where that keeps the algebra short: a
rotation and uniform scale is then one complex factor.
"""

import numpy as np


def as_complex(P):
    """``(n, 2)`` points as ``(n,)`` complex ``x + iy``."""
    P = np.asarray(P, dtype=float)
    return P[..., 0] + 1j * P[..., 1]


def as_points(z):
    """``(n,)`` complex as ``(n, 2)`` float points."""
    return np.stack([z.real, z.imag], axis=-1)


def mean_value_weights(V, F):
    """Mean value coordinates of every vertex with respect to its one-ring (Floater 2003, eq. 3.4).

    ``w_ij = (tan(a_{j-1}/2) + tan(a_j/2)) / |v_i - v_j|``, normalised so each vertex's weights
    sum to 1. For a vertex inside the mesh, ``v_i = sum_j w_ij v_j`` (eq. 3.5); outline vertices
    have an open one-ring and get weights too, but that identity does not hold for them.

    Parameters
    ----------
    V : (n, 2) float
    F : (m, 3) int
        Counter-clockwise triangles.

    Returns
    -------
    rows, cols : (k,) int
        Vertex ``rows[t]`` has weight ``weights[t]`` on vertex ``cols[t]``.
    weights : (k,) float

    Examples
    --------
    >>> V = np.array([[0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]], float)
    >>> F = np.array([[0, 2, 1], [0, 3, 2], [0, 4, 3], [0, 1, 4]])
    >>> r, c, w = mean_value_weights(V, F)
    >>> sorted(np.round(w[r == 0], 6).tolist())
    [0.25, 0.25, 0.25, 0.25]
    """
    V = np.asarray(V, dtype=float)
    rows, cols, weights = [], [], []
    for corner in range(3):
        i = F[:, corner]
        j = F[:, (corner + 1) % 3]
        k = F[:, (corner + 2) % 3]
        a, b = V[j] - V[i], V[k] - V[i]
        la, lb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
        cross = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        half_tan = cross / np.maximum(la * lb + np.sum(a * b, axis=1), 1e-300)  # tan(angle / 2)
        rows += [i, i]
        cols += [j, k]
        weights += [half_tan / np.maximum(la, 1e-300), half_tan / np.maximum(lb, 1e-300)]
    rows, cols, weights = np.concatenate(rows), np.concatenate(cols), np.concatenate(weights)
    # Sum duplicates (each neighbour is seen from two triangles), then normalise per vertex.
    key = rows * len(V) + cols
    unique, inverse = np.unique(key, return_inverse=True)
    summed = np.bincount(inverse, weights=weights)
    rows, cols = unique // len(V), unique % len(V)
    total = np.bincount(rows, weights=summed, minlength=len(V))
    # A vertex whose triangles all have no area has no angles to weigh by: weigh its
    # neighbours equally instead of dividing by zero.
    flat = total[rows] <= 0
    if flat.any():
        summed = np.where(flat, 1.0, summed)
        total = np.bincount(rows, weights=summed, minlength=len(V))
    return rows, cols, summed / total[rows]


def rsi_laplacian_coefficients(prev, point, after):
    """Rotation- and scale-invariant curve Laplacian (Sorkine 2004), eq. 3.2 made invariant.

    The curve Laplacian ``d = v - (v_prev + v_next) / 2`` is written relative to the chord
    ``v_next - v_prev`` as ``d = c (v_next - v_prev)`` with one complex ``c``. Keeping ``c``
    under deformation keeps the local shape of the curve whatever the rotation and scale, and
    ``v - (v_prev + v_next) / 2 - c (v_next - v_prev) = 0`` is linear in the new positions.

    Parameters
    ----------
    prev, point, after : (n, 2) float
        Each curve vertex and its two neighbours along the curve.

    Returns
    -------
    (n,) complex
        ``c``; zero where the chord has no length.
    """
    chord = as_complex(after) - as_complex(prev)
    delta = as_complex(point) - (as_complex(prev) + as_complex(after)) / 2
    ok = np.abs(chord) > 1e-12
    c = np.zeros(len(chord), dtype=complex)
    c[ok] = delta[ok] / chord[ok]
    return c


def barycentric(V, F, points, *, tolerance=1e-9):
    """The triangle of ``F`` holding each of ``points`` and the point's barycentric weights in it.

    Parameters
    ----------
    V : (n, 2) float
    F : (m, 3) int
    points : (p, 2) float
    tolerance : float
        How far below 0 a weight may be and the point still count as inside (on an edge).

    Returns
    -------
    triangle : (p,) int
        Index into ``F``; -1 for a point in no triangle.
    weights : (p, 3) float
        ``points[i] = weights[i] @ V[F[triangle[i]]]``; zeros where ``triangle`` is -1.

    Examples
    --------
    >>> V = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 4.0], [4.0, 4.0]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> t, w = barycentric(V, F, np.array([[1.0, 1.0], [3.0, 3.0], [9.0, 9.0]]))
    >>> t.tolist(), w[0].tolist()
    ([0, 1, -1], [0.5, 0.25, 0.25])
    """
    V, F = np.asarray(V, dtype=float), np.asarray(F)
    P = np.asarray(points, dtype=float).reshape(-1, 2)
    a = V[F[:, 0]]
    e1, e2 = V[F[:, 1]] - a, V[F[:, 2]] - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    det = np.where(det == 0, np.inf, det)  # a degenerate triangle holds nothing
    d = P[:, None, :] - a[None]  # (p, m, 2)
    w1 = (d[..., 0] * e2[:, 1] - d[..., 1] * e2[:, 0]) / det
    w2 = (e1[:, 0] * d[..., 1] - e1[:, 1] * d[..., 0]) / det
    w = np.stack([1.0 - w1 - w2, w1, w2], axis=-1)  # (p, m, 3)
    best = np.argmax(w.min(axis=-1), axis=1)
    weights = w[np.arange(len(P)), best]
    inside = weights.min(axis=1) >= -tolerance
    return np.where(inside, best, -1), np.where(inside[:, None], weights, 0.0)
