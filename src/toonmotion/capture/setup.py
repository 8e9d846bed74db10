"""The joints to track and the rectangle around each (thesis 4.3).

In the thesis the animator marks each joint of frame 1 with a small rectangle, guided by the
curve skeleton; the rectangle is the texture the joint is tracked by. :func:`suggest_setup`
proposes such a setup to start from (or to use as it is): joints where
:func:`~toonmotion.rig.auto_skeleton.skeleton_from_curve_skeleton` puts them (the ends of the
curve skeleton's branches, its junctions and evenly along long branches), each with a square
as wide as the figure is thick there: twice the largest distance to the outline within 3 px
of the joint (within a few pixels, since a branch's end point sits near the tip, where the
figure is thinnest), clamped to [8, 48] px, so small joints still have some texture and big
ones do not drag in much of the background. These values are
:class:`~toonmotion.capture.figure_tuning.FigureTuning`'s ``thickness_reach``, ``size_low`` and
``size_high`` (with ``frame_side``), given as ``tuning`` (default its defaults).

Rectangles: ``sizes[j] = (width, height)`` in pixels, centred on joint ``j``. Integer
coordinates are pixel centres, so a ``w`` x ``h`` frame spans ``[-0.5, w - 0.5]`` x
``[-0.5, h - 0.5]``, and a rectangle must lie within that span: ``x - width / 2 >= -0.5`` and
``x + width / 2 <= w - 0.5``, likewise in y. Suggested rectangles are shrunk, about their
joint, until they do.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage as ndi

from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.capture.foreground import guide_skeleton
from toonmotion.capture.track_scale import halvings
from toonmotion.errors import TrackingError
from toonmotion.rig.auto_skeleton import skeleton_from_curve_skeleton
from toonmotion.rig.skeleton import Skeleton

_EPS = 1e-9


def suggest_setup(mask: NDArray[np.bool_], *, max_bone: float | None = None, prune: float = 0.5,
                  tuning: FigureTuning | None = None) -> tuple[Skeleton, NDArray[np.float64]]:
    """Joints to track on frame 1, from its curve skeleton, and a rectangle for each.

    Parameters
    ----------
    mask : (h, w) bool
        Frame 1's foreground.
    max_bone : float, optional
        Longest bone in pixels (longer branches get joints along them); default a fifth of the
        curve skeleton's bounding-box diagonal.
    prune : float
        Spur pruning of the curve skeleton.
    tuning : FigureTuning, optional
        The rectangles' sizes (:func:`rectangle_sizes`); default its defaults.

    Returns
    -------
    skeleton : Skeleton
        Joints at frame 1's positions, (x, y) pixels, y down.
    sizes : (k, 2) float
        Width and height of each joint's rectangle, in skeleton joint order; every rectangle
        lies inside the frame.

    Examples
    --------
    A bar 12 px thick, touching the frame's left edge: the rectangle of the joint at its left
    end is narrowed to fit.

    >>> mask = np.zeros((40, 120), bool); mask[14:26, 0:110] = True
    >>> skeleton, sizes = suggest_setup(mask, max_bone=40)
    >>> skeleton.positions[:, 0].round().tolist(), sizes.tolist()
    ([54.0, 82.0, 107.0, 26.0, 1.0], [[12.0, 12.0], [12.0, 12.0], [10.0, 10.0], [12.0, 12.0], [3.0, 8.0]])
    """
    mask = np.asarray(mask, dtype=bool)
    skeleton = skeleton_from_curve_skeleton(guide_skeleton(mask, prune=prune), max_bone=max_bone)
    return skeleton, rectangle_sizes(mask, skeleton.positions, tuning)


def rectangle_sizes(mask: NDArray[np.bool_], positions: NDArray[np.float64],
                    tuning: FigureTuning | None = None) -> NDArray[np.float64]:
    """The tracking rectangle :func:`suggest_setup` gives a joint at each of ``positions``
    ``(k, 2)`` on the figure ``mask`` ``(h, w)``: a square twice the figure's local thickness (the
    largest distance to its outline within ``tuning.thickness_reach`` px), within
    ``tuning.size_low`` to ``tuning.size_high`` (times :func:`size_scale` of the frame), shrunk
    about the joint to lie inside the frame. ``(k, 2)`` widths and heights, pixels; ``tuning``
    default its defaults.

    >>> mask = np.zeros((40, 120), bool); mask[14:26, 0:110] = True
    >>> rectangle_sizes(mask, np.array([[54.0, 19.5]])).tolist()
    [[12.0, 12.0]]

    A body 200 px thick gets the range's largest square, twice as large on a frame twice as
    large as ``tuning.frame_side``:

    >>> body = np.zeros((600, 800), bool); body[200:400, 100:700] = True
    >>> large = np.zeros((1200, 1600), bool); large[400:800, 200:1400] = True
    >>> rectangle_sizes(body, np.array([[400.0, 300.0]])).tolist()
    [[48.0, 48.0]]
    >>> rectangle_sizes(large, np.array([[800.0, 600.0]])).tolist()
    [[96.0, 96.0]]
    """
    tuning = FigureTuning() if tuning is None else tuning
    mask = np.asarray(mask, dtype=bool)
    positions = np.asarray(positions, dtype=float)
    h, w = mask.shape
    # Largest distance to the outline within thickness_reach px of each pixel.
    reach = 2 * tuning.thickness_reach + 1
    radius = ndi.maximum_filter(ndi.distance_transform_edt(mask), size=reach, mode="constant")
    cols = np.clip(np.rint(positions[:, 0]).astype(int), 0, w - 1)
    rows = np.clip(np.rint(positions[:, 1]).astype(int), 0, h - 1)
    scale = size_scale((w, h), tuning)
    side = np.clip(2.0 * radius[rows, cols], tuning.size_low * scale, tuning.size_high * scale)
    sizes = np.stack([side, side], axis=1)
    # Shrink about the joint until the rectangle is inside the frame.
    room = 2.0 * np.minimum(positions + 0.5, np.array([w, h]) - 0.5 - positions)
    return np.minimum(sizes, np.maximum(room, 0.0))


def size_scale(frame_size: tuple[float, float], tuning: FigureTuning | None = None) -> float:
    """How many times the size range a suggested rectangle's size is on a frame of ``frame_size``
    ``(width, height)``: 1 up to ``tuning.frame_side`` pixels on its larger side (default the
    tracker's working side), doubling each time the frame does beyond that (the tracker halves the
    frame as many times, :func:`~toonmotion.capture.track_scale.halvings`).

    >>> [size_scale(size) for size in ((640, 480), (1280, 960), (1920, 1080), (3840, 2160))]
    [1.0, 2.0, 2.0, 4.0]
    """
    return 2.0 ** halvings(frame_size, (FigureTuning() if tuning is None else tuning).frame_side)


def check_setup(skeleton: Skeleton, sizes: ArrayLike, frame_size: Sequence[int]) -> None:
    """Raise :class:`TrackingError` unless every joint's rectangle is usable in the frame.

    Parameters
    ----------
    skeleton : Skeleton
        The joints, at their positions in the frame tracking starts from.
    sizes : (k, 2) float
        Width and height of each joint's rectangle, in skeleton joint order.
    frame_size : (width, height)
        The frames' size in pixels.

    Raises
    ------
    TrackingError
        When ``sizes`` is not ``(k, 2)``, a size is not finite or not positive, or a rectangle
        is not wholly inside the frame.
    """
    sizes = np.asarray(sizes, dtype=float)
    k = len(skeleton)
    if sizes.shape != (k, 2):
        raise TrackingError(
            f"give a (width, height) for each of the {k} joints; got sizes of shape {sizes.shape}"
        )
    try:
        w, h = (float(v) for v in frame_size)
    except (TypeError, ValueError):
        raise TrackingError(f"the frame size must be (width, height), got {frame_size!r}") from None
    for name, (x, y), (sw, sh) in zip(skeleton.names, skeleton.positions, sizes, strict=True):
        if not (np.isfinite(sw) and np.isfinite(sh) and sw > 0 and sh > 0):
            raise TrackingError(
                f"joint {name!r} has rectangle size {sw:g}x{sh:g}; give a width and height above 0"
            )
        x0, y0, x1, y1 = x - sw / 2, y - sh / 2, x + sw / 2, y + sh / 2
        if x0 < -0.5 - _EPS or y0 < -0.5 - _EPS or x1 > w - 0.5 + _EPS or y1 > h - 0.5 + _EPS:
            raise TrackingError(
                f"the rectangle of joint {name!r}, ({x0:g}, {y0:g}) to ({x1:g}, {y1:g}), is not inside the "
                f"{w:g}x{h:g} frame (which spans -0.5 to {w - 0.5:g}, -0.5 to {h - 0.5:g}); "
                "move the joint inwards or make its rectangle smaller"
            )
