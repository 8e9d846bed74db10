"""Foreground masks: from an alpha channel, a separate mask image, or found automatically.

Automatic segmentation handles the two backgrounds drawings come on:

* **flat** (digital art on one colour): every pixel far enough from the border's colour is
  foreground;
* **paper** (photographed pencil, marker or crayon): ink is what is darker than its
  surroundings (a local-mean threshold, robust to uneven lighting); the ink is closed and
  grown a little, and everything it encloses is foreground. This follows the Animated
  Drawings project's recipe, which its hand-checked masks were made from.

Either way, only regions not connected to the image border count, and specks are dropped.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage as ndi

from toonmotion import limits
from toonmotion.errors import MaskError

METHODS = ("auto", "flat", "paper")

_SQUARE = np.ones((3, 3), dtype=bool)


def mask_from_alpha(alpha: ArrayLike, *, threshold: int = 128) -> NDArray[np.bool_] | None:
    """Foreground where alpha >= ``threshold``; ``None`` when the image is fully opaque.

    Parameters
    ----------
    alpha : (h, w) uint8
    """
    alpha = np.asarray(alpha)
    if alpha.min() >= 255:
        return None
    return alpha >= threshold


def segment_foreground(rgb: ArrayLike, *, method: str = "auto", block: int = 115, offset: float = 8.0,
                       flat_tolerance: float = 24.0) -> NDArray[np.bool_]:
    """Find the figure in an image that has no alpha channel.

    Parameters
    ----------
    rgb : (h, w, 3) uint8
    method : {"auto", "flat", "paper"}
        "auto" picks "flat" when the image border is (nearly) one colour, else "paper".
    block : int
        Side of the window, in pixels, over which "paper" estimates the local paper tone.
    offset : float
        How much darker than the local mean (0–255 grey levels) a pixel must be to be ink.
    flat_tolerance : float
        RGB distance from the background colour above which a pixel is foreground ("flat").

    Returns
    -------
    (h, w) bool
        Foreground mask, holes filled. Validate it with :func:`check_mask`.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    rgb = np.asarray(rgb)
    if method == "auto":
        method = "flat" if _border_is_flat(rgb) else "paper"
    if method == "flat":
        background = np.median(_border_pixels(rgb), axis=0)
        distance = np.linalg.norm(rgb.astype(np.float32) - background.astype(np.float32), axis=2)
        ink = distance > flat_tolerance
    else:
        ink = _dark_ink(rgb, block=block, offset=offset)
        ink = ndi.binary_closing(ink, _SQUARE, iterations=2, border_value=0)
        ink = ndi.binary_dilation(ink, _SQUARE, iterations=2)
    # Ink plus every background region (4-connected) that does not touch the image border.
    return ndi.binary_fill_holes(ink)


# Fewer figure pixels than this (an 8x8 square) cannot be meshed into a figure worth posing.
MIN_FIGURE_PIXELS = 64


def check_mask(mask: NDArray[np.bool_], *, what: str = "mask") -> None:
    """Raise :class:`MaskError` unless ``mask`` has a figure of some size and some background."""
    count = int(np.count_nonzero(mask))
    if count == 0:
        raise MaskError(
            f"the {what} is empty: no foreground pixels were found; "
            "give a mask image with --mask, or a PNG whose alpha marks the figure"
        )
    if count < MIN_FIGURE_PIXELS:
        raise MaskError(
            f"the {what} marks only {count} figure pixels, too few to rig (at least "
            f"{MIN_FIGURE_PIXELS}); give a larger drawing or a mask that covers the figure"
        )
    if count == mask.size:
        raise MaskError(
            f"the {what} covers the whole image, so no background was found; "
            "crop the drawing with some margin of background, or give a mask with --mask"
        )


def clean_mask(mask: NDArray[np.bool_], *, min_fraction: float = 0.01,
               largest_only: bool = False) -> NDArray[np.bool_]:
    """Drop specks: 8-connected parts smaller than ``min_fraction`` of the largest part.

    With ``largest_only`` only the largest part is kept.
    """
    labels, count = ndi.label(mask, structure=_SQUARE)
    if count == 0:
        return np.asarray(mask, dtype=bool).copy()
    sizes = np.bincount(labels.ravel())[1:]
    keep = np.zeros(count + 1, dtype=bool)
    if largest_only:
        keep[1 + int(np.argmax(sizes))] = True
    else:
        keep[1:] = sizes >= min_fraction * sizes.max()
    limits.check("figure_parts", int(np.count_nonzero(keep)), "the number of separate parts in the figure",
                 hint="the mask is speckled (a dithered alpha?): clean it, or keep one with --largest-only")
    return keep[labels]


def _border_pixels(rgb):
    return np.concatenate([rgb[0], rgb[-1], rgb[:, 0], rgb[:, -1]]).reshape(-1, rgb.shape[2])


def _border_is_flat(rgb, *, spread=6.0, share=0.95):
    border = _border_pixels(rgb).astype(np.float32)
    distance = np.linalg.norm(border - np.median(border, axis=0), axis=1)
    return float(np.mean(distance <= spread)) >= share


def _dark_ink(rgb, *, block, offset):
    grey = rgb[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
    local_mean = ndi.uniform_filter(grey, size=block, mode="reflect")
    return grey <= local_mean - offset
