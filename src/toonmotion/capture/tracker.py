"""Joint tracking through an image sequence (thesis 4.3 and 4.4, eq. 4.1, 4.2, 4.4 and 4.6).

The user marks a rectangle round every joint on one frame (thesis 4.3); :func:`track` follows
each rectangle frame by frame to the place where the mixed cost of eq. 4.6 is least,

    D = w_alpha D_c + w_beta D_g,

``D_c`` the mean RGB colour difference between the rectangle and the joint's templates (eq. 4.1,
:mod:`~toonmotion.capture.template_match`), ``D_g`` the squared distance from the centre
predicted by constant acceleration (eq. 4.4, :mod:`~toonmotion.capture.track_prediction`).
Rectangles of joints with a parent turn with their bone (eq. 4.2). A joint matched less
confidently than ``MatchTuning.visible_confidence`` is taken to be hidden: it is carried by its parent
(a root coasts on its velocity). :func:`retrack` takes a user's corrections at one frame and
tracks again from there (thesis 4.4.3 and 6.3e).

Coordinates are (x, y) pixels, y down; the pixel in row ``i``, column ``j`` is centred on
``(j, i)`` and covers half a pixel each side. Time is in frames. RGB or BGR does not matter:
every channel is weighed the same. ``docs/capture.md`` (tracking) says where and why this
departs from the thesis.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from toonmotion.capture.joint_plan import Plans, Templates
from toonmotion.capture.patches import distinct_size
from toonmotion.capture.template_context import Pyramid, at_level, cut_templates
from toonmotion.capture.track_checks import (
    Frames,
    check_corrections,
    check_count,
    check_index,
    check_initial,
    check_inside,
    read_frame,
)
from toonmotion.capture.track_figure import FigureMasks, put_on_figure
from toonmotion.capture.track_gaps import fill_hidden_spans
from toonmotion.capture.track_hidden import hidden_for, longest_bones
from toonmotion.capture.track_light import Relit
from toonmotion.capture.track_path import best_paths
from toonmotion.capture.track_prediction import is_held, predict, turns
from toonmotion.capture.track_scale import (
    ReducedFrames,
    ReducedMasks,
    from_working,
    halvings,
    working_weight,
)
from toonmotion.capture.track_search import FrameSearch
from toonmotion.capture.track_settings import Masks, Tracking, TrackSettings, TrackSetup
from toonmotion.errors import TrackingError
from toonmotion.progress import Progress

# progress(stage, index, count), as everywhere in the library; the stage is "tracking".


def track(frames: Frames, setup: TrackSetup, *, settings: TrackSettings | None = None, start: int = 0,
          stop: int | None = None, initial: ArrayLike | None = None, masks: Masks | None = None,
          progress: Progress | None = None) -> Tracking:
    """Track joints through frames (thesis 4.4).

    Parameters
    ----------
    frames : (T, h, w, 3) uint8, or a sequence of T (h, w, 3) uint8 arrays
        RGB frames, all the same size. Only frames ``start`` to ``stop - 1`` are read.
    setup : TrackSetup
    settings : TrackSettings, optional
    start : int
        The frame where the joints are at ``initial``; their templates are cut there, so no
        joint may be occluded on it.
    stop : int, optional
        One past the last frame to track; default T.
    initial : (k, 2) float, optional
        Rectangle centres at ``start``; default ``setup.skeleton.positions``. Every rectangle
        must lie inside the frame.
    masks : (T, h, w) bool, or a sequence of T (h, w) bool arrays, optional
        Where the figure is in each frame
        (:func:`~toonmotion.capture.foreground.foreground_masks`). Joints are then matched only
        on the figure, and a joint not found is put on it
        (:mod:`~toonmotion.capture.track_figure`); joints off the mask at ``start`` are left free.
    progress : callable, optional
        Called as ``progress("tracking", index, stop)`` once each frame ``index`` from ``start``
        is done.

    Returns
    -------
    Tracking

    Examples
    --------
    A textured square moving 2 px right and 1 px down per frame:

    >>> rng = np.random.default_rng(0)
    >>> scene = rng.integers(0, 256, (60, 90, 3), dtype=np.uint8)
    >>> frames = np.stack([np.roll(scene, (t, 2 * t), axis=(0, 1)) for t in range(5)])
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> setup = TrackSetup(Skeleton.from_joints([("dot", None, (30, 25))]), sizes=[[12, 12]])
    >>> np.round(track(frames, setup).positions[:, 0], 3).tolist()
    [[30.0, 25.0], [32.0, 26.0], [34.0, 27.0], [36.0, 28.0], [38.0, 29.0]]
    """
    settings, setup = _settings(settings), _setup(setup)
    count = check_count(frames)
    start = check_index(start, "start", 0, count - 1, count)
    stop = count if stop is None else check_index(stop, "stop", start + 1, count, count)
    first = read_frame(frames, start, None)
    k = len(setup.skeleton)
    initial = setup.skeleton.positions if initial is None else check_initial(initial, k)
    check_inside(setup.skeleton, setup.sizes, initial, np.zeros(k), first, start, range(k))
    n = halvings((first.shape[1], first.shape[0]), settings.working_side)
    own = _held_on(frames, first, settings) if n else None
    if n:
        frames, masks, setup, settings = _at_working(frames, masks, setup, settings, first.shape, n)
        first, initial = read_frame(frames, start, None), at_level(initial, n)
    if settings.relight:
        frames = Relit(frames, first, settings.clip)
    out = _Arrays.empty(count, k, settings.match.others)
    out.positions[start] = initial
    out.angles[start] = 0.0
    out.confidence[start] = 1.0
    out.tracked[start] = True
    plan = _plans(setup, settings, first, initial)
    pyramid = Pyramid(first)
    templates = [cut_templates(pyramid, initial[m], 0.0, plan(m).size, settings.match) for m in range(k)]
    figure = None if masks is None else FigureMasks(masks, count, first.shape, tuning=settings.clip)
    on_figure = None if figure is None else figure.holds(start, initial)
    if progress:
        progress("tracking", start, stop)
    _run(frames, first.shape, plan, templates, out, np.full(k, start), start + 1, stop, progress,
         figure, on_figure, settings.best_path, own, tuning=settings.tuning, clip=settings.clip)
    if settings.both_ways:
        _run_back(frames, masks, first.shape, plan, templates, out, start, stop, on_figure, settings.tuning,
                  settings.clip)
    return _in_frame_pixels(_filled(out, plan, settings, figure, on_figure).freeze(), n)


def retrack(tracking: Tracking, frames: Frames, setup: TrackSetup, frame: int,
            corrections: Mapping[str, ArrayLike], *, settings: TrackSettings | None = None,
            masks: Masks | None = None, progress: Progress | None = None) -> Tracking:
    """Correct joints at one frame and track again from there (thesis 4.4.3, 6.3e).

    Tracking in segments (the thesis' cure for accumulated error) is calling this at each
    segment's first frame.

    Parameters
    ----------
    tracking : Tracking
        From :func:`track` (or :func:`retrack`) on the same frames and setup.
    frames : (T, h, w, 3) uint8, or a sequence of T (h, w, 3) uint8 arrays
    setup : TrackSetup
    frame : int
        A tracked frame.
    corrections : mapping of str to (x, y)
        Joint name to its true rectangle centre at ``frame``; the other joints keep their
        tracked positions there.
    settings : TrackSettings, optional
        Should be the ones ``tracking`` was made with.
    masks : (T, h, w) bool, or a sequence of T (h, w) bool arrays, optional
        Where the figure is in each frame, as for :func:`track`; joints off the mask at
        ``frame`` are left free.
    progress : callable, optional
        Called as ``progress("tracking", index, count)`` once each frame ``index`` from ``frame``
        is done, ``count`` one past the last frame to track.

    Returns
    -------
    Tracking
        Frames before ``frame`` as in ``tracking``; ``frame`` with the corrections; every later
        frame that ``tracking`` covered, tracked again.
    """
    settings, setup = _settings(settings), _setup(setup)
    if not isinstance(tracking, Tracking):
        raise TrackingError(f"retrack needs the Tracking to correct, got {type(tracking).__name__}")
    count, k = check_count(frames), len(setup.skeleton)
    if tracking.positions.shape != (count, k, 2):
        raise TrackingError(
            f"the tracking covers {tracking.positions.shape[0]} frames of {tracking.positions.shape[1]} "
            f"joints, but there are {count} frames and {k} joints; "
            "retrack with the frames and setup it was made from"
        )
    frame = check_index(frame, "the frame to correct", 0, count - 1, count)
    if not tracking.tracked[frame]:
        raise TrackingError(f"frame {frame} was not tracked; correct a tracked frame")
    fixed = check_corrections(corrections, setup.skeleton)
    begin = _run_start(tracking.tracked, frame)
    stop = frame + 1 + int(np.argmin(np.append(tracking.tracked[frame + 1:], False)))

    out = _Arrays.copy(tracking, settings.match.others)
    out.clear(frame + 1, stop)
    for m, xy in fixed.items():
        out.positions[frame, m] = xy
        out.confidence[frame, m] = 1.0
    out.held[frame] = False  # a corrected frame is a drawing of its own
    if frame > begin:
        out.angles[frame] = out.angles[frame - 1] + turns(
            out.positions[frame - 1], out.positions[frame], setup.skeleton.parents, settings.rotate
        )
    current = read_frame(frames, frame, None)
    check_inside(setup.skeleton, setup.sizes, out.positions[frame], out.angles[frame], current, frame, fixed)
    n = halvings((current.shape[1], current.shape[0]), settings.working_side)
    own = _held_on(frames, read_frame(frames, begin, None), settings) if n else None
    if n:
        frames, masks, setup, settings = _at_working(frames, masks, setup, settings, current.shape, n)
        out.positions = at_level(out.positions, n)
    if settings.relight:  # in the light of the frame the run started from, as track saw them
        frames = Relit(frames, read_frame(frames, begin, None), settings.clip)
    current = read_frame(frames, frame, None)
    plan = _plans(setup, settings, current, out.positions[frame])
    templates = []
    pyramids = {frame: Pyramid(current)}  # one per frame cut from, read and reduced once
    for m in range(k):
        cut = _anchor_frame(out.confidence[:, m], begin, frame, m in fixed, settings.match.update_confidence)
        if cut not in pyramids:
            pyramids[cut] = Pyramid(read_frame(frames, cut, current.shape))
        centre, angle = out.positions[cut, m], out.angles[cut, m]
        templates.append(cut_templates(pyramids[cut], centre, angle, plan(m).size, settings.match))
    history = np.where(np.isin(np.arange(k), list(fixed)), frame, begin)
    figure = None if masks is None else FigureMasks(masks, count, current.shape, tuning=settings.clip)
    on_figure = None if figure is None else figure.holds(frame, out.positions[frame])
    if progress:
        progress("tracking", frame, stop)
    _run(frames, current.shape, plan, templates, out, history, frame + 1, stop, progress, figure, on_figure,
         settings.best_path, own, tuning=settings.tuning, clip=settings.clip)
    if settings.both_ways:
        _run_back(frames, masks, current.shape, plan, templates, out, frame, stop, on_figure, settings.tuning,
                  settings.clip)
    return _in_frame_pixels(_filled(out, plan, settings, figure, on_figure, since=frame).freeze(), n)


def _at_working(frames, masks, setup, settings, shape, n):
    """The frames, masks, setup and settings halved ``n`` times (:mod:`~toonmotion.capture.track_scale`),
    for frames of ``shape``; a frame or mask of another size is named in the frames' own pixels."""
    frames = ReducedFrames(frames, n, shape)
    masks = None if masks is None else ReducedMasks(masks, n, shape)
    setup = TrackSetup(skeleton=setup.skeleton, sizes=at_level(setup.sizes, n))
    search = None if settings.search is None else float(at_level(settings.search, n))
    settings = replace(settings, search=max(search, 1.0) if search is not None else None,
                       w_beta=working_weight(settings.w_beta, n))
    return frames, masks, setup, settings


def _in_frame_pixels(tracking, n):
    """``tracking`` made after ``n`` halvings, its positions in the frames' own pixels."""
    return replace(tracking, positions=from_working(tracking.positions, n)) if n else tracking


# --- the tracking loop -----------------------------------------------------------------------------


@dataclass
class _Arrays:
    """The writable arrays of a Tracking being made."""

    positions: np.ndarray
    angles: np.ndarray
    confidence: np.ndarray
    tracked: np.ndarray
    held: np.ndarray
    # (T, k, others + 1, 3): the other places each joint's search found (MatchTuning.others) and,
    # tracked both ways, the place the tracking backwards gave it (the last), for the whole-sequence pass.
    options: np.ndarray

    @classmethod
    def empty(cls, count: int, k: int, others: int) -> _Arrays:
        return cls(np.full((count, k, 2), np.nan), np.full((count, k), np.nan), np.zeros((count, k)),
                   np.zeros(count, dtype=bool), np.zeros(count, dtype=bool), _no_options(count, k, others))

    @classmethod
    def copy(cls, tracking: Tracking, others: int) -> _Arrays:
        assert tracking.held is not None  # Tracking fills it in
        count, k = tracking.confidence.shape
        return cls(tracking.positions.copy(), tracking.angles.copy(), tracking.confidence.copy(),
                   tracking.tracked.copy(), tracking.held.copy(), _no_options(count, k, others))

    def clear(self, begin: int, end: int) -> None:
        self.positions[begin:end] = np.nan
        self.angles[begin:end] = np.nan
        self.confidence[begin:end] = 0.0
        self.tracked[begin:end] = False
        self.held[begin:end] = False

    def freeze(self) -> Tracking:
        return Tracking(positions=self.positions, angles=self.angles, confidence=self.confidence,
                        tracked=self.tracked, held=self.held)


def _run(frames, shape, plans: Plans, templates: list[Templates], out: _Arrays, history, begin, stop,
         progress, figure=None, on_figure=None, options=True, own=None, *, tuning, clip):
    """Track frames ``begin`` to ``stop - 1``; frame ``begin - 1`` is tracked; write into ``out``
    (with ``options``, the other places each joint's search found too). A held drawing is told on
    ``own``, the footage's own frames where ``frames`` are halved (:func:`_held_on`); ``tuning``
    is the search's (:class:`~toonmotion.capture.search_tuning.SearchTuning`), ``clip`` the
    reading of the clip's (:class:`~toonmotion.capture.clip_tuning.ClipTuning`), the matching's
    the one ``plans`` carry (:class:`~toonmotion.capture.match_tuning.MatchTuning`)."""
    P, C, match = out.positions, out.confidence, plans.tuning
    drawings = _drawings(out, begin, clip.coast_steps)
    visible = match.visible_confidence
    lost = hidden_for(C, drawings, history, visible=visible)
    longest = longest_bones(P, C, drawings, plans.hangs_from, visible=visible)
    search = FrameSearch(plans, templates, P, C, out.angles, lost, longest, figure, on_figure, tuning)
    told = frames if own is None else own
    drawn = read_frame(told, begin - 1, None)
    work = np.empty_like(drawn)
    for t in range(begin, stop):
        image = read_frame(frames, t, shape)
        seen = image if own is None else read_frame(own, t, drawn.shape)
        out.tracked[t] = True
        if is_held(seen, drawn, work=work, tuning=clip):
            P[t], C[t], out.angles[t], out.held[t] = P[t - 1], C[t - 1], out.angles[t - 1], True
        else:
            predicted, coast = predict(P, C, np.array(drawings), history, tuning=clip, match=match)
            # A drawing held n frames moves n frames' worth by the next: the search widens with it.
            pace = float(min(t - drawings[-1], search.tuning.max_hold))
            search.frame(image, t, predicted, coast, pace=pace)
            if options:
                for m, found in enumerate(search.taken):
                    if found is not None:
                        out.options[t, m, :len(found.others)] = found.others
            drawings = drawings[-clip.coast_steps:] + [t]
            drawn = seen
        if progress:
            progress("tracking", t, stop)


def _held_on(frames, first, settings):
    """The frames a held drawing is told on where the tracker halves them: their own, in the light
    of ``first`` if the settings relight them. Halving blurs a slow move away: a 1080p clip halved
    had 10 frames taken for held where 2 were, and its joints stood still on the other 8."""
    return Relit(frames, first, settings.clip) if settings.relight else frames


def _plans(setup, settings, image, centres):
    """The joints' :class:`~toonmotion.capture.joint_plan.Plans` for ``setup`` and ``settings``:
    templates cut from ``image`` at ``centres`` (grown where the rectangle is not distinct,
    :func:`~toonmotion.capture.patches.distinct_size`), windows as the rectangles ask."""
    tune = settings.tuning
    r = [settings.search if settings.search is not None
         else max(tune.min_search, tune.search_fraction * max(w, h)) for w, h in setup.sizes]
    whole = [(max(1, int(math.floor(w + 0.5))), max(1, int(math.floor(h + 0.5)))) for w, h in setup.sizes]
    sizes = [distinct_size(image, centre, size, settings.match)
             for centre, size in zip(centres, whole, strict=True)]
    return Plans(sizes, setup.skeleton.parents, r, w_alpha=settings.w_alpha, w_beta=settings.w_beta,
                 rotate=settings.rotate, frame_shape=image.shape, tuning=settings.match)


def _filled(out, plans, settings, figure, on_figure, since=0):
    """``out`` after the whole-sequence pass, if ``settings`` ask for it, from frame ``since`` on
    (the frames before a correction are kept); joints it re-placed off the figure are put back on
    it (as the frame-by-frame search puts them)."""
    if settings.best_path:
        drawings = np.flatnonzero(out.tracked & ~out.held)
        radius = np.array([plans(m).radius for m in range(len(plans))], dtype=float)
        P, C = best_paths(out.positions, out.confidence, out.options, plans.hangs_from,
                          drawings[drawings >= since], radius, tuning=settings.tuning)
        for t in np.flatnonzero(out.tracked[since + 1:]) + since + 1:  # held frames repeat the one before
            if out.held[t]:
                P[t], C[t] = P[t - 1], C[t - 1]
            out.angles[t] = out.angles[t - 1] + turns(P[t - 1], P[t], plans.parents, True)
        out.positions, out.confidence = P, C
    if settings.fill_gaps:
        out.positions = fill_hidden_spans(out.positions, out.confidence, plans.hangs_from, out.tracked,
                                          out.held, since, tuning=settings.clip, match=settings.match)
        if figure is not None:
            limit = np.array([plans(m).radius * settings.tuning.max_widen for m in range(len(plans))])
            hidden = out.confidence < settings.match.visible_confidence
            hidden &= on_figure & (out.tracked & ~out.held)[:, None]
            hidden[:since] = False
            put_on_figure(out.positions, hidden, figure, limit)
            for t in np.flatnonzero(out.held[since:]) + since:  # held frames repeat the frame before
                out.positions[t] = out.positions[t - 1]
    return out


def _no_options(count, k, others):
    return np.full((count, k, others + 1, 3), np.nan)


def _run_back(frames, masks, shape, plans, templates, out, start, stop, on_figure, tuning, clip):
    """Track frames ``stop - 2`` down to ``start + 1`` backwards, from where ``out`` puts the joints
    on frame ``stop - 1`` (as sure of them as it is) with the ``templates``' anchors (never re-cut:
    only the latest are); write where each joint went, with its confidence, as the last of its
    options (:mod:`~toonmotion.capture.track_path`)."""
    count, k = stop - start, out.positions.shape[1]
    if count < 3:
        return
    others = plans.tuning.others
    back = _Arrays.empty(count, k, others)
    back.positions[0], back.angles[0] = out.positions[stop - 1], out.angles[stop - 1]
    back.confidence[0], back.tracked[0] = out.confidence[stop - 1], True
    figure = None if masks is None else FigureMasks(_Backwards(masks, start, stop), count, shape, tuning=clip)
    anchors = [replace(t, latest=t.anchor) for t in templates]
    _run(_Backwards(frames, start, stop), shape, plans, anchors, back, np.zeros(k, int), 1, count - 1, None,
         figure, on_figure, options=False, tuning=tuning, clip=clip)
    for i in range(1, count - 1):
        out.options[stop - 1 - i, :, others] = np.column_stack([back.positions[i], back.confidence[i]])


class _Backwards(Sequence):
    """Items ``start`` to ``stop - 1`` of a sequence, last first."""

    def __init__(self, items, start, stop):
        self._items, self._start, self._stop = items, start, stop

    def __len__(self):
        return self._stop - self._start

    def __getitem__(self, i):
        if not 0 <= i < len(self):
            raise IndexError(i)
        return self._items[self._stop - 1 - i]


def _drawings(out, begin, steps):
    """The last (up to) ``steps + 1`` tracked frames before ``begin`` that are not held."""
    frames = [s for s in range(begin - 1, -1, -1) if out.tracked[s] and not out.held[s]][:steps + 1]
    return frames[::-1] or [begin - 1]


# --- retracking and input checks ---------------------------------------------------------------------


def _run_start(tracked, frame):
    """First frame of the run of tracked frames that holds ``frame``."""
    before = np.flatnonzero(~tracked[:frame])
    return int(before[-1]) + 1 if before.size else 0


def _anchor_frame(confidence, begin, frame, corrected, plain):
    """Where to re-cut a joint's templates: ``frame``, or the last frame before it at least ``plain``
    confident."""
    if corrected:
        return frame
    confident = np.flatnonzero(confidence[begin:frame + 1] >= plain)
    return begin + int(confident[-1]) if confident.size else begin


def _settings(settings):
    if settings is None:
        return TrackSettings()
    if not isinstance(settings, TrackSettings):
        raise TrackingError(f"settings must be a TrackSettings, got {type(settings).__name__}")
    return settings


def _setup(setup):
    if not isinstance(setup, TrackSetup):
        raise TrackingError(
            f"setup must be a TrackSetup (skeleton and rectangle sizes), got {type(setup).__name__}"
        )
    return setup
