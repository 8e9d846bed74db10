"""Frames seen in one light: each frame's brightness and contrast matched to a reference frame's
before the tracker looks at it.

The tracker compares colours by their squared differences (thesis eq. 4.1), and a camera's
exposure or a flickering light moves every colour at once: a joint's anchor, cut in the first
light, stops matching and the joint is taken to be hidden. Each colour channel of a frame is
mapped by a gain and an offset that take its quartiles and median to the reference frame's,
read off a band round the picture's border (``ClipTuning.light_border``), where the figure seldom is, so they
are the background's and do not move with the figure. A frame whose mapping would move no colour
between its quartiles by more than ``ClipTuning.light_tolerance`` grey levels is left exactly as it is,
so footage in steady light is tracked as it always was. A plain border (paper: quartiles closer
than ``ClipTuning.min_spread``) cannot tell gain from offset; its colours are taken to be scaled, as
exposure scales them. The camera must be still enough that the border shows the same background.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.track_checks import Frames, is_rgb_frame


def light_levels(image: NDArray[np.uint8], tuning: ClipTuning | None = None) -> NDArray[np.float64]:
    """Each channel's lower quartile, median and upper quartile, ``(3, 3)`` grey levels (rows are
    channels), from about ``tuning.light_samples`` pixels of a band ``tuning.light_border`` wide
    round the border (every fourth pixel of every fourth row at 640x480; every pixel of a small
    picture, whose levels would otherwise shake with what passes the border).

    >>> image = np.zeros((8, 8, 3), np.uint8); image[:, 4:] = 100
    >>> light_levels(image)[0].tolist()
    [0.0, 0.0, 100.0]
    """
    h, w = image.shape[:2]
    tuning = ClipTuning() if tuning is None else tuning
    band = max(1, int(tuning.light_border * min(h, w)))
    # Every pixel of a small picture's band, every step-th of a large one's: about light_samples.
    step = max(1, int((2 * band * (h + w) / tuning.light_samples) ** 0.5))
    strips = (image[:band:step, ::step], image[h - band::step, ::step],
              image[band:h - band:step, :band:step], image[band:h - band:step, w - band::step])
    sample = np.concatenate([strip.reshape(-1, 3) for strip in strips])[None]
    levels = np.empty((3, 3))
    for c in range(3):
        counts = cv2.calcHist([sample], [c], None, [256], [0, 256]).ravel()
        below = np.cumsum(counts) / counts.sum()
        levels[c] = np.searchsorted(below, [0.25, 0.5, 0.75])
    return levels


def relight(image: NDArray[np.uint8], reference: NDArray[np.float64], tuning: ClipTuning | None = None
            ) -> NDArray[np.uint8]:
    """``image`` with each channel mapped so that its quartiles and median (:func:`light_levels`)
    fall on ``reference``'s, or ``image`` itself where that changes too little to matter (module
    docstring).

    >>> dark = np.tile(np.arange(20, 120, dtype=np.uint8), (8, 1)).repeat(3).reshape(8, 100, 3)
    >>> bright = relight(dark, light_levels(2 * dark))
    >>> int(abs(bright.astype(int) - 2 * dark).max()) <= 2, relight(dark, light_levels(dark)) is dark
    (True, True)
    """
    tuning = ClipTuning() if tuning is None else tuning
    levels = light_levels(image, tuning)
    spread, wanted = levels[:, 2] - levels[:, 0], reference[:, 2] - reference[:, 0]
    # Where the border is plain (paper), its one colour cannot tell gain from offset: light is
    # taken to scale colours, as exposure does.
    contrast = (spread >= tuning.min_spread) & (wanted >= tuning.min_spread)
    gain = np.where(contrast, wanted / np.maximum(spread, 1.0),
                    reference[:, 1] / np.maximum(levels[:, 1], 1.0))
    offset = np.where(contrast, reference[:, 1] - gain * levels[:, 1], 0.0)
    moved = np.abs(gain[:, None] * levels + offset[:, None] - levels)
    if moved.max() <= tuning.light_tolerance:
        return image
    values = np.arange(256, dtype=float)
    table = np.clip(np.rint(gain[None, :] * values[:, None] + offset[None, :]), 0, 255).astype(np.uint8)
    return np.asarray(cv2.LUT(image, table.reshape(1, 256, 3)), dtype=np.uint8)


class Relit(Sequence):
    """``frames`` each seen in the light of ``reference`` (a frame of them): :func:`relight` as
    each is read (``tuning`` as there). Items that are not ``(h, w, 3)`` uint8 arrays pass through
    unchanged, for the tracker's own checks to report."""

    def __init__(self, frames: Frames, reference: NDArray[np.uint8],
                 tuning: ClipTuning | None = None) -> None:
        self._tuning = ClipTuning() if tuning is None else tuning
        self._frames, self._levels = frames, light_levels(reference, self._tuning)

    def __len__(self) -> int:
        return len(self._frames)

    def __getitem__(self, t):
        image = np.asarray(self._frames[t])
        if not is_rgb_frame(image):
            return image
        return relight(np.ascontiguousarray(image), self._levels, self._tuning)
