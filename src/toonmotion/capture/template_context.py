"""A joint's wider view: where its rectangle sees only a flat fill, the figure round it places it.

A joint inside a flat fill (a torso on a plain body, a knee on plain trousers) matches equally
well anywhere along the fill: its own templates cannot say where it is, and
:class:`~toonmotion.capture.track_search.FrameSearch` calls it *ambiguous* and places it among the
places that match as well, where its neighbours carry it. When its neighbours are inside the fill
too, they cannot say either, and the whole group drifts (a drawing's torso, neck and shoulders
on one grey body went 146 px off). Its *context* is a square round it ``context_growth``
times its rectangle's larger side (larger still where that is not distinct), cut with its
anchor where tracking started, at the level of the frame's Gaussian pyramid (``cv2.pyrDown``)
where the square is at most ``context_side`` pixels wide: there it takes in the fill's
outline and what lies round it. It is matched near the joint's match at the rectangle's angle
and at ``context_turns`` more (a root's rectangle does not turn, but a body leans), and where
it matches at least ``context_confidence``, next to a place alike to the joint's match, it
places the joint (each of :class:`~toonmotion.capture.match_tuning.MatchTuning`, given as
``tuning``). A figure whose parts move within the square (legs folding under the hips in a
squat) matches it badly there, and the neighbours decide, as before.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.joint_plan import Context, Templates
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.patches import confidence, distinct_size, is_distinct, sample


class Pyramid:
    """A frame and its Gaussian pyramid (``cv2.pyrDown`` level after level), each level made when
    first asked for."""

    def __init__(self, image: NDArray[np.uint8]) -> None:
        self._levels = [image]

    def level(self, n: int) -> NDArray[np.uint8]:
        """The frame at level ``n`` (0: as given), ``(h / 2^n, w / 2^n, 3)`` uint8."""
        while len(self._levels) <= n:
            self._levels.append(np.asarray(cv2.pyrDown(self._levels[-1]), np.uint8))
        return self._levels[n]


def at_level(xy: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Full-resolution ``(x, y)`` pixels in :class:`Pyramid` level ``n``'s pixels: ``cv2.pyrDown``
    centres its pixel ``i`` on pixel ``2 i`` of the level below.

    >>> image = np.zeros((64, 64, 3), np.uint8); image[30, 41] = 255  # a dot at x 41, y 30
    >>> low = Pyramid(image).level(2)[..., 0].astype(float)
    >>> y, x = np.mgrid[:16, :16]
    >>> seen = [(low * x).sum() / low.sum(), (low * y).sum() / low.sum()]
    >>> at_level(np.array([41.0, 30.0]), 2), bool(np.allclose(seen, [10.25, 7.5], atol=0.05))
    (array([10.25,  7.5 ]), True)
    """
    return np.asarray(xy, dtype=float) / 2.0**n


def cut_context(pyramid: Pyramid, centre: NDArray[np.float64], angle: float, size: tuple[int, int],
                tuning: MatchTuning | None = None) -> Context | None:
    """The context of a ``size`` rectangle at ``centre`` turned by ``angle`` radians, grown further
    where it is not distinct (:func:`~toonmotion.capture.patches.distinct_size`); None where
    it is not distinct even so (all inside a fill, it would match anywhere in it). ``tuning``
    default its defaults.
    """
    tuning = MatchTuning() if tuning is None else tuning
    centre = np.asarray(centre, dtype=float)
    grown = round(tuning.context_growth * max(size))
    side = max(distinct_size(pyramid.level(0), centre, (grown, grown), tuning))
    if not is_distinct(pyramid.level(0), centre, (side, side), tuning):
        return None
    level = max(0, math.ceil(math.log2(side / tuning.context_side)))
    s = max(1, round(side / 2**level))
    return Context(sample(pyramid.level(level), at_level(centre, level), angle, (s, s)), level)


def cut_templates(pyramid: Pyramid, centre: NDArray[np.float64], angle: float, size: tuple[int, int],
                  tuning: MatchTuning | None = None) -> Templates:
    """A joint's templates cut from the frame ``pyramid`` holds, with its :class:`Context` (if it
    has one)."""
    return replace(Templates.cut(pyramid.level(0), centre, angle, size),
                   context=cut_context(pyramid, centre, angle, size, tuning))


def place_by_context(pyramid: Pyramid, context: Context, centre: NDArray[np.float64], angle: float,
                     radius: float, tuning: MatchTuning | None = None) -> tuple[NDArray[np.float64], float]:
    """Where ``context`` matches best within ``radius`` pixels of ``centre`` (full resolution), its
    rectangle turned by ``angle`` and by each of ``tuning.context_turns`` more (default its
    defaults).

    Returns
    -------
    xy : (2,) float
        The joint's place there, full-resolution (x, y) pixels, to within a fraction of a level's pixel.
    confidence : float
        How well the context matches there (:func:`~toonmotion.capture.patches.confidence`).

    Examples
    --------
    A disc on a plain ground, moved 9 px right and turned, is found again by the context of a
    rectangle inside it, whose own look is one flat colour:

    >>> ground = np.full((200, 240, 3), 230, np.uint8)
    >>> first, later = ground.copy(), ground.copy()
    >>> _ = cv2.ellipse(first, (100, 100), (60, 40), 0, 0, 360, (40, 90, 200), -1)
    >>> _ = cv2.ellipse(later, (109, 100), (60, 40), 8, 0, 360, (40, 90, 200), -1)
    >>> context = cut_context(Pyramid(first), np.array([100.0, 100.0]), 0.0, (16, 16))
    >>> xy, sure = place_by_context(Pyramid(later), context, np.array([104.0, 100.0]), 0.0, 24.0)
    >>> bool(np.hypot(*(xy - [109.0, 100.0])) < 2.0), sure > MatchTuning().context_confidence
    (True, True)

    On the plain ground alone, however large, no context is distinct: none is cut.

    >>> cut_context(Pyramid(ground), np.array([100.0, 100.0]), 0.0, (16, 16)) is None
    True
    """
    tuning = MatchTuning() if tuning is None else tuning
    n, patch = context.level, context.patch
    s = patch.shape[0]
    R = max(1, math.ceil(radius / 2**n))
    image, middle = pyramid.level(n), at_level(centre, n)
    best: tuple[float, float, float, float] | None = None  # ssd, dx, dy (level pixels), angle
    for turn in tuning.context_turns:
        window = sample(image, middle, angle + turn, (s + 2 * R, s + 2 * R))
        ssd = cv2.matchTemplate(window, patch, cv2.TM_SQDIFF)
        i, j = divmod(int(np.argmin(ssd)), 2 * R + 1)
        if best is None or ssd[i, j] < best[0]:
            dx, dy = _vertex(ssd[i, j - 1:j + 2]), _vertex(ssd[i - 1:i + 2, j])
            best = (float(ssd[i, j]), j - R + dx, i - R + dy, angle + turn)
    assert best is not None
    least, dx, dy, turned = best
    c, s_ = math.cos(turned), math.sin(turned)
    offset = 2.0**n * np.array([c * dx - s_ * dy, s_ * dx + c * dy])
    return np.asarray(centre, dtype=float) + offset, confidence(least, (s, s), tuning)


def _vertex(costs: NDArray[Any]) -> float:
    """Sub-cell offset of a parabola's lowest point through three costs at -1, 0, 1 (at most half a
    cell; 0 at the map's edge, where fewer than three are given, or on a flat cost)."""
    if len(costs) < 3:
        return 0.0
    before, centre, after = (float(c) for c in costs)
    k = before + after - 2.0 * centre
    return 0.0 if not k > 0 else min(0.5, max(-0.5, (before - after) / (2.0 * k)))
