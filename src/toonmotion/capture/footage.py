"""Capturing a motion from footage, end to end: suggest joints, track, correct, read the result.

These are the steps the ``track`` command and the editor's capture panel take, on frames already
read (``(T, H, W, 3)`` uint8 RGB, see :func:`toonmotion.io.frames.load_frames`):

1. :func:`suggest_joints` places joint rectangles on the first frame's curve skeleton when the
   user has none (thesis 4.3);
2. :func:`capture_motion` tracks them through the footage (thesis 4.4) and returns a
   :class:`~toonmotion.animate.motion.Motion` with a confidence per joint-frame, trimmed to the
   frames tracked;
3. :func:`correct_motion` puts some joints right at one frame and tracks again from there, keeping
   the frames before it (an earlier motion read back from its file).

How the figure is found and the rectangles suggested is a
:class:`~toonmotion.capture.figure_tuning.FigureTuning`, given as ``tuning`` to the functions that
find it (default its defaults), and as ``TrackSettings.cutout`` to those that track.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.motion import Motion, motion_for
from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.capture.foreground import (
    cleaned_mask,
    estimate_background,
    flat_figure_masks,
    foreground_masks,
    without_frame,
)
from toonmotion.capture.setup import check_setup, rectangle_sizes, suggest_setup
from toonmotion.capture.track_checks import check_count, read_frame
from toonmotion.capture.track_settings import Tracking, TrackSettings, TrackSetup
from toonmotion.capture.tracker import retrack, track
from toonmotion.errors import SettingsError
from toonmotion.progress import Progress
from toonmotion.rig.skeleton import Skeleton

# A joint matched less confidently than this at a frame matched poorly there (hidden, or its look
# changed): where a user may want to look, and correct it.
POOR_MATCH = 0.5


@dataclass(frozen=True)
class PoorlyMatched:
    """A joint that matched poorly (:data:`POOR_MATCH`) in some frames of a capture.

    Attributes
    ----------
    name : str
    fraction : float
        Of the frames tracked, those where it matched poorly.
    start : int
        The footage frame its longest stretch of such frames starts at.
    length : int
        That stretch's frames.
    """

    name: str
    fraction: float
    start: int
    length: int


@dataclass(frozen=True)
class Capture:
    """A tracked motion and what drew it.

    Attributes
    ----------
    motion : Motion
        Joint positions of the frames tracked, with ``confidence``; fps as given.
    first : int
        The footage frame the motion's frame 0 is.
    angles : (T, k) float
        Each joint rectangle's rotation in every motion frame, radians (for drawing the rectangles).
    held : (T,) bool
        Motion frames that repeat the frame before (animation on twos or threes).
    """

    motion: Motion
    first: int
    angles: NDArray[np.float64]
    held: NDArray[np.bool_]

    @property
    def poor_fraction(self) -> float:
        """Of all joint-frames, those that matched poorly (:data:`POOR_MATCH`); 0 without confidence."""
        confidence = self.motion.confidence
        return 0.0 if confidence is None else float((confidence < POOR_MATCH).mean())

    def poorly_matched(self, count: int = 3) -> list[PoorlyMatched]:
        """Up to ``count`` joints that matched poorly (:data:`POOR_MATCH`) in any frame, in the
        most frames first (ties: in skeleton order), each with its longest stretch of such frames:
        where to look in the footage and correct it.

        >>> from toonmotion.rig.skeleton import Skeleton
        >>> skeleton = Skeleton.from_joints([("hip", None, (0.0, 0.0)), ("hand", "hip", (9.0, 0.0))])
        >>> sure = np.ones((6, 2)); sure[[1, 3, 4], 1] = 0.1
        >>> motion = Motion(skeleton, np.zeros((6, 2, 2)), fps=12, confidence=sure)
        >>> Capture(motion, first=10, angles=np.zeros((6, 2)), held=np.zeros(6, bool)).poorly_matched()
        [PoorlyMatched(name='hand', fraction=0.5, start=13, length=2)]
        """
        confidence = self.motion.confidence
        if confidence is None:
            return []
        poor = confidence < POOR_MATCH
        found = []
        for m in np.flatnonzero(poor.any(axis=0)):
            start, length = _longest_run(poor[:, m])
            found.append(PoorlyMatched(self.motion.skeleton.names[m], float(poor[:, m].mean()),
                                       self.first + start, length))
        return sorted(found, key=lambda joint: -joint.fraction)[:count]


def suggest_joints(
    frames: NDArray[np.uint8], *, colour: tuple[int, int, int] | None = None,
    tuning: FigureTuning | None = None,
) -> tuple[Skeleton, NDArray[np.float64]]:
    """Joints and rectangle sizes suggested from the first frame's figure.

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
    colour : (int, int, int), optional
        A flat background colour. Without it the first frame's border colour is used when that is
        flat, else a background estimated from the whole sequence; the figure is what differs.
    tuning : FigureTuning, optional
        How the figure is found and the rectangles sized; default its defaults.

    Returns
    -------
    skeleton : Skeleton
        Joints along the figure's curve skeleton, at their first-frame positions.
    sizes : (k, 2) float
        Each joint's tracking rectangle (width, height) in pixels.

    Examples
    --------
    >>> from toonmotion.samples import sample_character_on
    >>> picture = sample_character_on("white", scale=0.5)[0]
    >>> skeleton, sizes = suggest_joints(picture[None])
    >>> len(skeleton) == len(sizes) > 1
    True

    Raises
    ------
    TrackingError
        ``frames`` is not a sequence of ``(H, W, 3)`` uint8 frames (one frame alone, say).
    """
    check_count(frames)
    read_frame(frames, 0, None)
    return suggest_setup(first_figure(frames, colour=colour, tuning=tuning), tuning=tuning)


def suggested_sizes(frames: NDArray[np.uint8], positions: ArrayLike, *, start: int = 0,
                    colour: tuple[int, int, int] | None = None,
                    tuning: FigureTuning | None = None) -> NDArray[np.float64]:
    """The rectangles :func:`suggest_joints` would give joints at ``positions`` ``(k, 2)`` on
    frame ``start``'s figure (found as :func:`first_figure` finds frame 0's): twice the figure's
    thickness there. To tell a user whose own rectangles are much smaller.

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
    positions : (k, 2) float
        Joints on frame ``start``, (x, y) pixels.
    start : int
        The frame the joints are placed on.
    colour : (int, int, int), optional
        A flat background colour, as for :func:`suggest_joints`.
    tuning : FigureTuning, optional
        As for :func:`suggest_joints`.

    Returns
    -------
    (k, 2) float
        Each joint's suggested rectangle (width, height) in pixels.

    Examples
    --------
    >>> from toonmotion.samples import sample_character_on
    >>> picture, skeleton = sample_character_on("white", scale=0.5)
    >>> sizes = suggested_sizes(picture[None], skeleton.positions)
    >>> sizes.shape == (len(skeleton), 2) and bool((sizes >= 8).all())
    True
    """
    figure = first_figure(frames[start:], colour=colour, tuning=tuning)
    return rectangle_sizes(figure, np.asarray(positions, dtype=float), tuning)


# Rectangles whose median side is under this fraction of the suggested ones' are worth a warning:
# on the sample character's own wave, 24 px rectangles where 48 are suggested lost a hand for 15
# frames (5.9 px mean error, 1.8 with 48 px; 3.2 with 36).
SMALL_RECTANGLES = 0.6


def setup_warnings(frames: NDArray[np.uint8], skeleton: Skeleton, sizes: ArrayLike, *, start: int = 0,
                   colour: tuple[int, int, int] | None = None,
                   tuning: FigureTuning | None = None) -> list[str]:
    """What may go wrong in tracking joints placed as ``skeleton`` at frame ``start`` with
    rectangles ``sizes``, a line each for the user: rectangles much smaller than those
    :func:`suggested_sizes` gives there (:data:`SMALL_RECTANGLES`), and two joints, neither the
    other's parent, within half a rectangle of each other (each template is cut mostly from the
    other, and the tracker may follow one for the other: two legs alike, crossing).

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
    skeleton : Skeleton
        The joints, at their places on frame ``start``.
    sizes : (k, 2) float
        Each joint's rectangle (width, height), pixels.
    start, colour, tuning
        As for :func:`suggested_sizes`.

    Returns
    -------
    list of str

    Examples
    --------
    >>> from toonmotion.samples import sample_character_on
    >>> picture, skeleton = sample_character_on("white", scale=0.5)
    >>> sizes = suggested_sizes(picture[None], skeleton.positions)
    >>> setup_warnings(picture[None], skeleton, sizes)
    []
    >>> setup_warnings(picture[None], skeleton, sizes / 3)[0][:38]
    'the rectangles are small for this figu'
    """
    sizes = np.asarray(sizes, dtype=float)
    warnings = []
    given = float(np.median(sizes.max(axis=1)))
    suggested = float(np.median(suggested_sizes(frames, skeleton.positions, start=start,
                                                colour=colour, tuning=tuning).max(axis=1)))
    if given < SMALL_RECTANGLES * suggested:
        warnings.append(f"the rectangles are small for this figure (median {given:.0f} px, where "
                        f"{suggested:.0f} px are suggested from its thickness): a rectangle holding "
                        "little but one flat colour loses its joint; make them larger")
    P, parents, names = skeleton.positions, skeleton.parents, skeleton.names
    gap = np.hypot(*(P[:, None] - P[None]).transpose(2, 0, 1))
    side = sizes.max(axis=1)
    near = np.triu(gap < 0.5 * np.maximum(side[:, None], side[None]), 1)
    for a, b in zip(*np.nonzero(near), strict=True):
        if parents[b] != a and parents[a] != b:
            warnings.append(f"joints {names[a]} and {names[b]} start {gap[a, b]:.0f} px apart, within half a "
                            "rectangle: each is cut mostly from the other, and the tracker may follow one "
                            f"for the other; start on a frame where they are apart (now frame {start})")
            break
    return warnings


def first_figure(frames: NDArray[np.uint8], *, colour: tuple[int, int, int] | None = None,
                 tuning: FigureTuning | None = None) -> NDArray[np.bool_]:
    """Frame 0's figure, ``(H, W)`` bool, found as :func:`suggest_joints` finds it.

    On a flat colour (``colour``, else the first frame's border colour when that is flat) it is
    what the tracker holds joints to
    (:class:`~toonmotion.capture.foreground.FlatBackgroundMasks`), cleaned of specks and small
    holes: every pixel off that colour, so fills close to the paper's colour (skin on white)
    count. Otherwise it is what differs from a background estimated from the whole sequence
    (:func:`~toonmotion.capture.foreground.foreground_masks`). Either way a frame drawn round the
    picture is left out (:func:`~toonmotion.capture.foreground.without_frame`). ``tuning`` as for
    :func:`suggest_joints`.
    """
    flat = flat_figure_masks(frames[:1], colour=colour, tuning=tuning)
    if flat is not None:
        return without_frame(cleaned_mask(flat[0], tuning), tuning)
    figure = foreground_masks(frames[:1], background=estimate_background(frames), tuning=tuning)[0]
    return without_frame(figure, tuning)


def figure_box(frames: NDArray[np.uint8], *, colour: tuple[int, int, int] | None = None,
               tuning: FigureTuning | None = None) -> tuple[int, int, int, int] | None:
    """The box round frame 0's figure (:func:`first_figure`): ``(left, top, right, bottom)``
    pixels, right and bottom exclusive; None when no figure is found.

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
        The footage (frame 0 is looked at; the rest estimate a background that is not flat).
    colour : (r, g, b), optional
        The flat background's colour, when known.
    tuning : FigureTuning, optional
        As for :func:`suggest_joints`.

    Returns
    -------
    tuple of 4 int, or None

    Examples
    --------
    >>> frames = np.full((1, 40, 60, 3), 255, np.uint8)
    >>> frames[0, 10:30, 20:35] = 0  # a dark figure on white paper
    >>> figure_box(frames)
    (20, 10, 35, 30)
    """
    figure = first_figure(frames, colour=colour, tuning=tuning)
    if not figure.any():
        return None
    rows, cols = np.flatnonzero(figure.any(axis=1)), np.flatnonzero(figure.any(axis=0))
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def capture_motion(
    frames: NDArray[np.uint8],
    skeleton: Skeleton,
    sizes: NDArray[np.float64],
    *,
    fps: float,
    start: int = 0,
    settings: TrackSettings | None = None,
    background: tuple[int, int, int] | None = None,
    progress: Progress | None = None,
) -> Capture:
    """Track ``skeleton``'s joints, placed at frame ``start``, through ``frames``.

    ``sizes`` are each joint's rectangle (width, height) in pixels. Where the figure is drawn on
    one flat colour, ``background`` or else the first frame's border colour, the joints are held
    to it (``settings.figure``). Returns the motion of the frames tracked (from ``start`` to the
    end).
    """
    setup = _setup(frames, skeleton, sizes, start)
    result = track(frames, setup, settings=settings, start=start, masks=_masks(frames, settings, background),
                   progress=progress)
    return _capture(result, skeleton, fps)


def correct_motion(
    earlier: Motion,
    frames: NDArray[np.uint8],
    skeleton: Skeleton,
    sizes: NDArray[np.float64],
    frame: int,
    corrections: Mapping[str, tuple[float, float]],
    *,
    fps: float,
    start: int = 0,
    settings: TrackSettings | None = None,
    background: tuple[int, int, int] | None = None,
    progress: Progress | None = None,
) -> Capture:
    """Put joints right at ``frame`` and track again from there, keeping the frames before it.

    ``earlier`` is a motion tracked with the same joints from frame ``start`` (as read back from
    its file); ``corrections`` maps joint names to their true ``(x, y)`` at ``frame``. The figure
    holds the joints as in :func:`capture_motion`.
    """
    setup = _setup(frames, skeleton, sizes, start)
    tracking = tracking_from_motion(earlier, skeleton, len(frames), start)
    result = retrack(tracking, frames, setup, frame, dict(corrections), settings=settings,
                     masks=_masks(frames, settings, background), progress=progress)
    return _capture(result, skeleton, fps)


def tracking_from_motion(motion: Motion, skeleton: Skeleton, count: int, start: int) -> Tracking:
    """An earlier tracking, read back from its motion, laid out on ``count`` footage frames.

    The motion's frame 0 is footage frame ``start``; its joints are taken in ``skeleton``'s order.
    Rectangle angles are not kept in motion files, so they restart at 0.
    """
    positions = motion_for(skeleton, motion, where="the earlier motion")
    k = len(skeleton)
    if start + len(positions) > count:
        raise SettingsError(
            f"the earlier motion has {len(positions)} frames from frame {start}, more than "
            f"the footage's {count}"
        )
    span = slice(start, start + len(positions))
    full = np.zeros((count, k, 2))
    confidence = np.zeros((count, k))
    tracked = np.zeros(count, dtype=bool)
    full[span] = positions
    tracked[span] = True
    if motion.confidence is not None:
        columns = [motion.skeleton.names.index(n) for n in skeleton.names]
        confidence[span] = motion.confidence[:, columns]
    return Tracking(positions=full, angles=np.zeros((count, k)), confidence=confidence, tracked=tracked)


def _masks(frames, settings, background):
    """The figure's masks to hold joints to, if the settings ask for it and the figure is drawn on
    a flat colour (:func:`~toonmotion.capture.foreground.flat_figure_masks`, with the settings'
    ``cutout``), else None."""
    if settings is not None and not settings.figure:
        return None
    return flat_figure_masks(frames, colour=background, tuning=None if settings is None else settings.cutout)


def _setup(
    frames: NDArray[np.uint8], skeleton: Skeleton, sizes: NDArray[np.float64], start: int
) -> TrackSetup:
    if not 0 <= start < len(frames):
        raise SettingsError(f"the joints are given at frame {start} but the footage has {len(frames)} frames")
    h, w = frames.shape[1:3]
    check_setup(skeleton, sizes, (w, h))
    return TrackSetup(skeleton=skeleton, sizes=sizes)


def _capture(result: Tracking, skeleton: Skeleton, fps: float) -> Capture:
    tracked = np.flatnonzero(result.tracked)
    first, last = int(tracked[0]), int(tracked[-1]) + 1
    motion = Motion(
        skeleton=skeleton,
        positions=result.positions[first:last],
        fps=fps,
        confidence=result.confidence[first:last],
    )
    assert result.held is not None  # a Tracking fills it in
    return Capture(motion=motion, first=first, angles=np.array(result.angles[first:last]),
                   held=np.array(result.held[first:last]))


def _longest_run(flags: NDArray[np.bool_]) -> tuple[int, int]:
    """The start and length of the longest run of True in ``flags`` (the first, of equals)."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    longest = int(np.argmax(stops - starts))
    return int(starts[longest]), int(stops[longest] - starts[longest])
