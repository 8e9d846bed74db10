"""Patches of a frame for the joint tracker (thesis 4.4): a rectangle cut turned at a point
(:func:`sample`, many at once with :func:`patches`), how alike two look (the colour cost's
:func:`confidence`, the light-blind :func:`likeness`), and whether a patch is distinct or textured
enough to track a joint by; each with the :class:`~toonmotion.capture.match_tuning.MatchTuning` it
reads (default its defaults).

Patches are ``(h, w, 3)`` float32 in the rectangle's own frame: patch pixel ``(u, v)`` is the
image at ``centre + rotation(angle) (u - (w-1)/2, v - (h-1)/2)``; (x, y) pixels, y down.
"""

from __future__ import annotations

import itertools
import math

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.match_tuning import MatchTuning

_WARP = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP


_REMAP_ROWS = 32000


Patch = NDArray[np.float32]


def distinct_size(image: NDArray[np.uint8], centre: NDArray[np.float64], size: tuple[int, int],
                  tuning: MatchTuning | None = None) -> tuple[int, int]:
    """The template size to track a joint by: ``size``, grown by half again (at most
    ``tuning.max_growth`` times) while a patch of that size at ``centre`` looks like itself moved
    ``tuning.distinct_shift`` pixels in some direction: the mean squared difference in the
    direction it changes least is under ``tuning.distinct_ratio`` of that in the direction it
    changes most, or under ``tuning.distinct_level`` grey levels squared. A rectangle inside one
    flat colour, or on a straight outline, matches equally anywhere along it; a larger one takes in
    the outline's turns and ends that pin it down (the "good features to track" criterion,
    applied to the rectangle's size). A round outline changes few pixels when moved, but as many
    every way: it is distinct.

    >>> image = np.full((80, 80, 3), 200, np.uint8); image[:, 40:] = 40  # a straight edge
    >>> image[60:, :] = 120  # a corner 20 px below
    >>> on_edge, at_corner = np.array([40.0, 40.0]), np.array([40.0, 60.0])
    >>> distinct_size(image, on_edge, (12, 12)), distinct_size(image, at_corner, (12, 12))
    ((36, 36), (12, 12))
    """
    tuning = MatchTuning() if tuning is None else tuning
    w0, h0 = size
    for growth in _growths(tuning.max_growth):
        grown = (max(1, int(round(w0 * growth))), max(1, int(round(h0 * growth))))
        if is_distinct(image, centre, grown, tuning):
            break
    return grown


def _growths(most: float) -> tuple[float, ...]:
    """1, 1.5, 2.25, ... (half again each time) while under ``most``, then ``most`` (>= 1).

    >>> _growths(3.0), _growths(1.0)
    ((1.0, 1.5, 2.25, 3.0), (1.0,))
    """
    growths = itertools.takewhile(lambda growth: growth < most, (1.5**i for i in itertools.count()))
    return (*growths, most)


def is_distinct(image: NDArray[np.uint8], centre: NDArray[np.float64], size: tuple[int, int],
                tuning: MatchTuning | None = None) -> bool:
    """Whether a ``size`` patch of ``image`` at ``centre`` looks unlike itself moved
    ``tuning.distinct_shift`` pixels every way (:func:`distinct_size`).

    >>> image = np.full((80, 80, 3), 200, np.uint8); image[:, 40:] = 40  # a straight edge
    >>> image[60:, :] = 120  # a corner 20 px below
    >>> on_edge, at_corner = np.array([40.0, 40.0]), np.array([40.0, 60.0])
    >>> is_distinct(image, on_edge, (12, 12)), is_distinct(image, at_corner, (12, 12))
    (False, True)
    """
    tuning = MatchTuning() if tuning is None else tuning
    shift = tuning.distinct_shift
    patch = sample(image, centre, 0.0, size)
    change = [float(np.mean((sample(image, centre + shift * np.array([math.cos(a), math.sin(a)]),
                                    0.0, size) - patch) ** 2))
              for a in np.arange(8) * math.pi / 4]
    return min(change) >= max(tuning.distinct_ratio * max(change), tuning.distinct_level**2)


def is_textured(patch: Patch, tuning: MatchTuning | None = None) -> bool:
    """Whether a template ``(h, w, 3)`` has a texture of its own: at least
    ``tuning.textured_fraction`` of its pixels change by more than ``tuning.texture_level`` grey
    levels when it is moved ``tuning.distinct_shift`` pixels (the mean of the fractions along x and
    y).

    >>> flat = np.full((20, 20, 3), 200, np.float32); flat[:, 9:12] = 20  # a fill and an outline
    >>> noise = np.random.default_rng(0).uniform(0, 255, (20, 20, 3)).astype(np.float32)
    >>> is_textured(flat), is_textured(noise)
    (False, True)
    """
    tuning = MatchTuning() if tuning is None else tuning
    d, level = tuning.distinct_shift, tuning.texture_level
    along_x = np.abs(patch[:, d:] - patch[:, :-d]).max(axis=2) > level
    along_y = np.abs(patch[d:] - patch[:-d]).max(axis=2) > level
    return bool((along_x.mean() + along_y.mean()) / 2 >= tuning.textured_fraction)


def patches(image, centres, angles, size):
    """``(n, h, w, 3)`` float32 patches of ``size = (w, h)`` at ``centres`` ``(n, 2)``, each turned
    by its angle, as :func:`sample` cuts one: one ``cv2.remap`` for them all."""
    w, h = size
    u = np.arange(w, dtype=np.float32) - (w - 1) / 2
    v = np.arange(h, dtype=np.float32) - (h - 1) / 2
    c, s = np.cos(angles).astype(np.float32), np.sin(angles).astype(np.float32)
    cx, cy = centres[:, 0].astype(np.float32), centres[:, 1].astype(np.float32)
    map_x = cx[:, None, None] + c[:, None, None] * u[None, None, :] - s[:, None, None] * v[None, :, None]
    map_y = cy[:, None, None] + s[:, None, None] * u[None, None, :] + c[:, None, None] * v[None, :, None]
    # cv2.remap takes maps under 32767 rows: the patches go in batches stacked that high at most.
    n, batch = len(centres), max(1, _REMAP_ROWS // h)
    out = np.empty((n, h, w, 3), np.float32)
    for i in range(0, n, batch):
        j = min(n, i + batch)
        rows = cv2.remap(image, map_x[i:j].reshape(-1, w), map_y[i:j].reshape(-1, w), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)
        out[i:j] = rows.reshape(j - i, h, w, 3)
    return out


def confidence(ssd: float, size: tuple[int, int], tuning: MatchTuning | None = None) -> float:
    """Confidence of a match whose sum of squared RGB differences over a ``size`` rectangle is ``ssd``.

    ``exp(-d^2 / (2 s^2))``, ``d`` the root mean square difference per channel, ``s``
    ``tuning.confidence_scale``.

    >>> round(confidence(20.0**2 * 3 * 4, (2, 2)), 2)  # 20 grey levels off in every channel
    0.8
    """
    scale = (MatchTuning() if tuning is None else tuning).confidence_scale
    return math.exp(-ssd / (size[0] * size[1] * 3) / (2 * scale**2))


def likeness(template: Patch, patch: Patch) -> float:
    """How alike two patches of one size look, whatever the light: their normalized cross-correlation
    with each channel's mean taken off (1 alike, 0 unrelated, -1 a negative; 0 if either is flat).
    A patch made brighter or darker, or of more or less contrast, is as alike as it was.

    >>> patch = np.arange(12, dtype=np.float32).reshape(2, 2, 3)
    >>> round(likeness(patch, 0.5 * patch + 40), 6), round(likeness(patch, -patch), 6)
    (1.0, -1.0)
    """
    # From sums OpenCV takes in double precision (this runs for every textured joint and frame:
    # the same sums in numpy took seven times as long; cv2.matchTemplate's TM_CCOEFF_NORMED gives
    # the same value in 33 us against 5).
    n = template.shape[0] * template.shape[1]
    mean_a, mean_b = cv2.mean(template)[:3], cv2.mean(patch)[:3]
    aa, bb = cv2.norm(template, cv2.NORM_L2SQR), cv2.norm(patch, cv2.NORM_L2SQR)
    ab = (aa + bb - cv2.norm(template, patch, cv2.NORM_L2SQR)) / 2
    spread_a = aa - n * sum(a * a for a in mean_a)
    spread_b = bb - n * sum(b * b for b in mean_b)
    if not (spread_a > 1e-9 * aa and spread_b > 1e-9 * bb):
        return 0.0
    return (ab - n * sum(a * b for a, b in zip(mean_a, mean_b, strict=True))) / math.sqrt(spread_a * spread_b)


def ssd_at(confidence: float, size: tuple[int, int], tuning: MatchTuning | None = None) -> float:
    """The sum of squared differences that has ``confidence``: inverse of :func:`confidence`."""
    scale = (MatchTuning() if tuning is None else tuning).confidence_scale
    return -math.log(confidence) * 2 * scale**2 * size[0] * size[1] * 3


def sample(image: NDArray[np.uint8] | Patch, centre: NDArray[np.float64], angle: float,
           size: tuple[int, int]) -> Patch:
    """``(h, w, 3)`` float32 patch of ``size = (w, h)`` centred on ``centre``, turned by ``angle``.

    Patch pixel ``(u, v)`` is the image at ``centre + rotation(angle) (u - (w-1)/2, v - (h-1)/2)``,
    bilinear; pixels beyond the image repeat its border.

    >>> image = np.arange(16, dtype=np.uint8).repeat(3).reshape(4, 4, 3)
    >>> sample(image, np.array([1.5, 1.5]), 0.0, (2, 2))[..., 0].tolist()
    [[5.0, 6.0], [9.0, 10.0]]
    """
    w, h = size
    # The affine map is built by hand: this runs for every joint and frame.
    c, s = math.cos(angle), math.sin(angle)
    hx, hy = (w - 1) / 2, (h - 1) / 2
    M = np.array([[c, -s, centre[0] - c * hx + s * hy], [s, c, centre[1] - s * hx - c * hy]])
    patch = cv2.warpAffine(image, M, (w, h), flags=_WARP, borderMode=cv2.BORDER_REPLICATE)
    return patch.astype(np.float32)
