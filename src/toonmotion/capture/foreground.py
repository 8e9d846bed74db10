"""Background subtraction and the guide skeleton for placing joints (thesis 4.3).

The thesis cuts the character out of every frame with an interactive video cutout tool, then
shows the curve skeleton of frame 1's cut-out as a guide for marking joints. Here the cut-out
is automatic, for the two backgrounds that capture clips come on:

* a **static background** (a fixed camera): the background is the per-pixel median of up to
  25 evenly spaced frames, right wherever the figure covers a pixel in fewer than half of
  them; or give it as an image (a clean plate);
* a **flat colour** (a cartoon on one colour, a green screen): give the colour.

A pixel is foreground when the RGB (Euclidean) distance between its colour and the
background's exceeds a threshold. By default the threshold is Otsu's on frame 0's distances,
the split between "background plus noise" and "figure", clamped to [20, 100] (of 441, black
to white; ``threshold_low`` and ``threshold_high``): 20 stays above video compression noise,
100 keeps a figure close in colour to its background from being thrown away wholesale when the
distances are spread wide.

Each mask is then cleaned: specks (8-connected parts smaller than 1% of the largest part,
``clean_fraction``) are dropped, and holes (background parts not touching the frame's border)
smaller than 1% of the foreground's area are filled; bigger holes, such as the gap between an arm
on the hip and the body, stay. The values named are those of
:class:`~toonmotion.capture.figure_tuning.FigureTuning`, which every function here that reads
one takes as ``tuning`` (default its defaults).
"""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Real
from typing import overload

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage as ndi

from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.errors import TrackingError
from toonmotion.shape.curve_skeleton import CurveSkeleton, curve_skeleton
from toonmotion.shape.segment import clean_mask

_CROSS = ndi.generate_binary_structure(2, 1)


def estimate_background(frames: NDArray[np.uint8], *, samples: int = 25) -> NDArray[np.uint8]:
    """The static background: each pixel's median over evenly spaced frames.

    Parameters
    ----------
    frames : (T, h, w, 3) uint8
    samples : int
        How many frames, evenly spaced from the first to the last, the median is taken over
        (all of them when there are fewer). A pixel comes out right when the figure covers it
        in fewer than half of these.

    Returns
    -------
    (h, w, 3) uint8

    Examples
    --------
    >>> frames = np.zeros((5, 2, 2, 3), np.uint8); frames[1, 0, 0] = 200
    >>> estimate_background(frames)[0, 0].tolist()
    [0, 0, 0]
    """
    frames = _checked_frames(frames)
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ValueError(f"samples must be a positive whole number, got {samples!r}")
    T = len(frames)
    picked = np.unique(np.rint(np.linspace(0, T - 1, min(samples, T))).astype(int))
    out: NDArray[np.uint8] = np.empty(frames.shape[1:], np.uint8)
    for r in range(0, out.shape[0], 64):  # row bands keep the float copy median makes small
        band = np.median(frames[picked, r : r + 64], axis=0)
        out[r : r + 64] = np.rint(band).astype(np.uint8)
    return out


def foreground_masks(frames: NDArray[np.uint8], *, background: ArrayLike | None = None,
                     colour: Sequence[int] | None = None, threshold: float | None = None,
                     tuning: FigureTuning | None = None) -> NDArray[np.bool_]:
    """Where the figure is in each frame: pixels whose colour differs from the background's.

    Parameters
    ----------
    frames : (T, h, w, 3) uint8
    background : (h, w, 3) uint8, optional
        The background image (a clean plate). Default: :func:`estimate_background`, unless
        ``colour`` is given.
    colour : (r, g, b), optional
        A flat background colour, 0-255, instead of a background image.
    threshold : float, optional
        RGB distance (0 to 441) above which a pixel is foreground. Default: Otsu's threshold on
        frame 0's distances, clamped to ``tuning.threshold_low`` to ``tuning.threshold_high``.
    tuning : FigureTuning, optional
        The threshold's range and the cleaning's ``clean_fraction``; default its defaults.

    Returns
    -------
    (T, h, w) bool
        Cleaned masks: specks dropped, small holes filled (see the module docstring).
    """
    tuning = FigureTuning() if tuning is None else tuning
    frames = _checked_frames(frames)
    h, w = frames.shape[1:3]
    if background is not None and colour is not None:
        raise TrackingError("give a background image or a background colour, not both")
    if colour is not None:
        reference = _checked_colour(colour)[None, None, :]
    elif background is not None:
        reference = np.asarray(background)
        if reference.shape != (h, w, 3):
            raise TrackingError(
                f"the background image is {_size(reference.shape)} but the frames are {w}x{h} RGB; "
                "give a background of the frames' size"
            )
        reference = reference.astype(np.float32)
    else:
        reference = estimate_background(frames).astype(np.float32)
    if threshold is None:
        threshold = _auto_threshold(_distance(frames[0], reference), tuning)
    elif not _is_number(threshold) or not threshold >= 0:
        raise TrackingError(f"the foreground threshold must be a number >= 0, got {threshold!r}")
    masks = np.empty(frames.shape[:3], dtype=bool)
    for t, frame in enumerate(frames):
        masks[t] = cleaned_mask(_distance(frame, reference) > threshold, tuning)
    return masks


class FlatBackgroundMasks(Sequence[NDArray[np.bool_]]):
    """The figure in each frame of a cartoon on one flat colour, made as each frame is asked for.

    A pixel is the figure where the sum of its channels' differences from ``colour`` exceeds
    ``threshold`` (no less than the RGB distance :func:`foreground_masks` measures). On a flat
    colour nothing but the figure (and a grey level or two of noise) differs from it, so the
    threshold is the low end of the range (:class:`~toonmotion.capture.figure_tuning.FigureTuning`'s
    ``threshold_low``) by default: Otsu's split, which
    :func:`foreground_masks` takes, throws away a figure's fills that lie near the paper's colour
    (skin on cream paper) and keeps only its outlines. Masks are not cleaned (a tracker asks
    for one a frame, and a speck matters little to it). Each mask asked for reads its frame from
    ``frames`` again: a lazy sequence of frames is read a second time.

    Parameters
    ----------
    frames : (T, h, w, 3) uint8, or a sequence of T (h, w, 3) uint8 arrays
    colour : (r, g, b)
        The background colour, 0-255.
    threshold : float, optional
        Summed channel difference, 0 to 765; default ``FigureTuning().threshold_low``.

    Examples
    --------
    >>> frames = np.full((2, 4, 4, 3), 240, np.uint8); frames[1, 1:3, 1:3] = (250, 200, 160)
    >>> masks = FlatBackgroundMasks(frames, (240, 240, 240))
    >>> len(masks), int(masks[0].sum()), int(masks[1].sum())
    (2, 0, 4)
    """

    def __init__(self, frames: NDArray[np.uint8] | Sequence[NDArray[np.uint8]], colour: Sequence[int],
                 threshold: float | None = None) -> None:
        self._frames = frames
        self._colour = np.rint(_checked_colour(colour)).astype(np.uint8)
        self._plate: NDArray[np.uint8] | None = None  # the colour, frame-sized
        self._difference: NDArray[np.uint8] | None = None
        self._channels: tuple[NDArray[np.uint8], ...] = ()
        threshold = FigureTuning().threshold_low if threshold is None else threshold
        if not _is_number(threshold) or not threshold >= 0:
            raise TrackingError(f"the foreground threshold must be a number >= 0, got {threshold!r}")
        self._threshold = float(threshold)

    def __len__(self) -> int:
        return len(self._frames)

    @overload
    def __getitem__(self, t: int) -> NDArray[np.bool_]: ...

    @overload
    def __getitem__(self, t: slice) -> list[NDArray[np.bool_]]: ...

    def __getitem__(self, t: int | slice) -> NDArray[np.bool_] | list[NDArray[np.bool_]]:
        if isinstance(t, slice):
            return [self[i] for i in range(*t.indices(len(self)))]
        # The channels' absolute differences summed, in uint8 (sums past 255 saturate, far past
        # any threshold; adding the split channels takes a third of the time of cv2.transform's
        # weighted sum), in arrays kept from frame to frame: a frame-sized array made afresh is
        # mapped in from the system page by page, which took four fifths of the time.
        frame = np.asarray(self._frames[t])
        if self._plate is None or self._plate.shape != frame.shape:
            self._plate = np.empty_like(frame)
            self._plate[:] = self._colour
            self._difference = np.empty_like(frame)
            self._channels = tuple(np.empty(frame.shape[:2], np.uint8) for _ in range(3))
        # (Frames of another type than uint8 are split into arrays of their own.)
        red, green, blue = cv2.split(cv2.absdiff(frame, self._plate, dst=self._difference), self._channels)
        total = cv2.add(cv2.add(red, green, dst=red), blue, dst=red)
        return np.asarray(total > self._threshold)


def flat_figure_masks(frames: NDArray[np.uint8] | Sequence[NDArray[np.uint8]], *,
                      colour: Sequence[int] | None = None, tuning: FigureTuning | None = None
                      ) -> FlatBackgroundMasks | None:
    """The figure's masks when it is drawn on one flat colour, ``colour`` or else the first
    frame's border colour (:func:`border_colour`), at :func:`flat_threshold` (``tuning``'s range);
    None when that border is not flat.

    A background estimated from the footage itself (:func:`estimate_background`) is wrong
    wherever the figure holds still for half the clip (legs standing while an arm waves), and a
    tracker that holds joints to such a mask loses them, so none is offered there.

    >>> frames = np.full((2, 8, 8, 3), 240, np.uint8); frames[:, 3:5, 3:5] = 0
    >>> noise = np.random.default_rng(0).integers(0, 255, (1, 8, 8, 3), np.uint8)
    >>> int(flat_figure_masks(frames)[1].sum()), flat_figure_masks(noise)
    (4, None)
    """
    first = np.asarray(frames[0])
    if colour is None:
        colour = border_colour(first)
    if colour is None:
        return None
    return FlatBackgroundMasks(frames, colour, flat_threshold(first, colour, tuning))


def flat_threshold(frame: ArrayLike, colour: Sequence[int], tuning: FigureTuning | None = None) -> float:
    """The summed channel difference from ``colour`` above which a pixel of ``frame`` ``(h, w, 3)``
    is the figure (:class:`FlatBackgroundMasks`): the 99th percentile of the frame's border pixels'
    differences, within ``tuning.threshold_low`` to ``tuning.threshold_high`` (default its
    defaults). Digital art on white gets the low end; paper photographed under uneven light, whose
    own colour drifts by tens of levels, gets above its drift. Border pixels farther from the
    colour than the range's top are not paper (a frame drawn round the picture, the figure cut by
    the edge) and do not count.

    >>> frame = np.full((10, 10, 3), 250, np.uint8); frame[:, :5] = 235  # light falling off
    >>> flat_threshold(frame, (250, 250, 250)), flat_threshold(np.full((4, 4, 3), 9, np.uint8), (9, 9, 9))
    (45.0, 20.0)
    >>> frame[:, 0] = frame[0] = 20  # a dark frame on two sides
    >>> flat_threshold(frame, (250, 250, 250))
    45.0
    """
    tuning = FigureTuning() if tuning is None else tuning
    low, high = tuning.threshold_low, tuning.threshold_high
    border = _border_pixels(frame).astype(np.float32)
    difference = np.abs(border - _checked_colour(colour)).sum(axis=1)
    paper = difference[difference <= high]
    spread = float(np.percentile(paper, 99)) if paper.size else low
    return float(np.clip(spread, low, high))


def guide_skeleton(mask: NDArray[np.bool_], *, prune: float = 0.5) -> CurveSkeleton:
    """The curve skeleton of frame 1's foreground, the guide for placing joints (thesis 4.3).

    Parameters
    ----------
    mask : (h, w) bool
        Frame 1's foreground, e.g. ``foreground_masks(frames)[0]``.
    prune : float
        Spur pruning, as in :func:`~toonmotion.shape.curve_skeleton.curve_skeleton`.

    Returns
    -------
    CurveSkeleton
    """
    mask = np.asarray(mask, dtype=bool)
    if mask.ndim != 2:
        raise TrackingError(f"the guide mask must be one (h, w) frame, got shape {mask.shape}")
    if not mask.any():
        raise TrackingError(
            "the first frame's foreground is empty: no figure was found; check the background "
            "(or colour) and lower the threshold, or start from a frame where the figure shows"
        )
    return curve_skeleton(mask, prune=prune)


def _checked_frames(frames):
    frames = np.asarray(frames)
    if frames.ndim != 4 or frames.shape[3] != 3 or frames.dtype != np.uint8:
        raise TrackingError(
            f"frames must be a (T, h, w, 3) uint8 RGB array, got shape {frames.shape} dtype {frames.dtype}"
        )
    if frames.shape[0] == 0 or frames.shape[1] == 0 or frames.shape[2] == 0:
        raise TrackingError("the sequence is empty: there are no frames (or no pixels) to track")
    return frames


def _checked_colour(colour):
    try:
        values = np.array([float(v) for v in colour])
    except (TypeError, ValueError):
        values = np.zeros(0)
    if values.shape != (3,) or not np.all((values >= 0) & (values <= 255)):
        raise TrackingError(f"the background colour must be three numbers (r, g, b) 0-255, got {colour!r}")
    return values.astype(np.float32)


def _is_number(value):
    return isinstance(value, Real) and not isinstance(value, bool) and bool(np.isfinite(value))


def _size(shape):
    return f"{shape[1]}x{shape[0]}" if len(shape) >= 2 else f"shape {shape}"


def _distance(frame, reference):
    """RGB distance of each pixel to the background, (h, w) float32."""
    return np.sqrt(np.sum(np.square(frame.astype(np.float32) - reference), axis=2))


def _auto_threshold(distance, tuning):
    from skimage.filters import threshold_otsu

    low, high = tuning.threshold_low, tuning.threshold_high
    if float(distance.max()) - float(distance.min()) < 1e-3:
        return low
    return float(np.clip(threshold_otsu(distance), low, high))


def cleaned_mask(mask: NDArray[np.bool_], tuning: FigureTuning | None = None) -> NDArray[np.bool_]:
    """``mask`` ``(h, w)`` bool cleaned as :func:`foreground_masks` cleans its masks: specks
    (8-connected parts smaller than ``tuning.clean_fraction`` of the largest part) dropped, and
    holes (background parts off the frame's border) smaller than that share of the foreground
    filled (``tuning`` default its defaults).

    >>> mask = np.zeros((20, 20), bool); mask[2:18, 2:18] = True; mask[9, 9] = False
    >>> bool(cleaned_mask(mask)[9, 9])
    True
    """
    if not mask.any():
        return mask
    fraction = (FigureTuning() if tuning is None else tuning).clean_fraction
    mask = clean_mask(mask, min_fraction=fraction)
    # Holes: background parts (4-connected, the dual of 8-connected foreground) off the border.
    labels, count = ndi.label(~mask, structure=_CROSS)
    if count == 0:
        return mask
    sizes = np.bincount(labels.ravel())
    small = sizes < fraction * np.count_nonzero(mask)
    small[0] = False
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    small[border] = False
    return mask | small[labels]


def without_frame(mask: NDArray[np.bool_], tuning: FigureTuning | None = None) -> NDArray[np.bool_]:
    """``mask`` ``(h, w)`` bool without a frame drawn round the picture: lines along an edge that are
    ``tuning.frame_line`` figure, up to ``tuning.frame_depth`` of the picture's smaller side deep,
    are cleared (a frame the figure touches), then 8-connected parts that touch all four sides and
    cover less than ``tuning.frame_fill`` of their bounding box, the picture (a frame that stands
    apart). A figure cut by the picture's edges fills no whole edge, touches fewer sides, or fills
    more. ``tuning`` default its defaults.

    >>> mask = np.zeros((100, 100), bool); mask[:2] = mask[-2:] = mask[:, :2] = mask[:, -2:] = True
    >>> mask[40:60, 40:60] = True  # a figure inside a frame two pixels wide
    >>> int(without_frame(mask).sum())
    400
    >>> mask[2:40, 50] = True  # the figure touching the frame
    >>> int(without_frame(mask).sum())
    438
    """
    tuning = FigureTuning() if tuning is None else tuning
    mask = np.array(mask, dtype=bool)
    depth = max(1, int(tuning.frame_depth * min(mask.shape)))
    for side in (mask, mask[::-1], mask.T, mask.T[::-1]):  # views: top, bottom, left, right
        for line in side[:depth]:
            if line.mean() < tuning.frame_line:
                break
            line[:] = False
    labels, count = ndi.label(mask, structure=np.ones((3, 3), bool))
    if count == 0:
        return mask
    sides = [np.unique(side) for side in (labels[0], labels[-1], labels[:, 0], labels[:, -1])]
    framing = set(sides[0].tolist()).intersection(*(s.tolist() for s in sides[1:])) - {0}
    fill = tuning.frame_fill * mask.size
    framing = {part for part in framing if np.count_nonzero(labels == part) < fill}
    return mask & ~np.isin(labels, list(framing)) if framing else mask


def border_colour(frame: ArrayLike, *, spread: float = 12.0) -> tuple[int, int, int] | None:
    """The colour of a flat background, read off the frame's border, or None if it is not flat.

    A cartoon on a plain background has the same colour all round its edge; when the per-channel
    spread (standard deviation) of the border pixels is under ``spread``, their median is taken as
    the background colour. Footage with a textured or varied border returns None. Without a
    colour given, :func:`~toonmotion.capture.footage.suggest_joints` and the tracker take the
    figure to be what differs from this one.

    Parameters
    ----------
    frame : (h, w, 3) uint8
        An RGB frame.
    spread : float
        The largest standard deviation of a channel round the border, grey levels, for it to
        count as flat.

    Returns
    -------
    (int, int, int) or None

    Examples
    --------
    >>> frame = np.full((20, 30, 3), 240, np.uint8); frame[5:15, 10:20] = (200, 40, 40)
    >>> border_colour(frame)
    (240, 240, 240)
    >>> frame[0, :15] = 0  # half the top edge drawn dark: not flat
    >>> border_colour(frame) is None
    True
    """
    border = _border_pixels(frame).astype(float)
    if border.std(axis=0).max() >= spread:
        return None
    r, g, b = (int(v) for v in np.median(border, axis=0))  # an (h, w, 3) RGB frame
    return r, g, b


def _border_pixels(frame):
    """The pixels round a frame's edge, ``(n, channels)``: its first and last rows and columns."""
    frame = np.asarray(frame)
    return np.concatenate([frame[0], frame[-1], frame[:, 0], frame[:, -1]])
