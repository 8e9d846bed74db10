"""Joint tracking through an image sequence (thesis 4.3 and 4.4, eq. 4.1, 4.2, 4.4 and 4.6).

The user marks a rectangle round every joint on one frame (thesis 4.3); :func:`track` follows
each rectangle frame by frame to the place where the mixed cost of eq. 4.6 is least,

    D = w_alpha D_c + w_beta D_g,

``D_c`` the RGB colour difference between the rectangle and the joint's template (eq. 4.1),
``D_g`` the squared distance from the centre predicted by constant acceleration (eq. 4.4).
Rectangles of joints with a parent turn with their bone (eq. 4.2). :func:`retrack` takes a
user's corrections at one frame and tracks again from there (thesis 4.4.3 and 6.3e).

Coordinates are (x, y) pixels, y down; the pixel in row ``i``, column ``j`` is centred on
``(j, i)`` and covers half a pixel each side. Time is in frames: the thesis' ``tau`` is 1.
RGB or BGR does not matter: every channel is weighed the same.

Choices where the thesis leaves them open:

- The colour term is the *mean* over the rectangle's pixels of the squared RGB difference
  summed over the three channels (eq. 4.1 divided by the pixel count), so ``w_alpha D_c`` lies
  in ``[0, 3]`` whatever the rectangle's size. The thesis' sum with ``w_alpha = 1/255^2`` is
  hundreds of times larger than ``w_beta D_g <= 1`` inside the search range, so the prediction
  would only break ties. With the mean the two are comparable, and where the joint is hidden
  (the colour cost high everywhere) the prediction decides.
- The mean gives the prediction real pull: a wholly different texture of contrast 60 costs about
  0.33, as much as a perfect match 0.57 r from the prediction. So the mixed cost picks among the
  *plain* cells, those whose texture matches with confidence >= :data:`UPDATE_CONFIDENCE`, when
  there are any (the prediction then only chooses between look-alikes, as in the thesis), and
  among all cells when there are none (occlusion, a changed texture). And the colour alone then
  places the match: from the chosen cell it steps to the colour cost's local minimum, then fits
  a parabola through that minimum and its two neighbours, in x and in y. Refining the mixed cost
  instead would bias every visible joint towards its prediction by ``w_beta / (w_beta + K)`` of
  the prediction error, ``K`` the colour cost's curvature (about a fifth for a smooth texture:
  half a pixel when the prediction is 2.5 px off, as on the second frame of any motion).
- The search tries every whole-pixel offset up to ``floor(r)`` in x and in y from the
  prediction (a square, its corners penalised by ``w_beta D_g`` up to 2), with
  ``cv2.matchTemplate`` (``TM_SQDIFF``), instead of the thesis' anticlockwise walk over
  8-neighbours (fig. 4.4), which stops in the first local minimum. The parabola's vertex moves
  at most half a pixel, and no further than a parabola that stays >= 0 allows
  (``|dx| <= sqrt(2 c / k)``, ``c`` the minimum's sum of squares, recomputed exactly, ``k`` the
  curvature): an exact copy stays exactly where it is, so still frames do not drift. Sums of
  squares closer than half a grey level per pixel and channel (uint8 rounding, float32 sums) are
  ties, so a flat-coloured rectangle is not pushed about by rounding: the prediction places it.
- The default search radius is ``max(MIN_SEARCH, SEARCH_FRACTION * larger rectangle side)``:
  ±10 px for a 20 px rectangle. It scales with the rectangle, which the user draws to the size
  of the joint, so a figure drawn twice as large (and moving twice as many pixels) searches
  twice as far; the window is then twice the rectangle, never reaching a whole rectangle
  beyond the prediction, where a match would rather be another feature. ``MIN_SEARCH`` keeps
  small rectangles able to catch a joint a few pixels off its prediction. ``w_beta`` defaults to
  ``1 / r^2`` with each joint's own ``r``.
- Prediction (eq. 4.4, ``tau`` = 1): ``p + v + a / 2`` from a joint's last three positions;
  from two, ``p + v``; from one, ``p``. A joint's history starts at the frame tracking started
  (or where it was corrected): its velocity there is 0. Positions guessed while a joint was
  hidden (below) give no acceleration, and the step from the last guess to where the joint is
  found again is not taken as a velocity: the guesses' velocity carries on.
- Rotation (eq. 4.2): eq. 4.2 takes ``2 arctg(dy / dx)`` of the *difference* of the old and new
  bone vectors, which is not the angle between them (it is undefined for a bone that only
  translates, and wrong for one that turns and stretches). Here a rectangle turns by the signed
  angle from its bone's vector (parent to joint) at the previous frame to the predicted one,
  ``atan2(cross, dot)``; a root's rectangle, and every rectangle with ``rotate=False``, never
  turns. ``Tracking.angles`` sums these turns from the tracked positions: it is the bone's
  direction relative to frame ``start``, unwrapped. The thesis re-samples the *template*; this
  re-samples the search window instead, turned about the prediction by the rectangle's angle
  (``cv2.warpAffine``, bilinear, border pixels repeated). That is the same match, but keeps every
  template pixel and brings in no background at the corners of a turned template's bounding
  box. Templates are kept in the rectangle's own frame, cut the same way, so a window and a
  template sampled at the same place are the same pixels. A predicted turn lags a bone that
  starts turning (the first frames know no turn at all): a turning rectangle whose match at the
  predicted angle has confidence below :data:`TURN_CONFIDENCE` also tries :data:`TURNS`
  (±5, ±10, ±15 degrees) and keeps the most confident match. A limb that sets off at 12 degrees a
  frame is lost without this and tracked within 0.03 px with it. The bar is 0.6, not the 0.8 of
  a template update: a joint partly covered by another part matches at 0.6-0.8 at the right
  angle, and trying six more turns for it every frame cost the shared jumping-jacks clip two
  thirds of its speed (64 frames/s against 174) for no gain in accuracy.
- Templates: the thesis matches against the previous frame's rectangle, ``c_{m,t-1}``; then
  every frame's sub-pixel error is carried into the next template (the track random-walks away:
  1.06 px after 150 frames of a smoothly wandering patch, against 0.05 px here), and a rectangle
  sliding under an occluder learns the occluder and sticks to it. Here each joint keeps an
  *anchor*, cut where tracking starts (thesis precondition 3: no joint is occluded there), and a
  *latest*; both are matched each frame, and they *agree* when their matches lie within
  :data:`DRIFT_TOLERANCE` of each other. The anchor's match is taken when they agree and it is
  visible (confidence >= :data:`VISIBLE_CONFIDENCE`), or when it is at least as confident as the
  latest's: it removes the latest's drift (Matthews, Ishikawa and Baker 2004, "The template
  update problem", strategy 3). Otherwise the latest's match is taken: the texture has changed
  since the start. The latest is re-cut only where the two agree and the match taken has
  confidence >= :data:`UPDATE_CONFIDENCE`. So a joint sliding under an occluder does not teach
  its latest the occluder: the anchor still finds the joint's visible part, but less and less
  confidently, and its match is the one taken. The price: a texture that changes far from the
  anchor stops being learnt. Tracking in segments (:func:`retrack`) re-cuts the anchors.
- Confidence: ``exp(-d^2 / (2 CONFIDENCE_SCALE^2))``, ``d`` the root mean square difference per
  channel of the chosen match (``CONFIDENCE_SCALE`` = 30 grey levels): 1 for an exact match,
  0.8 at ``d`` = 20, 0.5 at ``d`` = 35. Noise of a few levels keeps it near 1; a different texture
  in the rectangle puts it near 0.
- Occlusion: a joint whose best match has confidence below :data:`VISIBLE_CONFIDENCE` is taken to
  be hidden: its position is guessed and its templates are left alone. A joint with a parent
  is carried by it: it keeps its last offset from the parent, turned as the parent's own bone
  turned (a hidden hand goes where its elbow takes it). That is the skeleton's geometric prior,
  and it cannot run away: coasting on velocity alone carried hidden joints hundreds of pixels off
  over long occlusions (mean error on the first 120 frames of the shared walking clip 73.5 px
  coasting, 31.2 px carried; fair_jumping 75.7 and 24.3). A root coasts at constant velocity,
  the mean over its last (up to) :data:`COAST_STEPS` visible steps: velocity it was seen to
  have, less swayed than the last step alone by a rectangle already partly covered, and no
  acceleration, the noisiest term, which integrated over several blind frames would carry it
  off quadratically. The search picks the joint up where it re-emerges.
- :func:`retrack` keeps every frame before the corrected one; the other joints keep their
  positions and their history at that frame, so they carry on at their speed. A corrected joint
  starts afresh there (its earlier positions were wrong, so is their velocity) with confidence 1.
  Each joint's anchor and latest are re-cut at the corrected frame if it was corrected or matched
  there with confidence >= :data:`UPDATE_CONFIDENCE`, else at the last frame before where it did.
- Frames are checked as they are read (a lazy sequence is read once): an odd frame stops
  tracking there with a :class:`TrackingError` that names it.
"""

import math
import numbers
from dataclasses import dataclass

import cv2
import numpy as np

from toonmotion.errors import TrackingError
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

# Default search radius: this fraction of a rectangle's larger side, at least MIN_SEARCH px.
SEARCH_FRACTION = 0.5
MIN_SEARCH = 8.0

# Confidence is exp(-d^2 / (2 CONFIDENCE_SCALE^2)), d the RMS difference per channel (grey levels).
CONFIDENCE_SCALE = 30.0

# Cells matching at least this confidently are plain; a match this confident, where both templates
# agree, re-cuts the joint's latest template.
UPDATE_CONFIDENCE = 0.8

# A joint whose best match is less confident than this is hidden: it coasts on its velocity.
VISIBLE_CONFIDENCE = 0.5

# A joint that hides coasts at its mean velocity over this many visible steps (at most).
COAST_STEPS = 4

# The anchor's and the latest template's matches agree when they lie within this many pixels.
DRIFT_TOLERANCE = 2.0

# A turning rectangle that matches poorly at its predicted angle also tries these turns, radians.
# A turning rectangle matching less confidently than this at its predicted angle tries TURNS too.
TURN_CONFIDENCE = 0.6
TURNS = tuple(math.radians(sign * step) for step in (5, 10, 15) for sign in (1, -1))

_WARP = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP


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

    def __post_init__(self):
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
        Search radius ``r``, pixels, >= 1. None: per joint, ``max(MIN_SEARCH, SEARCH_FRACTION *
        larger rectangle side)``.
    w_alpha : float
        Weight of the mean colour difference, > 0 (thesis: ``1 / 255^2``).
    w_beta : float or None
        Weight of the squared distance from the prediction, >= 0. None: ``1 / r^2`` (thesis).
    rotate : bool
        Turn the rectangles of joints with a parent with their bone (eq. 4.2).
    """

    search: float | None = None
    w_alpha: float = 1 / 255**2
    w_beta: float | None = None
    rotate: bool = True

    def __post_init__(self):
        if self.search is not None:
            object.__setattr__(self, "search", _number(self.search, "the search radius (px)", 1.0, ">= 1"))
        object.__setattr__(self, "w_alpha", _number(self.w_alpha, "w_alpha", 0.0, "> 0", strict=True))
        if self.w_beta is not None:
            object.__setattr__(self, "w_beta", _number(self.w_beta, "w_beta", 0.0, ">= 0"))
        if not isinstance(self.rotate, (bool, np.bool_)):
            raise TrackingError(f"rotate must be True or False, got {self.rotate!r}")
        object.__setattr__(self, "rotate", bool(self.rotate))


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
        How well the texture matched: near 1 on a clean match, below ``VISIBLE_CONFIDENCE``
        where the joint was taken to be hidden (its position then predicted); 0 at frames not
        tracked.
    tracked : (T,) bool
        Frames that have been tracked: ``start`` up to ``stop``.
    """

    positions: np.ndarray
    angles: np.ndarray
    confidence: np.ndarray
    tracked: np.ndarray

    def __post_init__(self):
        kinds = (("positions", float), ("angles", float), ("confidence", float), ("tracked", bool))
        for name, dtype in kinds:
            array = np.array(getattr(self, name), dtype=dtype)
            array.setflags(write=False)
            object.__setattr__(self, name, array)
        T = len(self.tracked)
        k = self.angles.shape[1] if self.angles.ndim == 2 else -1
        if (self.tracked.shape, self.angles.shape, self.confidence.shape, self.positions.shape) != (
            (T,), (T, k), (T, k), (T, k, 2)
        ):
            raise TrackingError(
                "a Tracking needs positions (T, k, 2), angles and confidence (T, k) and tracked (T,); "
                f"got {self.positions.shape}, {self.angles.shape}, {self.confidence.shape} "
                f"and {self.tracked.shape}"
            )


def track(frames, setup, *, settings=None, start=0, stop=None, initial=None, progress=None):
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
    progress : callable, optional
        Called as ``progress(frame, count)`` once each frame from ``start`` is done, with
        ``count = stop``.

    Returns
    -------
    Tracking

    Examples
    --------
    A textured square moving 2 px right and 1 px down per frame:

    >>> rng = np.random.default_rng(0)
    >>> scene = rng.integers(0, 256, (60, 90, 3), dtype=np.uint8)
    >>> frames = np.stack([np.roll(scene, (t, 2 * t), axis=(0, 1)) for t in range(5)])
    >>> setup = TrackSetup(Skeleton.from_joints([("dot", None, (30, 25))]), sizes=[[12, 12]])
    >>> np.round(track(frames, setup).positions[:, 0], 3).tolist()
    [[30.0, 25.0], [32.0, 26.0], [34.0, 27.0], [36.0, 28.0], [38.0, 29.0]]
    """
    settings, setup = _settings(settings), _setup(setup)
    count = _count(frames)
    start = _index(start, "start", 0, count - 1, count)
    stop = count if stop is None else _index(stop, "stop", start + 1, count, count)
    first = _frame(frames, start, None)
    k = len(setup.skeleton)
    initial = setup.skeleton.positions if initial is None else _initial(initial, k)
    _check_inside(setup, initial, np.zeros(k), first, start, range(k))
    out = _Arrays.empty(count, k)
    out.positions[start] = initial
    out.angles[start] = 0.0
    out.confidence[start] = 1.0
    out.tracked[start] = True
    joints = _plan(setup, settings)
    templates = [_Templates.cut(first, initial[m], 0.0, joints[m].size) for m in range(k)]
    if progress:
        progress(start, stop)
    _run(frames, first.shape, joints, templates, out, np.full(k, start), start + 1, stop, progress)
    return out.freeze()


def retrack(tracking, frames, setup, frame, corrections, *, settings=None, progress=None):
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
    progress : callable, optional
        Called as ``progress(frame, count)`` once each frame from ``frame`` is done, with
        ``count`` one past the last tracked frame.

    Returns
    -------
    Tracking
        Frames before ``frame`` as in ``tracking``; ``frame`` with the corrections; every later
        frame that ``tracking`` covered, tracked again.
    """
    settings, setup = _settings(settings), _setup(setup)
    if not isinstance(tracking, Tracking):
        raise TrackingError(f"retrack needs the Tracking to correct, got {type(tracking).__name__}")
    count, k = _count(frames), len(setup.skeleton)
    if tracking.positions.shape != (count, k, 2):
        raise TrackingError(
            f"the tracking covers {tracking.positions.shape[0]} frames of {tracking.positions.shape[1]} "
            f"joints, but there are {count} frames and {k} joints; "
            "retrack with the frames and setup it was made from"
        )
    frame = _index(frame, "the frame to correct", 0, count - 1, count)
    if not tracking.tracked[frame]:
        raise TrackingError(f"frame {frame} was not tracked; correct a tracked frame")
    fixed = _corrections(corrections, setup.skeleton)
    begin = _run_start(tracking.tracked, frame)
    stop = frame + 1 + int(np.argmin(np.append(tracking.tracked[frame + 1:], False)))

    out = _Arrays.copy(tracking)
    out.clear(frame + 1, stop)
    for m, xy in fixed.items():
        out.positions[frame, m] = xy
        out.confidence[frame, m] = 1.0
    if frame > begin:
        out.angles[frame] = out.angles[frame - 1] + _turns(
            out.positions[frame - 1], out.positions[frame], setup.skeleton.parents, settings.rotate
        )
    current = _frame(frames, frame, None)
    _check_inside(setup, out.positions[frame], out.angles[frame], current, frame, fixed)
    joints = _plan(setup, settings)
    templates = []
    for m in range(k):
        cut = _anchor_frame(out.confidence[:, m], begin, frame, m in fixed)
        image = current if cut == frame else _frame(frames, cut, current.shape)
        templates.append(_Templates.cut(image, out.positions[cut, m], out.angles[cut, m], joints[m].size))
    history = np.where(np.isin(np.arange(k), list(fixed)), frame, begin)
    if progress:
        progress(frame, stop)
    _run(frames, current.shape, joints, templates, out, history, frame + 1, stop, progress)
    return out.freeze()


# --- the tracking loop -----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Joint:
    """Per joint, fixed for a run: template size, search radius, weights, parent."""

    size: tuple  # (tw, th) whole pixels
    radius: int  # R: offsets -R..R are searched
    w_alpha: float  # per mean: w_alpha / (tw th), applied to the SSD
    w_beta: float
    parent: int  # -1: the rectangle does not turn
    hangs_from: int  # the joint's parent in the skeleton, -1 for a root (a hidden joint follows it)
    geometric: np.ndarray  # (2R+1, 2R+1) w_beta times squared offset from the window centre
    plain: float  # the SSD of a match with confidence UPDATE_CONFIDENCE
    tie: float  # SSDs closer than this are equal: half a grey level per pixel and channel


@dataclass
class _Templates:
    """A joint's anchor (cut where tracking started) and latest (last confident match).

    Both ``(th, tw, 3)`` float32, in the rectangle's own frame (see :func:`_sample`).
    """

    anchor: np.ndarray
    latest: np.ndarray

    @classmethod
    def cut(cls, image, centre, angle, size):
        patch = _sample(image, centre, angle, size)
        return cls(anchor=patch, latest=patch)


@dataclass
class _Arrays:
    """The writable arrays of a Tracking being made."""

    positions: np.ndarray
    angles: np.ndarray
    confidence: np.ndarray
    tracked: np.ndarray

    @classmethod
    def empty(cls, count, k):
        return cls(np.full((count, k, 2), np.nan), np.full((count, k), np.nan), np.zeros((count, k)),
                   np.zeros(count, dtype=bool))

    @classmethod
    def copy(cls, tracking):
        return cls(tracking.positions.copy(), tracking.angles.copy(), tracking.confidence.copy(),
                   tracking.tracked.copy())

    def clear(self, begin, end):
        self.positions[begin:end] = np.nan
        self.angles[begin:end] = np.nan
        self.confidence[begin:end] = 0.0
        self.tracked[begin:end] = False

    def freeze(self):
        return Tracking(positions=self.positions, angles=self.angles, confidence=self.confidence,
                        tracked=self.tracked)


def _plan(setup, settings):
    """A :class:`_Joint` per joint."""
    joints = []
    for m, (w, h) in enumerate(setup.sizes):
        size = (max(1, int(math.floor(w + 0.5))), max(1, int(math.floor(h + 0.5))))
        r = settings.search if settings.search is not None else max(MIN_SEARCH, SEARCH_FRACTION * max(w, h))
        w_beta = 1.0 / r**2 if settings.w_beta is None else settings.w_beta
        R = int(math.floor(r))
        offsets = np.arange(-R, R + 1, dtype=float) ** 2
        parent = int(setup.skeleton.parents[m]) if settings.rotate else -1
        joints.append(_Joint(size=size, radius=R, w_alpha=settings.w_alpha / (size[0] * size[1]),
                             w_beta=w_beta, parent=parent, hangs_from=int(setup.skeleton.parents[m]),
                             geometric=w_beta * (offsets[:, None] + offsets[None, :]),
                             plain=_ssd_at(UPDATE_CONFIDENCE, size), tie=0.25 * 3 * size[0] * size[1]))
    return joints


def _run(frames, shape, joints, templates, out, history, begin, stop, progress):
    """Track frames ``begin`` to ``stop - 1``; frame ``begin - 1`` is tracked; write into ``out``."""
    parents = np.array([j.parent for j in joints])
    for t in range(begin, stop):
        image = _frame(frames, t, shape)
        P = out.positions
        predicted, coast = _predict(P, out.confidence, t, history)
        angle = out.angles[t - 1] + _turns(P[t - 1], predicted, parents, True)
        update = []
        for m, joint in enumerate(joints):
            xy, confidence, agree = _match(image, templates[m], predicted[m], angle[m], joint)
            if confidence < VISIBLE_CONFIDENCE:
                xy = _hidden_at(P, t, m, joint, coast[m], joints)
            elif agree and confidence >= UPDATE_CONFIDENCE:
                update.append(m)
            P[t, m] = xy
            out.confidence[t, m] = confidence
        out.angles[t] = out.angles[t - 1] + _turns(P[t - 1], P[t], parents, True)
        out.tracked[t] = True
        for m in update:
            templates[m].latest = _sample(image, P[t, m], out.angles[t, m], joints[m].size)
        if progress:
            progress(t, stop)


def _hidden_at(P, t, m, joint, coast, joints):
    """Where hidden joint ``m`` is put at frame ``t``: carried by its parent, else coasting.

    A joint with a parent keeps its last offset from it, turned as the parent's own bone turned
    this frame (a hidden hand goes where its elbow takes it). Coasting on its own velocity would
    run away over a long occlusion (hundreds of pixels on the shared walking clips).
    """
    p = joint.hangs_from
    if p < 0:
        return coast
    offset = P[t - 1, m] - P[t - 1, p]
    g = joints[p].hangs_from
    if g >= 0:
        before, after = P[t - 1, p] - P[t - 1, g], P[t, p] - P[t, g]
        if np.hypot(*before) > MIN_BONE_LENGTH and np.hypot(*after) > MIN_BONE_LENGTH:
            turn = math.atan2(before[0] * after[1] - before[1] * after[0], before @ after)
            c, s = math.cos(turn), math.sin(turn)
            offset = np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
    return P[t, p] + offset


def _predict(P, C, t, history):
    """Eq. 4.4 from each joint's last (up to) three positions, and where a hidden joint coasts to.

    ``C`` is the confidence. A position guessed while hidden gives no acceleration, and the step
    from the last guess to a re-found joint is not a velocity: the guesses' velocity carries on.
    A joint that hides at ``t`` coasts at its mean velocity over its last (up to) COAST_STEPS
    visible steps, less swayed than one step by a rectangle already partly covered.
    Returns ``(k, 2)`` predicted centres and ``(k, 2)`` coasting centres.
    """
    k = len(history)
    seen = (t - history)[:, None]  # tracked frames each joint's history has before t (>= 1)
    first = max(t - COAST_STEPS - 1, 0)
    visible = (C[first:t] >= VISIBLE_CONFIDENCE) & (np.arange(first, t)[:, None] >= history)
    v1, v2, v3 = (visible[-i][:, None] if i <= len(visible) else np.zeros((k, 1), bool) for i in (1, 2, 3))
    p1 = P[t - 1]
    p2 = np.where(seen >= 2, P[max(t - 2, 0)], p1)
    p3 = np.where(seen >= 3, P[max(t - 3, 0)], p2)
    v = np.where(v1 & ~v2 & (seen >= 2), p2 - p3, p1 - p2)
    a = np.where(v1 & v2 & v3, v - (p2 - p3), 0.0)
    steps = np.cumprod(visible[::-1], axis=0).sum(axis=0) - 1  # visible steps ending at t - 1
    mean = (p1 - P[t - 1 - np.maximum(steps, 0), np.arange(k)]) / np.maximum(steps, 1)[:, None]
    coast = np.where(v1 & (steps >= 1)[:, None], mean, v)
    return p1 + v + a / 2, p1 + coast


def _turns(before, after, parents, rotate):
    """``(k,)`` signed angle each bone (parent to joint) turns from ``before`` to ``after``, (k, 2) each.

    0 for roots, bones shorter than ``MIN_BONE_LENGTH`` and with ``rotate`` False.
    """
    turns = np.zeros(len(parents))
    child = np.flatnonzero(parents >= 0) if rotate else np.array([], dtype=int)
    if child.size:
        a = before[child] - before[parents[child]]
        b = after[child] - after[parents[child]]
        cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        dot = (a * b).sum(axis=1)
        ok = (np.hypot(*a.T) > MIN_BONE_LENGTH) & (np.hypot(*b.T) > MIN_BONE_LENGTH)
        turns[child] = np.where(ok, np.arctan2(cross, dot), 0.0)
    return turns


def _match(image, templates, predicted, angle, joint):
    """Match a joint's templates round ``predicted``, its rectangle turned by ``angle``.

    Returns the ``(x, y)`` found, its confidence, and whether the anchor agrees with the latest.
    A rectangle that turns and matches poorly also tries :data:`TURNS` more; the most confident
    match is kept.
    """
    found = _match_turned(image, templates, predicted, angle, joint)
    for turn in TURNS if joint.parent >= 0 else ():
        if found[1] >= TURN_CONFIDENCE:
            break
        other = _match_turned(image, templates, predicted, angle + turn, joint)
        if other[1] > found[1]:
            found = other
    return found


def _match_turned(image, templates, predicted, angle, joint):
    """:func:`_match` at one angle (module notes, templates)."""
    R, (tw, th) = joint.radius, joint.size
    window = _sample(image, predicted, angle, (tw + 2 * R, th + 2 * R))
    latest = _best(window, templates.latest, joint)
    (offset, confidence), agree = latest, True
    if templates.anchor is not templates.latest:
        anchor = _best(window, templates.anchor, joint)
        agree = bool(np.hypot(*(anchor[0] - latest[0])) <= DRIFT_TOLERANCE)
        if anchor[1] >= latest[1] or (agree and anchor[1] >= VISIBLE_CONFIDENCE):
            offset, confidence = anchor
    c, s = math.cos(angle), math.sin(angle)
    return predicted + [c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]], confidence, agree


def _best(window, template, joint):
    """Best match of ``template`` in ``window``: sub-pixel ``(dx, dy)`` from the centre, confidence.

    The mixed cost picks the cell; the colour cost alone then places the match (module notes).
    """
    R, (tw, th) = joint.radius, joint.size
    ssd = cv2.matchTemplate(window, template, cv2.TM_SQDIFF)
    cost = joint.w_alpha * ssd + joint.geometric
    plain = ssd <= joint.plain  # cells where the texture is plainly there
    if plain.any():
        cost[~plain] = np.inf
    i, j = np.unravel_index(int(np.argmin(cost)), ssd.shape)
    i, j = _descend(ssd, i, j, joint.tie)
    # The map is float32 and its sums of squares round; the chosen cell's is recomputed exactly.
    d = (window[i:i + th, j:j + tw] - template).astype(np.float64).ravel()
    exact = float(d @ d)
    dx = _vertex(ssd[i, j - 1] if j > 0 else None, exact, ssd[i, j + 1] if j < 2 * R else None, joint.tie)
    dy = _vertex(ssd[i - 1, j] if i > 0 else None, exact, ssd[i + 1, j] if i < 2 * R else None, joint.tie)
    return np.array([j - R + dx, i - R + dy]), _confidence(exact, joint.size)


def _descend(cost, i, j, tie):
    """From cell ``(i, j)``, step to the lowest of the 8 neighbours while ``cost`` drops by > ``tie``."""
    while True:
        i0, j0 = max(i - 1, 0), max(j - 1, 0)
        block = cost[i0:i + 2, j0:j + 2]
        a, b = np.unravel_index(int(np.argmin(block)), block.shape)
        if not block[a, b] < cost[i, j] - tie:
            return i, j
        i, j = i0 + a, j0 + b


def _confidence(ssd, size):
    """Confidence of a match whose sum of squared RGB differences over a ``size`` rectangle is ``ssd``."""
    return math.exp(-ssd / (size[0] * size[1] * 3) / (2 * CONFIDENCE_SCALE**2))


def _ssd_at(confidence, size):
    """The sum of squared differences that has ``confidence``: inverse of :func:`_confidence`."""
    return -math.log(confidence) * 2 * CONFIDENCE_SCALE**2 * size[0] * size[1] * 3


def _vertex(before, centre, after, tie):
    """Sub-pixel offset of a parabola's lowest point through three costs at -1, 0, 1.

    At most half a pixel, and no further than a parabola that stays >= 0 could put it; 0 at an
    edge of the map and where the curvature is no more than ``tie`` (a flat cost places nothing).
    """
    if before is None or after is None:
        return 0.0
    k = float(before) + float(after) - 2.0 * centre
    if not k > tie:
        return 0.0
    limit = min(0.5, math.sqrt(max(centre, 0.0) * 2.0 / k))
    return min(limit, max(-limit, (float(before) - float(after)) / (2.0 * k)))


def _sample(image, centre, angle, size):
    """``(h, w, 3)`` float32 patch of ``size = (w, h)`` centred on ``centre``, turned by ``angle``.

    Patch pixel ``(u, v)`` is the image at ``centre + rotation(angle) (u - (w-1)/2, v - (h-1)/2)``,
    bilinear; pixels beyond the image repeat its border.
    """
    w, h = size
    c, s = math.cos(angle), math.sin(angle)
    hx, hy = (w - 1) / 2, (h - 1) / 2
    M = np.array([[c, -s, centre[0] - c * hx + s * hy], [s, c, centre[1] - s * hx - c * hy]])
    patch = cv2.warpAffine(image, M, (w, h), flags=_WARP, borderMode=cv2.BORDER_REPLICATE)
    return patch.astype(np.float32)


# --- input checks ---------------------------------------------------------------------------------


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


def _count(frames):
    if isinstance(frames, np.ndarray) and frames.ndim != 4:
        raise TrackingError(
            f"frames have shape {frames.shape}; give a (T, h, w, 3) array or a sequence of (h, w, 3) frames"
        )
    try:
        count = len(frames)
    except TypeError:
        raise TrackingError(
            f"frames must be a (T, h, w, 3) array or a sequence of frames, got {type(frames).__name__}"
        ) from None
    if count == 0:
        raise TrackingError("there are no frames to track; give at least one")
    return count


def _frame(frames, t, shape):
    """Frame ``t`` as a contiguous (h, w, 3) uint8 array, checked; ``shape`` that of the first read."""
    image = np.asarray(frames[t])
    if image.ndim != 3 or image.shape[2] != 3 or image.dtype != np.uint8 or 0 in image.shape:
        raise TrackingError(
            f"frame {t} is a {image.dtype} array of shape {image.shape}; give (h, w, 3) uint8 RGB frames"
        )
    if shape is not None and image.shape != shape:
        raise TrackingError(
            f"frame {t} is {image.shape[1]}x{image.shape[0]} but the first frame read is "
            f"{shape[1]}x{shape[0]}; all frames must be the same size"
        )
    return np.ascontiguousarray(image)


def _index(value, what, lowest, highest, count):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not lowest <= value <= highest:
        raise TrackingError(
            f"{what} is {value!r}; with {count} frames give a whole number {lowest}..{highest}"
        )
    return int(value)


def _initial(initial, k):
    try:
        xy = np.array(initial, dtype=float)
    except (TypeError, ValueError):
        raise TrackingError(f"initial positions must be numbers, shape ({k}, 2); got {initial!r}") from None
    if xy.shape != (k, 2):
        raise TrackingError(
            f"initial positions have shape {xy.shape}; give one (x, y) per joint, shape ({k}, 2)"
        )
    if not np.all(np.isfinite(xy)):
        raise TrackingError("initial positions include a non-finite value; give finite (x, y) pixels")
    return xy


def _corrections(corrections, skeleton):
    """``{joint index: (2,) float}`` from ``{name: (x, y)}``."""
    try:
        items = list(corrections.items())
    except AttributeError:
        raise TrackingError(
            f"corrections must map joint names to (x, y), got {type(corrections).__name__}"
        ) from None
    fixed = {}
    for name, xy in items:
        if name not in skeleton.names:
            raise TrackingError(
                f"a correction names joint {name!r}, which is not tracked; "
                f"the joints are: {', '.join(skeleton.names)}"
            )
        try:
            point = np.array(xy, dtype=float)
        except (TypeError, ValueError):
            point = np.empty(0)
        if point.shape != (2,) or not np.all(np.isfinite(point)):
            raise TrackingError(f"the correction of joint {name!r} is {xy!r}; give finite (x, y) pixels")
        fixed[skeleton.index(name)] = point
    return fixed


def _check_inside(setup, centres, angles, image, t, which):
    """Raise unless the rectangles of joints ``which`` (turned by ``angles``) lie inside ``image``."""
    H, W = image.shape[:2]
    for m in which:
        (x, y), (w, h) = centres[m], setup.sizes[m]
        c, s = abs(math.cos(angles[m])), abs(math.sin(angles[m]))
        hx, hy = (c * w + s * h) / 2, (s * w + c * h) / 2
        x0, x1, y0, y1 = x - hx, x + hx, y - hy, y + hy
        if x0 < -0.5 - 1e-9 or y0 < -0.5 - 1e-9 or x1 > W - 0.5 + 1e-9 or y1 > H - 0.5 + 1e-9:
            raise TrackingError(
                f"joint {setup.skeleton.names[m]!r} has its {w:g}x{h:g} rectangle at ({x:g}, {y:g}), "
                f"spanning x {x0:g}..{x1:g}, y {y0:g}..{y1:g}, not inside frame {t} ({W}x{H}, "
                f"x -0.5..{W - 0.5:g}, y -0.5..{H - 0.5:g}); move the joint or shrink its rectangle"
            )


def _run_start(tracked, frame):
    """First frame of the run of tracked frames that holds ``frame``."""
    before = np.flatnonzero(~tracked[:frame])
    return int(before[-1]) + 1 if before.size else 0


def _anchor_frame(confidence, begin, frame, corrected):
    """Where to re-cut a joint's templates: ``frame``, or the last confident frame before it."""
    if corrected:
        return frame
    confident = np.flatnonzero(confidence[begin:frame + 1] >= UPDATE_CONFIDENCE)
    return begin + int(confident[-1]) if confident.size else begin


def _number(value, what, bound, rule, *, strict=False):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TrackingError(f"{what} must be a number {rule}, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or value < bound or (strict and value == bound):
        raise TrackingError(f"{what} must be a finite number {rule}, got {value!r}")
    return value
