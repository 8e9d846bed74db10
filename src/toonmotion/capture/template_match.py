"""Matching a joint's templates in a frame: the colour search of the joint tracker (thesis 4.4).

A joint's rectangle is matched by sampling a search window round its predicted centre, turned
by the rectangle's angle, and finding its templates in it with ``cv2.matchTemplate``
(``TM_SQDIFF``, RGB sum of squared differences, eq. 4.1). The mixed cost of eq. 4.6 picks a
whole-pixel cell (where the anchor is found again as it was cut, at one place, that place); the
colour cost alone then places the match to sub-pixel precision. Each joint
keeps two templates, an *anchor* and a *latest*, matched every frame. ``docs/capture.md``
(tracking) gives the reasons for each choice.

Coordinates are (x, y) pixels, y down; the pixel in row ``i``, column ``j`` is centred on
``(j, i)``. Patches and windows are ``(h, w, 3)`` float32 in the rectangle's own frame: patch
pixel ``(u, v)`` is the image at ``centre + rotation(angle) (u - (w-1)/2, v - (h-1)/2)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.track_figure import figure_cells, on_figure

# Confidence is exp(-d^2 / (2 CONFIDENCE_SCALE^2)), d the RMS difference per channel (grey levels).
CONFIDENCE_SCALE = 30.0

# Cells matching at least this confidently are plain; a match this confident, where both templates
# agree, re-cuts the joint's latest template.
UPDATE_CONFIDENCE = 0.8

# A joint whose best match is less confident than this is hidden: it is carried by its parent
# (a root coasts on its velocity) and its templates are left alone.
VISIBLE_CONFIDENCE = 0.25

# The anchor's and the latest template's matches agree when they lie within this many pixels.
DRIFT_TOLERANCE = 2.0

# A turning rectangle matching less confidently than this at its predicted angle tries TURNS too
# (radians).
TURN_CONFIDENCE = 0.6
TURNS = tuple(math.radians(sign * step) for step in (5, 10, 15) for sign in (1, -1))
# A rectangle on a bone seen nearly end-on (shorter than the rectangle) has no angle to go by:
# the bone's direction swings wildly with the least movement. Matching badly, it is looked for
# coarsely at turns all round (:func:`locate`).
SPIN_TURNS = tuple(math.radians(step) for step in range(0, 360, 20))
# The extra turns are ranked at half resolution; at most this many, best first, are then matched
# finely, until one matches at TURN_CONFIDENCE.
FINE_TURNS = 2
# A template is distinct when moved DISTINCT_SHIFT px in any direction it changes by at least
# DISTINCT_RATIO of its change in the direction it changes most, and by a grey level (RMS per
# channel); one that is not grows, up to MAX_GROWTH times its side (:func:`distinct_size`).
DISTINCT_SHIFT = 2.0
DISTINCT_RATIO = 0.1
DISTINCT_LEVEL = 1.0
MAX_GROWTH = 3.0

# A template is textured when at least TEXTURED_FRACTION of its pixels change by more than
# TEXTURE_LEVEL grey levels (in some channel) when it is moved DISTINCT_SHIFT px along x or along
# y: a look of its own, which other places rarely share. One drawn in flat fills and outlines
# changes along its outlines only: 22-48% of its pixels on the tracking benchmark's cel renders,
# 93-98% on its textured ones, with camera noise of 5 grey levels or without.
TEXTURE_LEVEL = 12.0
TEXTURED_FRACTION = 0.75

# Cells whose sum of squared differences exceeds the match's by less than ALIKE_LEVEL grey levels
# (RMS per channel) squared match as well as it. Joined to it, they are where the texture cannot
# tell the joint's place apart: a cell or two on a textured joint, a stretch of a flat fill.
ALIKE_LEVEL = 3.0

# A joint's anchor found again as it was cut (every cell within ALIKE_LEVEL grey levels, RMS per
# channel: compression noise) at no more than EXACT_CELLS whole-pixel cells (a place between cells
# takes up to 2 x 2) is there, however far from the prediction: among plain cells eq. 4.6's colour
# weight leaves the choice to the distance from the prediction, which holds a joint that drifted
# along a flat limb where it drifted to, even once its limb is back as it was drawn. A flat anchor
# is found as cut along a stretch of fill; the prediction still chooses there.
EXACT_CELLS = 9

# Besides its match, a joint's search keeps up to OTHERS other places where the texture is found
# (local minima of the colour cost, OTHER_SPACING px apart and at least VISIBLE_CONFIDENCE
# confident), for the whole-sequence pass to choose among (:mod:`~toonmotion.capture.track_path`).
OTHERS = 4
OTHER_SPACING = 2

# The coarse search for a hidden joint (:func:`locate`) also tries these turns (radians).
COARSE_TURNS = (0.0, math.radians(25), math.radians(-25))

_WARP = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
_REMAP_ROWS = 32000

Patch = NDArray[np.float32]


@dataclass(frozen=True)
class JointPlan:
    """Per joint, fixed for a run: template size, search radius, weights, parent.

    Attributes
    ----------
    size : (int, int)
        Template width and height ``(tw, th)``, whole pixels.
    radius : int
        ``R``: offsets ``-R..R`` from the prediction are searched, in x and in y.
    w_alpha : float
        Weight of the colour cost per mean: the thesis' ``w_alpha / (tw th)``, applied to the SSD.
    w_beta : float
        Weight of the squared distance from the prediction.
    parent : int
        The joint whose bone turns the rectangle; -1: the rectangle does not turn.
    hangs_from : int
        The joint's parent in the skeleton, -1 for a root (a hidden joint follows it).
    turns : tuple of float
        The turns (radians) tried when the predicted angle matches badly (see :func:`match`).
    geometric : (2R+1, 2R+1) float
        ``w_beta`` times the squared offset of each cell from the window centre.
    plain : float
        The SSD of a match with confidence :data:`UPDATE_CONFIDENCE`.
    tie : float
        SSDs closer than this are equal: half a grey level per pixel and channel.
    alike : float
        Cells within this SSD of the match's match as well as it: :data:`ALIKE_LEVEL` per pixel
        and channel.
    visible : float
        The SSD of a match with confidence :data:`VISIBLE_CONFIDENCE`.
    """

    size: tuple[int, int]
    radius: int
    w_alpha: float
    w_beta: float
    parent: int
    hangs_from: int
    turns: tuple[float, ...]
    geometric: NDArray[np.float64]
    plain: float
    tie: float
    alike: float
    visible: float


def plan_joint(size: tuple[int, int], r: float, w_alpha: float, w_beta: float, parent: int,
               hangs_from: int, pace: float = 1.0) -> JointPlan:
    """A :class:`JointPlan` for a ``size`` template searched within radius ``r`` (pixels, >= 1),
    trying :data:`TURNS` times ``pace`` (the frames a step spans: 2 after a drawing held on twos)."""
    R = int(math.floor(r))
    offsets = np.arange(-R, R + 1, dtype=float) ** 2
    return JointPlan(size=size, radius=R, w_alpha=w_alpha / (size[0] * size[1]), w_beta=w_beta,
                     parent=parent, hangs_from=hangs_from, turns=tuple(pace * turn for turn in TURNS),
                     geometric=w_beta * (offsets[:, None] + offsets[None, :]),
                     plain=ssd_at(UPDATE_CONFIDENCE, size), tie=0.25 * 3 * size[0] * size[1],
                     alike=ALIKE_LEVEL**2 * 3 * size[0] * size[1], visible=ssd_at(VISIBLE_CONFIDENCE, size))


@dataclass(frozen=True)
class Context:
    """A joint's wider view: ``patch`` ``(s, s, 3)`` float32 at pyramid level ``level``, in the
    rectangle's own frame (:func:`sample`); cut by
    :func:`~toonmotion.capture.template_context.cut_context`."""

    patch: Patch
    level: int


@dataclass
class Templates:
    """A joint's anchor (cut where tracking started) and latest (last confident match).

    Both ``(th, tw, 3)`` float32, in the rectangle's own frame (see :func:`sample`); the same
    array while the latest has not been re-cut. ``coarse`` is the anchor at half resolution
    (``cv2.pyrDown``), for :func:`locate`. ``context``, the wider view cut with the anchor
    (:mod:`~toonmotion.capture.template_context`), if one was.
    """

    anchor: Patch
    latest: Patch
    coarse: Patch
    context: Context | None = None

    @classmethod
    def cut(cls, image: NDArray[np.uint8], centre: NDArray[np.float64], angle: float,
            size: tuple[int, int]) -> Templates:
        """Both templates cut from ``image`` at ``centre``, turned by ``angle`` radians."""
        patch = sample(image, centre, angle, size)
        return cls(anchor=patch, latest=patch, coarse=np.asarray(cv2.pyrDown(patch), dtype=np.float32))


@dataclass(frozen=True)
class BoneRule:
    """The kinematic term beside eq. 4.6 for a joint with a parent tracked this frame: a cell
    ``x`` costs ``weight (|x - parent| - length)^2`` more, so the joint keeps near the length its
    bone had; beyond ``longest`` from the parent nothing is taken.

    Attributes
    ----------
    parent : (2,) float
        The parent joint's centre this frame, (x, y) pixels.
    length : float
        The bone's length last frame, pixels.
    weight : float
        Per squared pixel, as the prediction's ``w_beta``.
    longest : float
        How far from the parent the joint may be, pixels (inf: no bound).
    """

    parent: NDArray[np.float64]
    length: float
    weight: float
    longest: float = math.inf


def distinct_size(image: NDArray[np.uint8], centre: NDArray[np.float64], size: tuple[int, int]
                  ) -> tuple[int, int]:
    """The template size to track a joint by: ``size``, grown by half again (at most
    :data:`MAX_GROWTH` times) while a patch of that size at ``centre`` looks like itself moved
    :data:`DISTINCT_SHIFT` pixels in some direction: the mean squared difference in the direction
    it changes least is under :data:`DISTINCT_RATIO` of that in the direction it changes most, or
    under :data:`DISTINCT_LEVEL` grey levels squared. A rectangle inside one flat colour, or on a
    straight outline, matches equally anywhere along it; a larger one takes in the outline's turns
    and ends that pin it down (the "good features to track" criterion, applied to the
    rectangle's size). A round outline changes few pixels when moved, but as many every way: it
    is distinct.

    >>> image = np.full((80, 80, 3), 200, np.uint8); image[:, 40:] = 40  # a straight edge
    >>> image[60:, :] = 120  # a corner 20 px below
    >>> on_edge, at_corner = np.array([40.0, 40.0]), np.array([40.0, 60.0])
    >>> distinct_size(image, on_edge, (12, 12)), distinct_size(image, at_corner, (12, 12))
    ((36, 36), (12, 12))
    """
    w0, h0 = size
    for growth in (1.0, 1.5, 2.25, MAX_GROWTH):
        grown = (max(1, int(round(w0 * growth))), max(1, int(round(h0 * growth))))
        if is_distinct(image, centre, grown):
            break
    return grown


def is_distinct(image: NDArray[np.uint8], centre: NDArray[np.float64], size: tuple[int, int]) -> bool:
    """Whether a ``size`` patch of ``image`` at ``centre`` looks unlike itself moved
    :data:`DISTINCT_SHIFT` pixels every way (:func:`distinct_size`).

    >>> image = np.full((80, 80, 3), 200, np.uint8); image[:, 40:] = 40  # a straight edge
    >>> image[60:, :] = 120  # a corner 20 px below
    >>> on_edge, at_corner = np.array([40.0, 40.0]), np.array([40.0, 60.0])
    >>> is_distinct(image, on_edge, (12, 12)), is_distinct(image, at_corner, (12, 12))
    (False, True)
    """
    patch = sample(image, centre, 0.0, size)
    change = [float(np.mean((sample(image, centre + DISTINCT_SHIFT * np.array([math.cos(a), math.sin(a)]),
                                    0.0, size) - patch) ** 2))
              for a in np.arange(8) * math.pi / 4]
    return min(change) >= max(DISTINCT_RATIO * max(change), DISTINCT_LEVEL**2)


def is_textured(patch: Patch) -> bool:
    """Whether a template ``(h, w, 3)`` has a texture of its own: at least
    :data:`TEXTURED_FRACTION` of its pixels change by more than :data:`TEXTURE_LEVEL` grey levels
    when it is moved :data:`DISTINCT_SHIFT` pixels (the mean of the fractions along x and y).

    >>> flat = np.full((20, 20, 3), 200, np.float32); flat[:, 9:12] = 20  # a fill and an outline
    >>> noise = np.random.default_rng(0).uniform(0, 255, (20, 20, 3)).astype(np.float32)
    >>> is_textured(flat), is_textured(noise)
    (False, True)
    """
    d = int(DISTINCT_SHIFT)
    along_x = np.abs(patch[:, d:] - patch[:, :-d]).max(axis=2) > TEXTURE_LEVEL
    along_y = np.abs(patch[d:] - patch[:-d]).max(axis=2) > TEXTURE_LEVEL
    return bool((along_x.mean() + along_y.mean()) / 2 >= TEXTURED_FRACTION)


@dataclass(frozen=True)
class _Cells:
    """A search's whole-pixel cells: the colour cost ``ssd`` (``(2R+1, 2R+1)``, in the window's
    frame), those the search could take (``allowed``: finite prior) and the match's ``cell``
    ``(i, j)``; None in a :class:`Match` where nothing could be taken."""

    ssd: NDArray[np.float32]
    allowed: NDArray[np.bool_]
    cell: tuple[int, int]
    joint: JointPlan

    @cached_property
    def parts(self) -> NDArray[np.int32]:
        """The cells matching as well as the match's (:data:`ALIKE_LEVEL`), labelled by connected
        part (8-connected)."""
        i, j = self.cell
        alike = (self.ssd <= self.ssd[i, j] + self.joint.alike) & self.allowed
        alike[i, j] = True
        return cv2.connectedComponents(alike.view(np.uint8), connectivity=8)[1]

    def alike(self) -> NDArray[np.float64]:
        """Offsets ``(n, 2)`` from the window's centre of the alike cells joined to the match's."""
        rows, cols = np.nonzero(self.parts == self.parts[self.cell])
        R = self.joint.radius
        return np.column_stack([cols - R, rows - R]).astype(float)

    def others(self) -> NDArray[np.float64]:
        """Up to :data:`OTHERS` local minima of the colour cost, :data:`OTHER_SPACING` cells apart,
        among the allowed cells not joined to the match's alike ones, at least
        :data:`VISIBLE_CONFIDENCE` confident, most confident first: ``(m, 3)`` offsets from the
        window's centre and confidence."""
        ssd, joint = self.ssd, self.joint
        R = joint.radius
        apart = (ssd <= joint.visible) & self.allowed
        apart &= self.parts != self.parts[self.cell]
        if not apart.any():
            return np.zeros((0, 3))
        side = 2 * OTHER_SPACING + 1
        rows, cols = np.nonzero(apart & (ssd <= cv2.erode(ssd, np.ones((side, side), np.uint8))))
        order = np.argsort(ssd[rows, cols], kind="stable")[:OTHERS]
        rows, cols = rows[order], cols[order]
        # confidence(), for every place at once
        mean = ssd[rows, cols].astype(float) / (3 * joint.size[0] * joint.size[1])
        return np.column_stack([cols - R, rows - R, np.exp(-mean / (2 * CONFIDENCE_SCALE**2))]).astype(float)


@dataclass(frozen=True, eq=False)
class Match:
    """What :func:`match` found.

    Attributes
    ----------
    xy : (2,) float
        The centre found, (x, y) pixels, sub-pixel.
    confidence : float in [0, 1]
    agree : bool
        Whether the latest template may be re-cut at the match: the anchor's match lies within
        :data:`DRIFT_TOLERANCE` of the latest's, or the anchor matches plainly
        (:data:`UPDATE_CONFIDENCE`), or there is no latest apart from the anchor.
    alike : (n, 2) float
        The whole-pixel places of the search, joined to the match's, that match as well as it
        (:data:`ALIKE_LEVEL`), (x, y) pixels: where the texture cannot tell the joint apart.
    others : (m, 3) float
        Up to :data:`OTHERS` other places of the search where the template is found, apart from
        the alike ones: local minima of the colour cost at least :data:`VISIBLE_CONFIDENCE`
        confident, whole-pixel ``(x, y)`` and the confidence there, most confident first.
    cells : _Cells or None
        The search's colour costs, from which ``alike`` and ``others`` are worked out when first
        asked for (most matches made are dropped for a better one); None where nothing could be
        taken (the bone cannot reach the window).
    centre : (2,) float
        The search window's centre, (x, y) pixels.
    angle : float
        The window's turn, radians.
    """

    xy: NDArray[np.float64]
    confidence: float
    agree: bool
    cells: _Cells | None
    centre: NDArray[np.float64]
    angle: float

    @cached_property
    def alike(self) -> NDArray[np.float64]:
        return self.centre[None] if self.cells is None else self._placed(self.cells.alike())

    @cached_property
    def others(self) -> NDArray[np.float64]:
        if self.cells is None:
            return np.zeros((0, 3))
        found = self.cells.others()
        return np.column_stack([self._placed(found[:, :2]), found[:, 2]])

    def _placed(self, offsets):
        """Offsets from the search window's centre, in its frame, as (x, y) places in the image."""
        c, s = math.cos(self.angle), math.sin(self.angle)
        return self.centre + offsets @ np.array([[c, s], [-s, c]])


def match(image: NDArray[np.uint8], templates: Templates, predicted: NDArray[np.float64], angle: float,
          joint: JointPlan, bone: BoneRule | None = None, *, turn: bool = True,
          figure: NDArray[np.uint8] | None = None, small: NDArray[np.uint8] | None = None,
          turn_ranks: list[float] | None = None) -> Match:
    """Match a joint's templates round ``predicted``, its rectangle turned by ``angle`` radians.

    A rectangle that turns and matches less confidently than :data:`TURN_CONFIDENCE` is also
    looked for turned by the plan's turns more (:data:`TURNS`, scaled by its pace): they are
    ranked at half resolution (:func:`locate`), and the :data:`FINE_TURNS` best are matched finely,
    best first, until one matches at :data:`TURN_CONFIDENCE`; the most confident match is kept.

    Parameters
    ----------
    image : (h, w, 3) uint8
        The frame, contiguous.
    templates : Templates
    predicted : (2,) float
        The predicted centre, (x, y) pixels.
    angle : float
        The rectangle's predicted rotation, radians.
    joint : JointPlan
    bone : BoneRule, optional
        The kinematic term for a joint whose parent is tracked this frame.
    turn : bool
        Try the plan's extra turns where the angle matches badly; False where the angle is
        known (a place :func:`search_round` found, turned with its bone).
    figure : (h, w) uint8, optional
        Non-zero where the figure is (:mod:`~toonmotion.capture.track_figure`): cells off it
        are not matched.
    small : (h/2, w/2, 3) uint8, optional
        ``image`` after ``cv2.pyrDown``, for the coarse turns; made here when not given.
    turn_ranks : list of float, optional
        The coarse confidences of the plan's turns round ``predicted``, if already worked out
        (:func:`rank_turns` with the same arguments and ``joint.turns``).

    Returns
    -------
    Match
    """
    found = _match_turned(image, templates, predicted, angle, joint, bone, figure)
    if joint.parent < 0 or not turn or found.confidence >= TURN_CONFIDENCE:
        return found
    # The turns are ranked at half resolution, and matched finely best first.
    coarse = turn_ranks
    if coarse is None:
        half: NDArray[np.uint8] = np.asarray(cv2.pyrDown(image) if small is None else small, np.uint8)
        coarse = rank_turns(half, templates, predicted, angle, joint, bone, figure, joint.turns)
    for k in np.argsort(coarse)[::-1][:FINE_TURNS]:
        if found.confidence >= TURN_CONFIDENCE:
            break
        other = _match_turned(image, templates, predicted, angle + joint.turns[k], joint, bone, figure)
        if other.confidence > found.confidence:
            found = other
    return found


def locate(small: NDArray[np.uint8], templates: Templates, centre: NDArray[np.float64], angle: float,
           joint: JointPlan, radius: float, bone: BoneRule | None = None,
           figure: NDArray[np.uint8] | None = None, turns: tuple[float, ...] = COARSE_TURNS
           ) -> tuple[NDArray[np.float64], float, float]:
    """Look for a hidden joint at half resolution, up to ``radius`` pixels (full resolution) from
    ``centre``: the anchor's coarse template is matched in ``small`` (the frame after
    ``cv2.pyrDown``) at the rectangle's angle turned by each of ``turns``, by eq. 4.6's mixed
    cost with ``joint``'s colour weight, ``w_beta = 1 / radius^2`` and the kinematic term
    (``bone``), among the plain cells if there are any (as :func:`match`). Only where to look
    again: the place is to be refined by :func:`match`.

    Returns
    -------
    xy : (2,) float
        The best place, full-resolution (x, y) pixels, to about a pixel.
    confidence : float
        The coarse match's confidence.
    angle : float
        The rectangle's angle there, radians.
    """
    places, confidences, angles = _coarse_turns(small, templates, centre, angle, joint, radius, bone, figure,
                                                turns)
    best = int(np.argmax(confidences))
    if not confidences[best] > 0.0:
        return np.asarray(centre, dtype=float), 0.0, angle
    return places[best], confidences[best], angles[best]


def _coarse_turns(small: NDArray[np.uint8], templates: Templates, centre: NDArray[np.float64], angle: float,
                  joint: JointPlan, radius: float, bone: BoneRule | None, figure: NDArray[np.uint8] | None,
                  turns: tuple[float, ...]) -> tuple[list[NDArray[np.float64]], list[float], list[float]]:
    """:func:`locate` at each of ``turns`` apart: per turn, the best place (full-resolution (x, y)),
    its coarse confidence (0 where no cell could be taken) and the rectangle's angle, as lists.
    The turns' windows are costed together (the ranking of a joint's turns runs for a third of
    the matches on a flat cartoon)."""
    template = templates.coarse
    th, tw = template.shape[:2]
    R = max(1, int(math.ceil(radius / 2)))
    w_alpha = joint.w_alpha * joint.size[0] * joint.size[1] / (tw * th)
    plain_ssd = ssd_at(UPDATE_CONFIDENCE, (tw, th))
    centre = np.asarray(centre, dtype=float)
    # Pixel centres: full-resolution x is half-resolution 2 x + 0.5.
    middle = (centre - 0.5) / 2
    angles = [angle + turn for turn in turns]
    size = (tw + 2 * R, th + 2 * R)
    windows = [sample(small, middle, a, size) for a in angles]
    ssd = np.stack([cv2.matchTemplate(window, template, cv2.TM_SQDIFF) for window in windows])
    cost = w_alpha * ssd + coarse_geometric(R, radius)
    if bone is not None:
        cost += _bone_cost(centre, angles, R, bone, step=2.0)
    if figure is not None:
        cost[~np.stack([figure_cells(figure, centre, a, R, step=2.0) for a in angles])] = np.inf
    plain = (ssd <= plain_ssd) & np.isfinite(cost)  # as in the fine search: plain cells first
    cost[plain.any(axis=(1, 2))[:, None, None] & ~plain] = np.inf
    cells = np.argmin(cost.reshape(len(angles), -1), axis=1)
    places, confidences = [], []
    for a, turn_cost, turn_ssd, cell in zip(angles, cost, ssd, cells.tolist(), strict=True):
        i, j = divmod(cell, 2 * R + 1)
        if not np.isfinite(turn_cost[i, j]):
            places.append(centre)
            confidences.append(0.0)
            continue
        c, s = math.cos(a), math.sin(a)
        dx, dy = 2.0 * (j - R), 2.0 * (i - R)
        places.append(centre + [c * dx - s * dy, s * dx + c * dy])
        confidences.append(confidence(float(turn_ssd[i, j]), (tw, th)))
    return places, confidences, angles


def rank_turns(small: NDArray[np.uint8], templates: Templates, centre: NDArray[np.float64], angle: float,
               joint: JointPlan, bone: BoneRule | None, figure: NDArray[np.uint8] | None,
               turns: tuple[float, ...]) -> list[float]:
    """The coarse confidence of the rectangle turned by each of ``turns`` more, in the joint's own
    window round ``centre`` (:func:`_coarse_turns`): how :func:`match` ranks its extra turns."""
    return _coarse_turns(small, templates, centre, angle, joint, max(joint.radius, 1), bone, figure, turns)[1]


@functools.lru_cache(maxsize=64)
def coarse_geometric(R: int, radius: float) -> NDArray[np.float64]:
    """The coarse search's geometric term over ``(2R+1, 2R+1)`` cells 2 px apart round a window's
    centre: the squared distance from it (full-resolution pixels) times ``w_beta = 1 / radius^2``.

    >>> coarse_geometric(1, 2.0).tolist()
    [[2.0, 1.0, 2.0], [1.0, 0.0, 1.0], [2.0, 1.0, 2.0]]
    """
    offsets = (2.0 * np.arange(-R, R + 1)) ** 2
    return (offsets[:, None] + offsets[None, :]) / radius**2


def search_round(small: NDArray[np.uint8], templates: Templates, joint: JointPlan, bone: BoneRule,
                 start: float, span: float, turn: float, count: int = 2,
                 figure: NDArray[np.uint8] | None = None, by_look: bool = False
                 ) -> list[tuple[NDArray[np.float64], float, float]]:
    """Look for a hidden joint round its parent, found this frame: at every place within the
    bone's reach (``bone.longest``, at least half the rectangle from the parent) whose direction
    from the parent lies within ``span`` radians of ``start``, a quarter rectangle apart, with the
    rectangle turned as its bone would be there (``turn`` plus the direction's change from
    ``start``). The anchor's coarse template is compared with each place in ``small`` (the frame
    after ``cv2.pyrDown``) by eq. 4.6's mixed cost with the kinematic term; only where to look
    again, to be refined by :func:`match`. With ``figure`` (full resolution), places off the
    figure are left out. With ``by_look`` (a joint with a texture of its own,
    :func:`is_textured`), the places are picked by their look alone and ordered by that cost.

    Returns
    -------
    list of (xy, confidence, angle)
        The ``count`` best places at least a rectangle apart (with ``by_look``, best-looking), the
        least mixed cost first (none if no place lies within reach): full-resolution (x, y)
        pixels, the coarse match's confidence, and the rectangle's angle there (radians).
    """
    template = templates.coarse
    th, tw = template.shape[:2]
    side = max(joint.size)
    step = side / 4
    rings = np.arange(max(side / 2, step), bone.longest + step / 2, step)
    places, directions = [], []
    for rho in rings:
        around = max(1, int(math.ceil(2 * span * rho / step)))
        phi = start + np.linspace(-span, span, around) if span < math.pi else \
            start + np.arange(around) * (2 * math.pi / around)
        places.append(bone.parent + rho * np.column_stack([np.cos(phi), np.sin(phi)]))
        directions.append(phi)
    if not places:
        return []
    xy, phi = np.concatenate(places), np.concatenate(directions)
    if figure is not None:
        keep = on_figure(figure, xy)
        xy, phi = xy[keep], phi[keep]
        if not len(xy):
            return []
    angles = turn + (phi - start)
    patches = _patches(small, (xy - 0.5) / 2, angles, (tw, th))
    d = patches - template[None]
    ssd = np.einsum("nijc,nijc->n", d, d)
    w_alpha = joint.w_alpha * joint.size[0] * joint.size[1] / (tw * th)
    rho = np.hypot(*(xy - bone.parent).T)
    cost = w_alpha * ssd + bone.weight * (rho - bone.length) ** 2
    # The best place of each neighbourhood, a rectangle apart, then the least mixed cost first. A
    # coarse grid a quarter rectangle wide misses the joint by up to an eighth of one, which costs
    # a fine texture most of its likeness, so likeness here only picks and ranks places and
    # :func:`match` decides. Picked by the mixed cost, a neighbourhood's place is the one nearest
    # the bone's last length: a textured foot hidden while its shin came out of foreshortening was
    # left 15-30 px from every place looked at (the walk on twos), so a textured joint's places
    # are picked by look. A flat-coloured joint's look-alikes are all over a cartoon, and picked
    # by look it was found again on them (a drawn hand 135 px off).
    unpicked = (ssd if by_look else cost).astype(float)
    picked: list[int] = []
    while len(picked) < count and np.isfinite(unpicked).any():
        best = int(np.argmin(unpicked))
        picked.append(best)
        unpicked[np.hypot(*(xy - xy[best]).T) < side] = np.inf
    picked.sort(key=lambda i: cost[i])
    return [(xy[i], confidence(float(ssd[i]), (tw, th)), float(angles[i])) for i in picked]


def _patches(image, centres, angles, size):
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


def _match_turned(image, templates, predicted, angle, joint, bone, figure=None):
    """:func:`match` at one angle: the anchor's match where it is trusted, else the latest's.

    An anchor matching plainly (:data:`UPDATE_CONFIDENCE`) is taken without matching the latest:
    it does not drift, and the joint is plainly there (the latest may be re-cut).
    """
    R, (tw, th) = joint.radius, joint.size
    prior = joint.geometric if bone is None else joint.geometric + _bone_cost(predicted, angle, R, bone)
    if figure is not None:
        prior = np.where(figure_cells(figure, predicted, angle, R), prior, np.inf)
    allowed = np.isfinite(prior)
    if not allowed.any():  # the bone cannot reach the window, or it is off the figure: nothing is found
        return Match(predicted.copy(), 0.0, True, None, predicted, angle)
    window = sample(image, predicted, angle, (tw + 2 * R, th + 2 * R))
    anchor = _best(window, templates.anchor, joint, prior, allowed, exact=True)
    (offset, confidence, cells), agree = anchor, True
    if anchor[1] < UPDATE_CONFIDENCE and templates.anchor is not templates.latest:
        latest = _best(window, templates.latest, joint, prior, allowed)
        (offset, confidence, cells) = latest
        agree = bool(np.hypot(*(anchor[0] - latest[0])) <= DRIFT_TOLERANCE)
        if agree and anchor[1] >= VISIBLE_CONFIDENCE:
            # Both find the joint here: the anchor's place (it does not drift), and the latest's
            # confidence when higher (the anchor is older, the joint's looks may have changed:
            # a limb bends at it). The latest may then be re-cut: an occluder sliding over the
            # joint would have to hold the anchor, which never learns, at the same place too.
            # (Re-cutting only where the anchor matched plainly lost every joint whose looks
            # change as its limb bends, on the flat cartoons above all.)
            offset, confidence, cells = anchor[0], max(anchor[1], latest[1]), anchor[2]
        elif anchor[1] >= latest[1]:
            offset, confidence, cells = anchor
    # The offset, in the window's frame, turned into the image's (a per-joint hot path: by hand).
    c, s = math.cos(angle), math.sin(angle)
    xy = predicted + [c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]]
    return Match(xy, confidence, agree, cells, predicted, angle)


def _bone_cost(predicted, angle, R, bone, step=1.0):
    """The kinematic term (:class:`BoneRule`) of every cell of a window round ``predicted``
    turned by ``angle``, ``(2R+1, 2R+1)``, cells ``step`` pixels apart; inf beyond the bone's
    longest reach. With a list of angles, one window per angle: ``(n, 2R+1, 2R+1)``."""
    if isinstance(angle, list):
        c = np.array([math.cos(a) for a in angle])[:, None, None]
        s = np.array([math.sin(a) for a in angle])[:, None, None]
    else:
        c, s = math.cos(angle), math.sin(angle)
    d = step * np.arange(-R, R + 1, dtype=float)
    # Cell (i, j) lies at predicted + rotation(angle) (j - R, i - R) in the image.
    x = predicted[0] - bone.parent[0] + c * d[None, :] - s * d[:, None]
    y = predicted[1] - bone.parent[1] + s * d[None, :] + c * d[:, None]
    reach = np.hypot(x, y)
    cost = bone.weight * (reach - bone.length) ** 2
    cost[reach > bone.longest] = np.inf
    return cost


def _best(window, template, joint, prior, allowed, exact=False):
    """Best match of ``template`` in ``window``: sub-pixel ``(dx, dy)`` from the centre, confidence.

    The mixed cost (colour plus ``prior``, the geometric and kinematic terms per cell; ``allowed``
    where it is finite, some cell) picks the cell among the plain ones, if any; with ``exact``
    (the anchor), among the cells where the template is found again as cut, if they are few
    (:data:`EXACT_CELLS`). The colour cost alone then places the match: a descent to its local
    minimum and a parabola through it in x and in y.
    """
    R, (tw, th) = joint.radius, joint.size
    ssd = cv2.matchTemplate(window, template, cv2.TM_SQDIFF)
    cost = joint.w_alpha * ssd + prior
    plain = (ssd <= joint.plain) & allowed  # cells where the texture is plainly there
    if plain.any():
        if exact:
            same = plain & (ssd <= joint.alike)
            if 0 < np.count_nonzero(same) <= EXACT_CELLS:
                plain = same
        cost[~plain] = np.inf
    i, j = np.unravel_index(int(np.argmin(cost)), ssd.shape)
    i, j = _descend(ssd, i, j, joint.tie)
    # The map is float32 and its sums of squares round; the chosen cell's is recomputed exactly.
    d = (window[i:i + th, j:j + tw] - template).astype(np.float64).ravel()
    exact = float(d @ d)
    dx = _vertex(ssd[i, j - 1] if j > 0 else None, exact, ssd[i, j + 1] if j < 2 * R else None, joint.tie)
    dy = _vertex(ssd[i - 1, j] if i > 0 else None, exact, ssd[i + 1, j] if i < 2 * R else None, joint.tie)
    cells = _Cells(ssd, allowed, (i, j), joint)
    return np.array([j - R + dx, i - R + dy]), confidence(exact, joint.size), cells


def _descend(cost, i, j, tie):
    """From cell ``(i, j)``, step to the lowest of the 8 neighbours while ``cost`` drops by > ``tie``."""
    # Plain Python on the 3 x 3 block: numpy's overhead on nine numbers was most of the time.
    # The first lowest in row order is taken, as np.argmin would.
    while True:
        i0, j0 = max(i - 1, 0), max(j - 1, 0)
        block = cost[i0:i + 2, j0:j + 2].tolist()
        low, a, b = min((value, a, b) for a, row in enumerate(block) for b, value in enumerate(row))
        if not low < cost[i, j] - tie:
            return i, j
        i, j = i0 + a, j0 + b


def confidence(ssd: float, size: tuple[int, int]) -> float:
    """Confidence of a match whose sum of squared RGB differences over a ``size`` rectangle is ``ssd``.

    ``exp(-d^2 / (2 CONFIDENCE_SCALE^2))``, ``d`` the root mean square difference per channel.

    >>> round(confidence(20.0**2 * 3 * 4, (2, 2)), 2)  # 20 grey levels off in every channel
    0.8
    """
    return math.exp(-ssd / (size[0] * size[1] * 3) / (2 * CONFIDENCE_SCALE**2))


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


def ssd_at(confidence: float, size: tuple[int, int]) -> float:
    """The sum of squared differences that has ``confidence``: inverse of :func:`confidence`."""
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
