"""Tracked joints drawn over footage: rotated rectangles, bones, and confidence as colour."""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray


def draw_tracking(frame: NDArray[np.uint8], positions: NDArray[np.float64], sizes: NDArray[np.float64],
                  parents: NDArray[np.int_], *, angles: NDArray[np.float64] | None = None,
                  confidence: NDArray[np.float64] | None = None) -> NDArray[np.uint8]:
    """A copy of ``frame`` with the tracked skeleton drawn on it.

    Parameters
    ----------
    frame : (h, w, 3) uint8
    positions : (k, 2) float
        Joint centres this frame.
    sizes : (k, 2) float
        Rectangle width and height of each joint.
    parents : (k,) int
    angles : (k,) float, optional
        Rectangle rotations, radians.
    confidence : (k,) float in [0, 1], optional
        Drawn from red (0) through yellow to green (1); all green when not given.

    Returns
    -------
    (h, w, 3) uint8
    """
    out = np.ascontiguousarray(frame).copy()
    k = len(positions)
    angles = np.zeros(k) if angles is None else angles
    confidence = np.ones(k) if confidence is None else confidence
    for j, p in enumerate(parents):
        if p >= 0:
            cv2.line(out, _pixel(positions[p]), _pixel(positions[j]), (40, 90, 255), 2, cv2.LINE_AA)
    for j in range(k):
        box = ((float(positions[j, 0]), float(positions[j, 1])), (float(sizes[j, 0]), float(sizes[j, 1])),
               float(np.degrees(angles[j])))
        corners = np.rint(cv2.boxPoints(box)).astype(np.int32)
        cv2.polylines(out, [corners], True, _colour(confidence[j]), 1, cv2.LINE_8)
        cv2.circle(out, _pixel(positions[j]), 2, _colour(confidence[j]), -1, cv2.LINE_AA)
    return out


def _pixel(point):
    return int(round(float(point[0]))), int(round(float(point[1])))


def _colour(c):
    c = float(np.clip(c, 0, 1))
    return (int(255 * min(1, 2 * (1 - c))), int(255 * min(1, 2 * c)), 0)
