"""Alpha compositing: premultiplied colour over a background, back to straight-alpha RGBA.

Premultiplied colour here is float32 in the units of :func:`premultiply`: ``(r a, g a, b a,
255 a)`` for straight ``(r, g, b, a)`` in 0-255, so every channel runs 0 to 65025 and a pixel
made from uint8 values holds exact integers. Blending and resampling are done in these units
(colours of transparent pixels then weigh nothing), and :func:`over` turns the result into
straight-alpha uint8, over a background or not.

>>> rgba = np.array([[200, 100, 0, 255], [200, 100, 0, 51], [0, 0, 0, 0]], np.uint8)
>>> over(premultiply(rgba), (255, 255, 255)).tolist()  # an opaque white background
[[200, 100, 0, 255], [244, 224, 204, 255], [255, 255, 255, 255]]
>>> over(premultiply(rgba)).tolist()  # no background: straight alpha again
[[200, 100, 0, 255], [200, 100, 0, 51], [0, 0, 0, 0]]
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import cast

import cv2
import numpy as np
from numpy.typing import NDArray


def premultiply(rgba: NDArray[np.uint8]) -> NDArray[np.float32]:
    """Premultiplied float32 ``(r a, g a, b a, 255 a)`` of straight RGBA, integers 0-65025.

    Parameters
    ----------
    rgba : (..., 4) uint8
        Straight alpha.

    Returns
    -------
    (..., 4) float32
    """
    flat = np.ascontiguousarray(rgba).reshape(-1, 4)
    scale = np.empty_like(flat)
    scale[:, :3] = flat[:, 3:]
    scale[:, 3] = 255
    product = cast(NDArray[np.float32], cv2.multiply(flat, scale, dtype=cv2.CV_32F))
    return product.reshape(np.shape(rgba))


def over(src: NDArray[np.float32], background: Sequence[int] | NDArray[np.uint8] | None = None
         ) -> NDArray[np.uint8]:
    """Composite premultiplied pixels over a background ("over"); straight-alpha RGBA uint8.

    Parameters
    ----------
    src : (k, 4) float32
        Premultiplied colour in the units of :func:`premultiply`. Overwritten.
    background : (r, g, b) or (r, g, b, a) ints 0-255, or (k, 4) uint8, optional
        One straight-alpha colour under every pixel, or one under each; None: nothing under
        them (the pixels are only turned back into straight alpha).

    Returns
    -------
    (k, 4) uint8
        Rounded to the nearest level; a pixel of alpha 0 comes out (0, 0, 0, 0).
    """
    p = src
    if len(p) == 0:
        return np.zeros((0, 4), np.uint8)
    if background is None:
        return _unpremultiplied(p, 65025)
    bg = np.asarray(background)
    if bg.ndim == 1:
        if len(bg) == 3:
            bg = np.append(bg, 255)
        colour = tuple(int(v) for v in bg)
        # Premultiplied "over" in 0-255 units: p + bg * bg_alpha * (1 - alpha).
        p *= np.float32(1 / 255)
        uncovered = 1 - p[:, 3] * np.float32(1 / 255)
        bga = colour[3] / 255
        for channel, value in enumerate((colour[0] * bga, colour[1] * bga, colour[2] * bga, colour[3])):
            if value:
                p[:, channel] += np.float32(value) * uncovered
        if colour[3] == 255:
            return _rounded(p)  # opaque: no division needed
        return _unpremultiplied(p, 255)
    # One background pixel under each: the same arithmetic, row by row.
    p *= np.float32(1 / 255)
    uncovered = 1 - p[:, 3] * np.float32(1 / 255)
    d = bg.astype(np.float64)
    under = np.empty(p.shape, np.float32)
    under[:, :3] = d[:, :3] * (d[:, 3:] / 255)
    under[:, 3] = d[:, 3]
    p += under * uncovered[:, None]
    opaque = bg[:, 3] == 255
    out = np.empty(p.shape, np.uint8)
    if opaque.any():
        out[opaque] = _rounded(p[opaque])
    if not opaque.all():
        out[~opaque] = _unpremultiplied(p[~opaque], 255)
    return out


def _unpremultiplied(p: NDArray[np.float32], full: int) -> NDArray[np.uint8]:
    """Straight-alpha uint8 ``(k, 4)``: colour * 255 / alpha, alpha * 255 / ``full``; 0 / 0 gives 0.

    Computed here, not by a library's division, whose result for 0 / 0 is its own choice (OpenCV
    4 gave 0, OpenCV 5 gives 255). Products of uint8 levels stay below 2**24, so a pixel made from
    uint8 values comes back exactly.
    """
    out = np.zeros(p.shape, np.float32)
    alpha = p[:, 3:]
    np.divide(p[:, :3] * np.float32(255), alpha, out=out[:, :3], where=alpha > 0)
    np.divide(alpha[:, 0] * np.float32(255), np.float32(full), out=out[:, 3])
    return _rounded(out)


def _rounded(levels: NDArray[np.float32]) -> NDArray[np.uint8]:
    """The nearest uint8 level of each value (halves to even, as ``np.rint``), saturated to 0-255."""
    return np.clip(np.rint(levels), 0, 255).astype(np.uint8)
