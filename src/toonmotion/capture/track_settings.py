"""What the joint tracker is given and gives (:mod:`toonmotion.capture.tracker`): the joints to
track (:class:`TrackSetup`), how to track them (:class:`TrackSettings`), the figure's masks
(:data:`Masks`), and the joints' paths found (:class:`Tracking`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.search_tuning import SearchTuning
from toonmotion.capture.track_checks import (
    check_number,
)
from toonmotion.capture.track_scale import (
    WORKING_SIDE,
)
from toonmotion.errors import TrackingError
from toonmotion.rig.skeleton import Skeleton

# Where the figure is in each frame: (T, h, w) bool, or a sequence of (h, w) bool.
Masks = NDArray[np.bool_] | Sequence[NDArray[np.bool_]]


@dataclass(frozen=True, eq=False)
class TrackSetup:
    """What to track: joints and a rectangle per joint (thesis 4.3).

    Attributes
    ----------
    skeleton : Skeleton
        Joint names and parents (a forest is allowed: a hat tracked apart from a man); its
        positions are the rectangles' centres at the frame tracking starts from, by default.
    sizes : (k, 2) float
        Width and height of each joint's rectangle, pixels, > 0; rounded to whole pixels (at
        least 1) for matching.
    """

    skeleton: Skeleton
    sizes: np.ndarray

    def __post_init__(self) -> None:
        if not isinstance(self.skeleton, Skeleton):
            raise TrackingError(f"a TrackSetup needs a Skeleton, got {type(self.skeleton).__name__}")
        k = len(self.skeleton)
        try:
            sizes = np.array(self.sizes, dtype=float)
        except (TypeError, ValueError):
            raise TrackingError(
                f"rectangle sizes must be numbers, shape ({k}, 2); got {self.sizes!r}"
            ) from None
        if sizes.shape != (k, 2):
            raise TrackingError(
                f"rectangle sizes have shape {sizes.shape}; give a width and height per joint, shape ({k}, 2)"
            )
        bad = ~(np.isfinite(sizes) & (sizes > 0)).all(axis=1)
        if bad.any():
            m = int(np.flatnonzero(bad)[0])
            raise TrackingError(
                f"joint {self.skeleton.names[m]!r} has a rectangle of size {sizes[m, 0]:g}x{sizes[m, 1]:g}; "
                "give a finite width and height > 0"
            )
        sizes.setflags(write=False)
        object.__setattr__(self, "sizes", sizes)


@dataclass(frozen=True)
class TrackSettings:
    """How far to search and how to weigh colour against prediction (eq. 4.6).

    Attributes
    ----------
    search : float or None
        Search radius ``r``, pixels, >= 1. None: per joint, ``max(tuning.min_search,
        tuning.search_fraction * larger rectangle side)``.
    w_alpha : float
        Weight of the mean colour difference, > 0 (thesis: ``1 / 255^2``).
    w_beta : float or None
        Weight of the squared distance from the prediction, >= 0. None: ``1 / r^2`` (thesis).
    rotate : bool
        Turn the rectangles of joints with a parent with their bone (eq. 4.2).
    fill_gaps : bool
        After tracking, re-place each joint where it was hidden between two frames where it was
        found, from both ends (:mod:`~toonmotion.capture.track_gaps`).
    best_path : bool
        After tracking, choose each joint's path again among the places its searches found, by
        the least cost over the whole clip (:mod:`~toonmotion.capture.track_path`); before
        ``fill_gaps``.
    both_ways : bool
        Also track the clip backwards, from its last frame where the tracking put the joints, with
        the templates cut where tracking started, and let ``best_path`` choose between the two
        ways: a joint lost for a stretch and found again is put where the tracking backwards
        held it. About twice the time; needs ``best_path``.
    figure : bool
        Where the footage is a figure on one flat colour, hold the joints to the figure: they are
        matched only on it and a joint not found is put on it
        (:mod:`~toonmotion.capture.track_figure`). Read by
        :func:`~toonmotion.capture.footage.capture_motion`, which finds the figure's masks and
        gives them to :func:`track`.
    relight : bool
        See every frame in the light of the frame tracking started from: where a frame's
        brightness or contrast has changed (a camera's exposure, a flickering lamp), its colours
        are mapped back before its joints are looked for (:mod:`~toonmotion.capture.track_light`).
        Frames in the same light are left as they are.
    working_side : float or None
        Frames larger than this on their larger side (pixels) are tracked halved, as many times as
        it takes to fit (a 1920 x 1080 video at 960 x 540), every rectangle, window and
        ``search`` with them: about four times fewer pixels to match per halving
        (:mod:`~toonmotion.capture.track_scale`). Positions, rectangles and corrections are
        given and returned in the frames' own pixels all the same. None: at full resolution.
    tuning : SearchTuning
        How each frame is searched: windows, confidences, weights
        (:class:`~toonmotion.capture.search_tuning.SearchTuning`, each value with the
        measurement that chose it).
    clip : ClipTuning
        How the clip is read round the search: held drawings, coasting, hidden spans, the
        figure's edge, the light (:class:`~toonmotion.capture.clip_tuning.ClipTuning`).
    match : MatchTuning
        How a joint's templates are matched and the match read: confidence and its bars, the
        turns tried, templates' size and texture, the wider view
        (:class:`~toonmotion.capture.match_tuning.MatchTuning`).
    cutout : FigureTuning
        How the figure the joints are held to is found on a flat colour (``figure``): its
        threshold's range (:class:`~toonmotion.capture.figure_tuning.FigureTuning`, which the
        functions that suggest joints take too). Read by
        :func:`~toonmotion.capture.footage.capture_motion`.
    """

    search: float | None = None
    w_alpha: float = 1 / 255**2
    w_beta: float | None = None
    rotate: bool = True
    fill_gaps: bool = True
    best_path: bool = True
    both_ways: bool = False
    figure: bool = True
    relight: bool = True
    working_side: float | None = WORKING_SIDE
    tuning: SearchTuning = field(default_factory=SearchTuning)
    clip: ClipTuning = field(default_factory=ClipTuning)
    match: MatchTuning = field(default_factory=MatchTuning)
    cutout: FigureTuning = field(default_factory=FigureTuning)

    def __post_init__(self) -> None:
        if self.search is not None:
            search = check_number(self.search, "the search radius (px)", 1.0, ">= 1")
            object.__setattr__(self, "search", search)
        object.__setattr__(self, "w_alpha", check_number(self.w_alpha, "w_alpha", 0.0, "> 0", strict=True))
        if self.w_beta is not None:
            object.__setattr__(self, "w_beta", check_number(self.w_beta, "w_beta", 0.0, ">= 0"))
        if self.working_side is not None:
            side = check_number(self.working_side, "the working side (px)", 1.0, ">= 1")
            object.__setattr__(self, "working_side", side)
        for name in ("rotate", "fill_gaps", "best_path", "both_ways", "figure", "relight"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise TrackingError(f"{name} must be True or False, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        tunings = {"tuning": SearchTuning, "clip": ClipTuning, "match": MatchTuning, "cutout": FigureTuning}
        for name, kind in tunings.items():
            given = getattr(self, name)
            if not isinstance(given, kind):
                raise TrackingError(f"{name} must be a {kind.__name__}, got {type(given).__name__}")
        if self.both_ways and not self.best_path:
            raise TrackingError(
                "both_ways needs best_path: the whole-sequence pass chooses between the two ways"
            )


@dataclass(frozen=True, eq=False)
class Tracking:
    """Tracked joints, frame by frame.

    Attributes
    ----------
    positions : (T, k, 2) float
        Rectangle centres, (x, y) pixels, sub-pixel; NaN at frames not tracked.
    angles : (T, k) float
        Each rectangle's rotation, radians, relative to the frame tracking started from (its
        bone's change of direction, unwrapped); 0 for roots and with ``rotate=False``; NaN at
        frames not tracked.
    confidence : (T, k) float in [0, 1]
        How well the texture matched: near 1 on a clean match, below the settings'
        ``match.visible_confidence`` where the joint was taken to be hidden (then carried by its
        parent, or coasting if a root); 0 at frames not tracked.
    tracked : (T,) bool
        Frames that have been tracked: ``start`` up to ``stop``.
    held : (T,) bool, optional
        Tracked frames found to repeat the frame before (animation on twos or threes): their
        joints are the frame before's. All False when not given.
    """

    positions: np.ndarray
    angles: np.ndarray
    confidence: np.ndarray
    tracked: np.ndarray
    held: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.held is None:
            object.__setattr__(self, "held", np.zeros(np.shape(self.tracked), dtype=bool))
        kinds = (("positions", float), ("angles", float), ("confidence", float), ("tracked", bool),
                 ("held", bool))
        for name, dtype in kinds:
            array = np.array(getattr(self, name), dtype=dtype)
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        T = len(self.tracked)
        k = self.angles.shape[1] if self.angles.ndim == 2 else -1
        held = np.asarray(self.held)
        shapes = (self.tracked.shape, held.shape, self.angles.shape, self.confidence.shape,
                  self.positions.shape)
        if shapes != ((T,), (T,), (T, k), (T, k), (T, k, 2)):
            raise TrackingError(
                "a Tracking needs positions (T, k, 2), angles and confidence (T, k), tracked and held "
                f"(T,); got {self.positions.shape}, {self.angles.shape}, {self.confidence.shape}, "
                f"{self.tracked.shape} and {held.shape}"
            )
