"""Cartoon capture by key-shapes (Bregler et al. 2002): the calls behind key-shape models and
contour capture (docs/keyshapes.md)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.contour import capture_contours as _capture
from toonmotion.keyshape.space import KeyShapeSpace, build_space
from toonmotion.render.keyshape_sheet import inbetween_sheet

# The bounds on the eigen-shapes' weights in an extended space: half as much again as any
# example (docs/keyshapes.md).
EIGEN_BOUND = 1.5


def keyshape_space(keys: ArrayLike, *, closed: bool = True, inbetweens: int = 5,
                   tolerance: float = 0.5) -> KeyShapeSpace:
    """The extended key-shape space of hand-picked ``keys``: ARAP in-betweens of every pair, PCA.

    Parameters
    ----------
    keys : (K, N, 2) float
        Key-shapes, points in correspondence, drawing pixels.
    closed : bool
        The points run round a closed contour (its inside is triangulated for the in-betweens).
    inbetweens : int
        In-betweens per pair of keys (the paper's M).
    tolerance : float
        The largest reconstruction error of any key or in-between, px; fixes the number of
        eigen-shapes.

    Returns
    -------
    KeyShapeSpace
        ``extended`` is the key-shapes to capture with (eq. 3).

    Raises
    ------
    KeyShapeError
        For keys of different point counts, too few, collinear or non-finite points.

    Examples
    --------
    >>> ball = np.stack([(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)]) * 20
    >>> space = keyshape_space([ball, ball * [1.4, 0.7], ball * [0.8, 1.25] + [0, -5]])
    >>> space.extended.shape[1:], space.error <= 0.5
    ((24, 2), True)
    """
    return build_space(keys, closed=closed, inbetweens=inbetweens, tolerance=tolerance)


def capture_contours(contours: ArrayLike, shapes: ArrayLike | KeyShapeSpace, *, lower: float = -0.5,
                     upper: float = 1.5, support: int | None = None) -> ContourCapture:
    """The affine motion and key weights of each contour (eq. 4-7).

    Parameters
    ----------
    contours : (T, N, 2) float
        The contour of every frame, in correspondence with the key-shapes.
    shapes : (K, N, 2) float or KeyShapeSpace
        Hand-picked key-shapes, or an extended space (then its eigen-shapes' weights are bounded
        to [-1.5, 1.5], the mean's is free, and ``lower``, ``upper`` and ``support`` are not used).
    lower, upper : float
        Each key's weight bounds (the paper's T1, T2).
    support : int, optional
        At most this many non-zero weights (the paper's J).

    Returns
    -------
    ContourCapture
        ``affine`` (T, 2, 3), ``weights`` (T, K), ``error`` (rms px) and ``rounds`` per frame.

    Raises
    ------
    KeyShapeError
        For contours out of correspondence, bad points, or bounds no weights summing to 1 fit.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)], [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])
    >>> found = capture_contours([warp([[0, -1, 9], [1, 0, 2]], [0.25, 0.75], S)], S)
    >>> found.weights.round(9).tolist()
    [[0.25, 0.75]]
    """
    if isinstance(shapes, KeyShapeSpace):
        L = len(shapes.eigen)
        low = np.append(np.full(L, -EIGEN_BOUND), -np.inf)
        high = np.append(np.full(L, EIGEN_BOUND), np.inf)
        return _capture(contours, shapes.extended, lower=low, upper=high)
    return _capture(contours, shapes, lower=lower, upper=upper, support=support)


def keyshape_sheet(space: KeyShapeSpace) -> NDArray[np.uint8]:
    """A preview sheet of the space's keys and their in-betweens, one row per pair of keys.

    Parameters
    ----------
    space : KeyShapeSpace
        From :func:`keyshape_space`; its ``inbetweens`` per pair are drawn (at least 3).

    Returns
    -------
    (h, w, 3) uint8
        Outlines on white: keys dark, in-betweens blue.

    Examples
    --------
    >>> ball = np.stack([(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)]) * 20
    >>> keyshape_sheet(keyshape_space([ball, ball * [1.4, 0.7]], inbetweens=3)).shape
    (160, 800, 3)
    """
    keys = space.keys
    triangles = triangulate_shape(keys[0], closed=space.closed)
    rows = []
    for i in range(len(keys)):
        for j in range(i + 1, len(keys)):
            pair = ArapPair(keys[i], keys[j], closed=space.closed, triangles=triangles)
            between = pair.inbetweens(max(3, space.inbetweens))
            rows.append(np.concatenate([keys[i][None], between, keys[j][None]]))
    if not rows:  # one key: itself
        rows.append(keys[:1])
    return inbetween_sheet(rows, closed=space.closed)
