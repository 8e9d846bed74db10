"""A captured shape drawn over footage: its outline and its points (video capture's overlay)."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

SHIFT = 4  # sub-pixel bits for OpenCV's drawing


def draw_shape(frame: NDArray[np.uint8], points: ArrayLike, *, closed: bool = True,
               colour: tuple[int, int, int] = (255, 60, 200), width: int = 2) -> NDArray[np.uint8]:
    """A copy of ``frame`` (h, w, 3) with ``points`` (N, 2) drawn as a polyline and dots.

    Examples
    --------
    >>> out = draw_shape(np.zeros((20, 20, 3), np.uint8), [(2, 2), (17, 2), (17, 17)])
    >>> int(out[2, 10].max()) > 0, out.shape
    (True, (20, 20, 3))
    """
    out = np.ascontiguousarray(frame).copy()
    P = np.rint(np.asarray(points, dtype=float) * (1 << SHIFT)).astype(np.int32)
    cv2.polylines(out, [P], closed, colour, width, cv2.LINE_AA, shift=SHIFT)
    for p in P:  # the points, small, so the correspondence shows without hiding the line
        cv2.circle(out, (int(p[0]), int(p[1])), 1 << SHIFT, (255, 230, 0), -1, cv2.LINE_AA, shift=SHIFT)
    return out
