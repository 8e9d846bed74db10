"""Large footage tracked at a working resolution: halved until it is at most :data:`WORKING_SIDE`
pixels on its larger side.

The tracker's values in pixels (the largest rectangle it suggests, ``FigureTuning.size_high``;
the context's width, ``MatchTuning.context_side``; the slack round the figure,
``ClipTuning.figure_slack``) were chosen on frames up to 640 x 480, and the cost of a match
grows with the square of its rectangle's side. A 1920 x 1080 video is tracked at 960 x 540, every
rectangle and window halved with it: four times fewer pixels to match, the rectangles of the sizes
the tracker was made for, and the joints' places given back in the frames' own pixels. On the
rendered clips at 1280 x 960 this tracked 2.0-3.2 times as fast, as close to the truth
(docs/capture.md, "Large footage").

A frame halved ``n`` times is level ``n`` of its Gaussian pyramid
(:class:`~toonmotion.capture.template_context.Pyramid`: ``cv2.pyrDown``, a blur then every other
pixel, once per halving), so a place ``xy`` in the frame is
:func:`~toonmotion.capture.template_context.at_level` ``(xy, n)``, ``xy / 2^n``, whatever the
frame's size, odd or even.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.template_context import Pyramid
from toonmotion.capture.track_checks import Frames, read_frame
from toonmotion.capture.track_figure import check_mask

# Frames larger than this on their larger side (pixels) are tracked halved, as many times as it
# takes to fit.
WORKING_SIDE = 1000


def halvings(frame_size: tuple[float, float], side: float | None = WORKING_SIDE) -> int:
    """How many times a frame of ``frame_size`` ``(width, height)`` is halved to be at most
    ``side`` pixels on its larger side (None: never).

    >>> [halvings(size) for size in ((640, 480), (1280, 960), (1920, 1080), (3840, 2160))]
    [0, 1, 1, 2]
    >>> halvings((1920, 1080), None), halvings((1920, 1080), 480)
    (0, 2)
    """
    if side is None:
        return 0
    n, larger = 0, max(frame_size)
    while larger > side:
        n, larger = n + 1, larger / 2
    return n


def reduce(image: NDArray[Any], n: int) -> NDArray[Any]:
    """``image`` halved ``n`` times by ``cv2.pyrDown``: ``((h + 1) // 2, (w + 1) // 2, ...)`` each
    time; a bool mask is reduced as 0 and 1 and kept where at least half of it was figure.

    >>> mask = np.zeros((8, 6), bool); mask[:4] = True  # the top half
    >>> reduce(mask, 1).astype(int)
    array([[1, 1, 1],
           [1, 1, 1],
           [0, 0, 0],
           [0, 0, 0]])
    >>> reduce(np.zeros((1080, 1920, 3), np.uint8), 2).shape
    (270, 480, 3)
    """
    if image.dtype == bool:
        return reduce(np.ascontiguousarray(image).view(np.uint8) * np.uint8(255), n) >= 128
    return Pyramid(image).level(n)


class ReducedFrames(Sequence):
    """``frames`` each halved ``n`` times as it is read (:func:`reduce`), after checking it is an
    RGB frame of shape ``shape`` (:func:`~toonmotion.capture.track_checks.read_frame`), so a wrong
    one is named in the frames' own pixels."""

    def __init__(self, frames: Frames, n: int, shape: tuple[int, ...]) -> None:
        self._frames, self._n, self._shape = frames, n, tuple(shape)

    def __len__(self) -> int:
        return len(self._frames)

    def __getitem__(self, t):
        return reduce(read_frame(self._frames, t, self._shape), self._n)


class ReducedMasks(Sequence):
    """Figure masks each halved ``n`` times as read, after checking each is of the frames' own
    size ``shape`` ``(h, w, ...)`` (:func:`~toonmotion.capture.track_figure.check_mask`), so a
    wrong one is named in the frames' pixels."""

    def __init__(self, masks: NDArray[np.bool_] | Sequence[NDArray[np.bool_]], n: int,
                 shape: tuple[int, ...]) -> None:
        self._masks, self._n, self._shape = masks, n, tuple(shape[:2])

    def __len__(self) -> int:
        return len(self._masks)

    def __getitem__(self, t):
        mask = check_mask(np.asarray(self._masks[t]), t, self._shape)
        return reduce(mask if mask.dtype == bool else mask != 0, self._n)


def from_working(points: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Places found after ``n`` halvings, in the frames' own pixels: the inverse of
    :func:`~toonmotion.capture.template_context.at_level`.

    >>> from toonmotion.capture.template_context import at_level
    >>> from_working(at_level(np.array([[7.0, 3.5]]), 2), 2).tolist()
    [[7.0, 3.5]]
    """
    return np.asarray(points, dtype=float) * 2**n


def working_weight(w_beta: float | None, n: int) -> float | None:
    """A weight per squared pixel of the frames (eq. 4.6's ``w_beta``) per squared pixel after
    ``n`` halvings, where the same distance is ``2^n`` times fewer pixels; None stays None (``1 /
    r^2``, which scales with the window)."""
    return None if w_beta is None else w_beta * 4.0**n

