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

import math
from dataclasses import dataclass
from functools import cached_property

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.coarse_search import rank_turns
from toonmotion.capture.joint_plan import (
    BoneRule,
    JointPlan,
    Templates,
    bone_cost,
)
from toonmotion.capture.patches import (
    confidence,
    sample,
)
from toonmotion.capture.track_figure import figure_cells


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
        """The cells matching as well as the match's (``tuning.alike_level`` of the plan's
        :class:`~toonmotion.capture.match_tuning.MatchTuning`), labelled by connected part
        (8-connected)."""
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
        """Up to ``tuning.others`` local minima of the colour cost, the least of the cells
        ``tuning.other_spacing`` round them, among the allowed cells not joined to the match's
        alike ones, at least ``tuning.visible_confidence`` confident, most confident first:
        ``(m, 3)`` offsets from the window's centre and confidence (the plan's tuning)."""
        ssd, joint = self.ssd, self.joint
        R, tuning = joint.radius, joint.tuning
        apart = (ssd <= joint.visible) & self.allowed
        apart &= self.parts != self.parts[self.cell]
        if not apart.any():
            return np.zeros((0, 3))
        side = 2 * tuning.other_spacing + 1
        rows, cols = np.nonzero(apart & (ssd <= cv2.erode(ssd, np.ones((side, side), np.uint8))))
        order = np.argsort(ssd[rows, cols], kind="stable")[:tuning.others]
        rows, cols = rows[order], cols[order]
        # confidence(), for every place at once
        mean = ssd[rows, cols].astype(float) / (3 * joint.size[0] * joint.size[1])
        sure = np.exp(-mean / (2 * tuning.confidence_scale**2))
        return np.column_stack([cols - R, rows - R, sure]).astype(float)


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
        ``drift_tolerance`` of the latest's, or the anchor matches plainly
        (``update_confidence``), or there is no latest apart from the anchor (the plan's
        :class:`~toonmotion.capture.match_tuning.MatchTuning`, as below).
    alike : (n, 2) float
        The whole-pixel places of the search, joined to the match's, that match as well as it
        (``alike_level``), (x, y) pixels: where the texture cannot tell the joint apart.
    others : (m, 3) float
        Up to ``others`` other places of the search where the template is found, apart from
        the alike ones: local minima of the colour cost at least ``visible_confidence``
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

    A rectangle that turns and matches less confidently than ``turn_confidence`` (of the plan's
    :class:`~toonmotion.capture.match_tuning.MatchTuning`) is also looked for turned by the plan's
    turns more (its ``turns``, scaled by its pace): they are ranked at half resolution
    (:func:`locate`), and the ``fine_turns`` best are matched finely, best first, until one matches
    at ``turn_confidence``; the most confident match is kept.

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
    enough = joint.tuning.turn_confidence
    if joint.parent < 0 or not turn or found.confidence >= enough:
        return found
    # The turns are ranked at half resolution, and matched finely best first.
    coarse = turn_ranks
    if coarse is None:
        half: NDArray[np.uint8] = np.asarray(cv2.pyrDown(image) if small is None else small, np.uint8)
        coarse = rank_turns(half, templates, predicted, angle, joint, bone, figure, joint.turns)
    for k in np.argsort(coarse)[::-1][:joint.tuning.fine_turns]:
        if found.confidence >= enough:
            break
        other = _match_turned(image, templates, predicted, angle + joint.turns[k], joint, bone, figure)
        if other.confidence > found.confidence:
            found = other
    return found


def _match_turned(image, templates, predicted, angle, joint, bone, figure=None):
    """:func:`match` at one angle: the anchor's match where it is trusted, else the latest's.

    An anchor matching plainly (the plan's ``tuning.update_confidence``) is taken without matching
    the latest: it does not drift, and the joint is plainly there (the latest may be re-cut).
    """
    R, (tw, th), tuning = joint.radius, joint.size, joint.tuning
    prior = joint.geometric if bone is None else joint.geometric + bone_cost(predicted, angle, R, bone)
    if figure is not None:
        prior = np.where(figure_cells(figure, predicted, angle, R), prior, np.inf)
    allowed = np.isfinite(prior)
    if not allowed.any():  # the bone cannot reach the window, or it is off the figure: nothing is found
        return Match(predicted.copy(), 0.0, True, None, predicted, angle)
    window = sample(image, predicted, angle, (tw + 2 * R, th + 2 * R))
    anchor = _best(window, templates.anchor, joint, prior, allowed, exact=True)
    (offset, confidence, cells), agree = anchor, True
    if anchor[1] < tuning.update_confidence and templates.anchor is not templates.latest:
        latest = _best(window, templates.latest, joint, prior, allowed)
        (offset, confidence, cells) = latest
        agree = bool(np.hypot(*(anchor[0] - latest[0])) <= tuning.drift_tolerance)
        if agree and anchor[1] >= tuning.visible_confidence:
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


def _best(window, template, joint, prior, allowed, exact=False):
    """Best match of ``template`` in ``window``: sub-pixel ``(dx, dy)`` from the centre, confidence.

    The mixed cost (colour plus ``prior``, the geometric and kinematic terms per cell; ``allowed``
    where it is finite, some cell) picks the cell among the plain ones, if any; with ``exact``
    (the anchor), among the cells where the template is found again as cut (every cell within the
    plan's ``tuning.alike_level``, compression noise), if they are few (``tuning.exact_cells``;
    a place between cells takes up to 2 x 2): there it is, however far from the prediction. Among
    plain cells eq. 4.6's colour weight leaves the choice to the distance from the prediction,
    which holds a joint that drifted along a flat limb where it drifted to, even once its limb is
    back as it was drawn; a flat anchor is found as cut along a stretch of fill, and there the
    prediction still chooses. The colour cost alone then places the match: a descent to its local
    minimum and a parabola through it in x and in y.
    """
    R, (tw, th) = joint.radius, joint.size
    ssd = cv2.matchTemplate(window, template, cv2.TM_SQDIFF)
    cost = joint.w_alpha * ssd + prior
    plain = (ssd <= joint.plain) & allowed  # cells where the texture is plainly there
    if plain.any():
        if exact:
            same = plain & (ssd <= joint.alike)
            if 0 < np.count_nonzero(same) <= joint.tuning.exact_cells:
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
    return np.array([j - R + dx, i - R + dy]), confidence(exact, joint.size, joint.tuning), cells


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


