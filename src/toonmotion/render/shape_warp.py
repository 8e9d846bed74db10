"""A drawing moved by its outline: the picture inside the first key-shape warped, triangle by
triangle, onto each retargeted shape (Bregler et al. 3.4's 2D output).

The triangles are the key-shape's own (:func:`toonmotion.keyshape.arap.triangulate_shape`:
Delaunay over its points, those outside a closed contour dropped), so the drawing inside the
outline follows it piecewise-affinely; what lies outside the outline is not drawn.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray


def warp_picture(picture: NDArray[np.uint8], source: ArrayLike, target: ArrayLike, triangles: ArrayLike, *,
                 size: tuple[int, int], origin: Sequence[float] = (0.0, 0.0)) -> NDArray[np.uint8]:
    """``picture`` (h, w, 4) RGBA with its points ``source`` (N, 2) moved to ``target`` (N, 2),
    on a transparent canvas ``size`` (width, height) whose pixel (0, 0) is ``origin``.

    Examples
    --------
    >>> picture = np.zeros((10, 10, 4), np.uint8); picture[...] = (200, 0, 0, 255)
    >>> square = np.array([(0.0, 0), (10, 0), (10, 10), (0, 10)])
    >>> out = warp_picture(picture, square, square + [5, 0], [(0, 1, 2), (0, 2, 3)], size=(20, 10))
    >>> int(out[5, 2, 3]), int(out[5, 10, 3]), out[5, 10, :3].tolist()
    (0, 255, [200, 0, 0])
    """
    S, T = np.asarray(source, dtype=float), np.asarray(target, dtype=float) - np.asarray(origin, dtype=float)
    F = np.asarray(triangles, dtype=np.int64)
    width, height = size
    map_x = np.full((height, width), -1.0, np.float32)
    map_y = np.full((height, width), -1.0, np.float32)
    for a, b, c in F:
        corners = T[[a, b, c]]
        edges = np.column_stack([corners[1] - corners[0], corners[2] - corners[0]])
        if abs(np.linalg.det(edges)) < 1e-9:
            continue
        x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int), 0)
        x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + 1, (width, height))
        if x0 >= x1 or y0 >= y1:
            continue
        ys, xs = np.mgrid[y0:y1, x0:x1]
        local = np.linalg.solve(edges, np.stack([xs.ravel() - corners[0, 0], ys.ravel() - corners[0, 1]]))
        u, v = local
        inside = (u >= -1e-6) & (v >= -1e-6) & (u + v <= 1 + 1e-6)
        where = S[a] + np.outer(u, S[b] - S[a]) + np.outer(v, S[c] - S[a])
        rows, cols = ys.ravel()[inside], xs.ravel()[inside]
        map_x[rows, cols] = where[inside, 0]
        map_y[rows, cols] = where[inside, 1]
    out = cv2.remap(np.ascontiguousarray(picture), map_x, map_y, cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0))
    return np.asarray(out, dtype=np.uint8)


def warp_sequence(picture: NDArray[np.uint8], source: ArrayLike, shapes: ArrayLike, triangles: ArrayLike, *,
                  background: tuple[int, int, int] | None = None, margin: float = 8.0
                  ) -> Iterator[NDArray[np.uint8]]:
    """Every frame of ``picture`` moved onto ``shapes`` (T, N, 2), on one canvas that holds them
    all (and a ``margin``); over ``background`` when given, else transparent."""
    P = np.asarray(shapes, dtype=float)
    low = np.floor(P.reshape(-1, 2).min(axis=0) - margin)
    high = np.ceil(P.reshape(-1, 2).max(axis=0) + margin)
    size = (int(high[0] - low[0]), int(high[1] - low[1]))
    for shape in P:
        frame = warp_picture(picture, source, shape, triangles, size=size, origin=low)
        if background is not None:
            alpha = frame[..., 3:4].astype(np.float32) / 255
            flat = frame[..., :3] * alpha + np.asarray(background, np.float32) * (1 - alpha)
            frame = np.dstack([np.rint(flat).astype(np.uint8), np.full(frame.shape[:2], 255, np.uint8)])
        yield frame
