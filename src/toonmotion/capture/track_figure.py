"""The figure's mask in the joint tracker: every joint lies on the figure.

A joint that shows lies on the figure, and one that is hidden lies behind a nearer part of it:
either way its centre is on the figure's foreground (:mod:`~toonmotion.capture.foreground`). On
a flat-coloured cartoon that is the one thing that tells a place on a limb from the plain paper
round it as well as from a look-alike patch. The tracker uses it twice:

* a match whose centre lies off the figure is no match (the matching cost there is infinite);
* a joint that was not found, placed where its parent or the joints below it carry it, goes to
  the nearest point of the figure when that place is off it (a hand carried by its elbow while
  the arm bends out of sight does not float in the air beside it).

A mask counts a point as on the figure when it lies within ``ClipTuning.figure_slack`` pixels of a
foreground pixel (anti-aliased outlines and thresholds shift a mask's edge by a pixel or so).
Joints that lie off their frame's mask where tracking starts (a mask that misses part of the
figure) are not held to it at all.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.errors import TrackingError


class FigureMasks:
    """Each frame's figure, as the tracker asks for it (module docstring).

    Parameters
    ----------
    masks : (T, h, w) bool, or a sequence of T (h, w) bool arrays
        Where the figure is in each frame, as :func:`~toonmotion.capture.foreground.foreground_masks`
        gives it; the frames' size.
    shape : tuple
        ``(h, w, ...)`` of the frames.
    tuning : ClipTuning, optional
        Its ``figure_slack`` and ``pull_reach``; default its defaults.
    """

    def __init__(self, masks: NDArray[np.bool_] | Sequence[NDArray[np.bool_]], count: int,
                 shape: tuple[int, ...], *, tuning: ClipTuning | None = None) -> None:
        if len(masks) != count:
            raise TrackingError(f"there are {len(masks)} figure masks for {count} frames; give one a frame")
        self._masks, self._shape = masks, tuple(shape[:2])
        self.tuning = ClipTuning() if tuning is None else tuning
        self._cache: tuple[int, NDArray[np.uint8]] | None = None
        radius = int(np.ceil(self.tuning.figure_slack))
        self._kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))

    def near(self, t: int) -> NDArray[np.uint8]:
        """``(h, w)`` uint8, non-zero where frame ``t``'s figure is within ``tuning.figure_slack`` px."""
        if self._cache is None or self._cache[0] != t:
            mask = check_mask(np.asarray(self._masks[t]), t, self._shape)
            # A bool mask is dilated as the 0s and 1s it holds, uncopied.
            ones = np.ascontiguousarray(mask if mask.dtype == bool else mask != 0).view(np.uint8)
            near = np.asarray(cv2.dilate(ones, self._kernel), dtype=np.uint8)
            self._cache = (t, near)
        return self._cache[1]

    def holds(self, t: int, points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Whether each of ``points`` ``(k, 2)`` lies on frame ``t``'s figure."""
        return on_figure(self.near(t), points)


def check_mask(mask: NDArray[Any], t: int, shape: tuple[int, ...]) -> NDArray[Any]:
    """``mask``, frame ``t``'s figure, if it is of the frames' size ``shape`` ``(h, w, ...)``; else
    raise :class:`TrackingError`."""
    if mask.shape != tuple(shape[:2]):
        raise TrackingError(
            f"the figure mask of frame {t} has shape {mask.shape} but the frames are "
            f"{shape[1]}x{shape[0]}; give (h, w) masks of the frames' size"
        )
    return mask


def on_figure(near: NDArray[np.uint8], points: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Whether each of ``points`` ``(n, 2)`` (x, y) falls on a non-zero pixel of ``near``; points
    off the frame are off the figure.

    >>> near = np.zeros((4, 6), np.uint8); near[1:3, 2:4] = 255
    >>> on_figure(near, np.array([[2.4, 1.6], [0.0, 0.0], [9.0, 1.0]])).tolist()
    [True, False, False]
    """
    h, w = near.shape
    ij = np.rint(np.asarray(points, dtype=float)[:, ::-1]).astype(int)
    inside = (ij[:, 0] >= 0) & (ij[:, 0] < h) & (ij[:, 1] >= 0) & (ij[:, 1] < w)
    out = np.zeros(len(ij), dtype=bool)
    out[inside] = near[ij[inside, 0], ij[inside, 1]] > 0
    return out


def onto_figure(near: NDArray[np.uint8], point: NDArray[np.float64], limit: float, *,
                pull: float | None = None) -> NDArray[np.float64]:
    """``point`` (x, y) if it lies on the figure (``near`` non-zero), else the nearest pixel of the
    figure if it is no farther than ``limit`` pixels, else ``limit`` pixels toward that pixel if
    it is within ``pull`` limits (default ``ClipTuning.pull_reach``), else ``point`` itself.

    >>> near = np.zeros((10, 10), np.uint8); near[:, 6:] = 255
    >>> point = np.array([2.0, 4.0])
    >>> onto_figure(near, point, 5.0).tolist(), onto_figure(near, point, 3.0).tolist()
    ([6.0, 4.0], [5.0, 4.0])
    """
    h, w = near.shape
    x, y = (int(round(v)) for v in point)
    if 0 <= x < w and 0 <= y < h and near[y, x]:
        return point
    r = int(np.ceil((ClipTuning().pull_reach if pull is None else pull) * limit))
    x0, y0 = max(0, x - r), max(0, y - r)
    rows, cols = np.nonzero(near[y0:min(h, y + r + 1), x0:min(w, x + r + 1)])
    if not rows.size:
        return point
    d2 = (cols + x0 - point[0]) ** 2 + (rows + y0 - point[1]) ** 2
    best = int(np.argmin(d2))
    nearest = np.array([cols[best] + x0, rows[best] + y0], dtype=float)
    if d2[best] <= limit**2:
        return nearest
    # Farther: a step of the limit toward it (a joint hidden where it was not last seen, an arm
    # gone behind the body in one drawing, was left on the paper beside it).
    return point + (nearest - point) * (limit / float(np.sqrt(d2[best])))


def put_on_figure(P: NDArray[np.float64], hidden: NDArray[np.bool_], figure: FigureMasks,
                  limit: NDArray[np.float64]) -> None:
    """Move every joint-frame marked ``hidden`` ``(T, k)`` that lies off the figure onto it, or
    toward it, by at most its joint's ``limit`` (pixels, ``(k,)``; :func:`onto_figure`), in place;
    ``P`` is ``(T, k, 2)``."""
    for t in np.flatnonzero(hidden.any(axis=1)):
        near = figure.near(int(t))
        for m in np.flatnonzero(hidden[t]):
            P[t, m] = onto_figure(near, P[t, m], float(limit[m]), pull=figure.tuning.pull_reach)


def figure_cells(near: NDArray[np.uint8], centre: NDArray[np.float64], angle: float, R: int,
                 step: float = 1.0) -> NDArray[np.bool_]:
    """Which cells of a ``(2R+1, 2R+1)`` search window round ``centre``, turned by ``angle`` and
    ``step`` pixels apart, lie on the figure: cell ``(i, j)`` is the point
    ``centre + step * rotation(angle) (j - R, i - R)`` (as the tracker's windows lay cells out)."""
    c, s = np.cos(angle), np.sin(angle)
    n = 2 * R + 1
    M = np.array([[step * c, -step * s, centre[0] - step * R * (c - s)],
                  [step * s, step * c, centre[1] - step * R * (s + c)]])
    cells = cv2.warpAffine(near, M, (n, n), flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP,
                           borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return cells > 0
