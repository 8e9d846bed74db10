"""Rays resolved into pixels: ``k x k`` samples a pixel become one colour, depth, id and alpha.

An element's edge crosses a pixel somewhere between its centre and its border; one ray a pixel
says all or nothing, a staircase. With ``k x k`` rays on a grid centred on the pixel
(:class:`toonmotion.render.zbuffer.SampleBuffer`), the pixel takes:

- **alpha**: the fraction of its rays that hit an element (its coverage, ``0``, ``1 / k^2``, ..., 1);
- **colour**: the mean colour of the rays that hit, rounded half to even (so where two elements
  meet in a pixel their colours blend, and where one meets nothing, alpha does the blending);
- **depth** and **id**: those of the nearest ray that hit (the depth test against the drawing
  uses the element's nearest surface in the pixel).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray


def resolve_samples(rgba: NDArray[np.uint8], depth: NDArray[np.float64], ids: NDArray[np.int32], k: int
                    ) -> tuple[NDArray[np.uint8], NDArray[np.float64], NDArray[np.int32],
                               NDArray[np.float64]]:
    """Colour ``(H, W, 3)``, depth, ids and alpha ``(H, W)`` of samples ``(k H, k W)``.

    ``rgba`` is ``(k H, k W, 4)`` bytes (alpha unused), ``depth`` ``inf`` and ``ids`` -1 where a
    ray met nothing.

    >>> ids = np.array([[0, -1], [0, 1]], np.int32)
    >>> depth = np.where(ids >= 0, [[2.0, 9.0], [3.0, 1.0]], np.inf)
    >>> rgba = np.zeros((2, 2, 4), np.uint8); rgba[ids == 0] = (200, 0, 0, 255); rgba[1, 1] = (0, 0, 100, 255)
    >>> colour, near, seen, alpha = resolve_samples(rgba, depth, ids, 2)
    >>> colour[0, 0].tolist(), float(near[0, 0]), int(seen[0, 0]), float(alpha[0, 0])
    ([133, 0, 33], 1.0, 1, 0.75)
    """
    H, W = depth.shape[0] // k, depth.shape[1] // k
    hits, total, near, seen = _gather(rgba, depth, ids, k, H, W)
    colour, alpha = _means(hits, total, k)
    return colour, near, seen, alpha


# Two compiled loops, not one: fused, Numba's loop ran three times slower (13 ms against 4.3 ms for
# the demo's 640 x 480 frame at k = 2).
@njit(cache=True)
def _gather(rgba, depth, ids, k, H, W):  # pragma: no cover - compiled
    """Each pixel's hits, the sum of their colours and the nearest hit's depth and id, in one pass
    over the samples in memory order (most samples miss)."""
    hits = np.zeros((H, W), np.int32)
    total = np.zeros((H, W, 3))
    near = np.full((H, W), np.inf)
    seen = np.full((H, W), -1, np.int32)
    for si in range(k * H):  # sample row si, column sj; pixel i, j
        i = si // k
        for sj in range(k * W):
            if ids[si, sj] < 0:
                continue
            j = sj // k
            hits[i, j] += 1
            for c in range(3):
                total[i, j, c] += rgba[si, sj, c]
            if depth[si, sj] < near[i, j]:
                near[i, j], seen[i, j] = depth[si, sj], ids[si, sj]
    return hits, total, near, seen


@njit(cache=True)
def _means(hits, total, k):  # pragma: no cover - compiled
    """Alpha (the fraction of the ``k x k`` rays that hit) and the mean colour of the hits."""
    H, W = hits.shape
    colour = np.zeros((H, W, 3), np.uint8)
    alpha = np.zeros((H, W))
    for i in range(H):
        for j in range(W):
            if hits[i, j]:
                alpha[i, j] = hits[i, j] / (k * k)
                for c in range(3):
                    colour[i, j, c] = np.rint(total[i, j, c] / hits[i, j])
    return colour, alpha
