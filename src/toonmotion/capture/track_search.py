"""One frame of the joint tracker: where each joint is looked for, and where it is put when it is
not found (thesis 4.4, with re-acquisition).

A frame is searched in four passes over the skeleton:

1. **Down** (parents before children). A joint seen last drawing is matched round its
   prediction (eq. 4.4-4.6). A joint with a parent found this frame is held near its bone's last
   length, a kinematic term beside eq. 4.6 (:class:`~toonmotion.capture.joint_plan.BoneRule`);
   one with a texture of its own weighs its colour ``tuning.textured_colour_weight`` times as much.
   A *hidden* joint is looked for afresh: round its parent, if that was found, at every place its
   bone can reach in directions widening from where it was last (``tuning.span_step`` a drawing),
   its rectangle turned with its bone there (:func:`~toonmotion.capture.coarse_search.search_round`);
   else near where its parent carries it (a parent hidden too is first put where its own parent
   carries it), in a window that widens for every drawing it stays hidden
   (:func:`~toonmotion.capture.coarse_search.locate`; with no bone to give its angle, at turns
   all round, :func:`~toonmotion.capture.template_spin.locate_all_round`); after a held drawing,
   as every window, as many times as wide as the frames it was held. A joint with a texture of its own not
   found round its prediction is looked for at once in the same way. The best places are then matched
   finely, and the joint is taken as found again only by a match at least
   ``tuning.reacquire_confidence`` confident (a joint with a texture of its own, within its window
   of where it is carried, as plainly as a joint that shows), within ``tuning.reach_slack`` times the
   longest its bone has been seen. A joint with a texture of its own
   (:func:`~toonmotion.capture.patches.is_textured`) is looked for where it looks alike:
   its places are picked by look, it is not held to its bone's last length, a weak match is
   taken wherever it lies, and one at least ``tuning.weak_confidence`` confident even beside a joint
   that shows (not on it); a flat-coloured one, whose look-alikes are all over a cartoon, is held
   to where its bone and its guessed place put it.
2. **Up** (children before parents). A joint still not found is looked for where the joints
   hanging from it that were found put it (each moved as its child moved), if its coarse match
   there is at least ``tuning.up_coarse_confidence``.
3. **Settle** (parents first). A joint found on a flat fill, where places along the fill match as
   well as its match (``tuning.ambiguous_spread``), is put among them where its parent and its
   children found plainly carry it.
4. **Place the rest** (parents first): at the mean of where its parent carries it and where its
   children found put it (a root: the joints found below it); a root with neither coasts.

Arrays are the tracker's: ``P`` ``(T, k, 2)`` joint centres, ``C`` ``(T, k)`` confidence,
``angles`` ``(T, k)`` the rectangles' turns; skeletons list parents before children.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.coarse_search import locate, rank_turns, search_round
from toonmotion.capture.joint_plan import (
    BoneRule,
    Plans,
    Templates,
)
from toonmotion.capture.patches import is_textured, likeness, sample
from toonmotion.capture.search_tuning import SearchTuning
from toonmotion.capture.template_context import Pyramid, place_by_context
from toonmotion.capture.template_match import Match, match
from toonmotion.capture.template_spin import TurnedDiscs, locate_all_round
from toonmotion.capture.track_figure import FigureMasks, onto_figure
from toonmotion.capture.track_hidden import carried_by_parent, lengthen, moves_below, place_hidden
from toonmotion.capture.track_prediction import bone_turn, hidden_at, turns


class FrameSearch:
    """The joints' search, frame after frame of one run (module docstring).

    Parameters
    ----------
    plans : Plans
    templates : list of Templates
        One per joint; their latest templates are re-cut as joints are found.
    P, C, angles : arrays
        The run's positions, confidence and angles, written frame by frame.
    lost : (k,) int
        Drawings each joint has been hidden for (0: found last drawing); updated.
    longest : (k,) float
        The longest each joint's bone has been seen, pixels (0 for roots); updated.
    figure : FigureMasks, optional
        Where the figure is in each frame: joints marked in ``on_figure`` are matched only on it,
        and put back on it when not found (:mod:`~toonmotion.capture.track_figure`).
    on_figure : (k,) bool, optional
        The joints held to the figure (those on it where tracking started); default all.
    tuning : SearchTuning, optional
        The search's tuning (:class:`~toonmotion.capture.search_tuning.SearchTuning`); default
        its defaults. The matching's (:class:`~toonmotion.capture.match_tuning.MatchTuning`) is
        the one ``plans`` carry.
    """

    def __init__(self, plans: Plans, templates: list[Templates], P: NDArray[np.float64],
                 C: NDArray[np.float64], angles: NDArray[np.float64], lost: NDArray[np.int_],
                 longest: NDArray[np.float64], figure: FigureMasks | None = None,
                 on_figure: NDArray[np.bool_] | None = None, tuning: SearchTuning | None = None) -> None:
        self.plans, self.templates = plans, templates
        self.tuning = SearchTuning() if tuning is None else tuning
        self.match = plans.tuning
        # The confidence a joint taken to be hidden is saved with, at most: just under the visible bar.
        self._hidden = float(np.nextafter(self.match.visible_confidence, 0))
        self.P, self.C, self.angles = P, C, angles
        self.lost: NDArray[np.int_] = np.array(lost, dtype=int)
        self.longest: NDArray[np.float64] = np.array(longest, dtype=float)
        self.figure = figure
        self.held_to_figure = np.ones(len(plans), bool) if on_figure is None else np.asarray(on_figure, bool)
        self._near: NDArray[np.uint8] | None = None
        self._textured = [is_textured(t.anchor, self.match) for t in templates]
        self._turned: list[TurnedDiscs | None] = [None] * len(plans)
        self._pyramid: Pyramid | None = None
        self._pace = 1.0
        # Per joint, this frame: the places alike to its match (template_match.Match), and the match
        # taken (None: not found), whose other places the whole-sequence pass may ask for.
        self._alike: list[NDArray[np.float64]] = []
        self.taken: list[Match | None] = []

    def frame(self, image: NDArray[np.uint8], t: int, predicted: NDArray[np.float64],
              coast: NDArray[np.float64], *, pace: float = 1.0) -> None:
        """Track frame ``t`` (``image``; frame ``t - 1`` is tracked) from the joints' predicted
        centres and where hidden roots coast to (``(k, 2)`` each); every window round a prediction
        or a guess is ``pace`` times as wide (the frames since the last drawing), not the up pass's
        round where the joints below put a joint (widened too, the rendered clips on twos summed 4 px
        worse).
        Writes ``P[t]``, ``C[t]``, ``angles[t]``."""
        P, plans, tune = self.P, self.plans, self.tuning
        k = len(plans)
        self._near = None if self.figure is None else self.figure.near(t)
        self._pyramid = Pyramid(image)
        self._pace = pace
        angle = self.angles[t - 1] + turns(P[t - 1], predicted, plans.parents, True)
        seen, agree = np.zeros(k, dtype=bool), np.zeros(k, dtype=bool)
        self._alike = [np.zeros((0, 2))] * k
        self.taken = [None] * k
        self.C[t] = 0.0
        for m in range(k):  # down
            if not self.lost[m]:
                self._try(image, t, m, self._plan(m, pace), predicted[m], angle[m],
                          self.match.visible_confidence, seen, agree)
                if seen[m]:
                    continue
            carried = hidden_at(P, t, m, coast[m], plans.hangs_from)
            if self.lost[m] or self._textured[m]:
                # A textured joint not found round its prediction is looked for at once as if hidden.
                hidden = max(int(self.lost[m]), 1)
                for centre, turned in self._places_to_look(self._small(), t, m, carried, angle[m], seen,
                                                           hidden):
                    if self._try(image, t, m, self._plan(m, pace), centre, turned, tune.reacquire_confidence,
                                 seen, agree, bounded=True, turn=False, expected=carried):
                        break
            if not seen[m]:
                # Where its parent carries it for now (placed for good below): a hidden joint
                # hanging from it is looked for near there.
                P[t, m] = carried
        moves = moves_below(P, t, seen, plans.hangs_from)
        for m in range(k - 1, -1, -1):  # up
            if not seen[m] and np.isfinite(moves[m]).all():
                centre = P[t - 1, m] + moves[m]
                ranks = self._coarse_ranks(self._small(), t, m, centre, angle[m], seen)
                if max(ranks) >= tune.up_coarse_confidence:
                    self._try(image, t, m, self._plan(m), centre, angle[m], tune.reacquire_confidence, seen,
                              agree, bounded=True, turn_ranks=ranks[1:])
        self._settle(t, coast, seen)
        # A joint not found goes no farther in one frame than its search could have reached.
        reach = np.array([plans(m, pace).radius * min(1.0 + tune.widen_step * self.lost[m], tune.max_widen)
                          for m in range(k)])
        place_hidden(P, t, coast, seen, plans.hangs_from, reach)
        # A joint leaving the picture stays at its edge.
        np.clip(P[t], 0.0, [image.shape[1] - 1, image.shape[0] - 1], out=P[t])
        if self._near is not None and self.figure is not None:  # a hidden joint is behind the figure: on it
            pull = self.figure.tuning.pull_reach
            for j in np.flatnonzero(~seen & self.held_to_figure):
                P[t, j] = onto_figure(self._near, P[t, j], reach[j], pull=pull)
        self.lost = np.where(seen, 0, self.lost + 1)
        self.angles[t] = self.angles[t - 1] + turns(P[t - 1], P[t], plans.parents, True)
        for j in np.flatnonzero(seen & agree):
            self._learn(image, t, int(j))
        lengthen(self.longest, P[t], self.C[t], plans.hangs_from, visible=self.match.visible_confidence)

    def _settle(self, t, coast, seen):
        """Put each ambiguous joint found at ``t`` (its alike places reach farther than
        ``tuning.ambiguous_spread`` of its rectangle from its match), parents first, among those places
        where its parent and its children found unambiguously carry it, as a hidden joint is placed
        (:func:`place_hidden`): at that place itself if it lies within a pixel of one, else at the
        nearest. Where its wider view (:mod:`~toonmotion.capture.template_context`) matches plainly
        enough, that places the joint instead (neighbours inside the same fill drift as it does). A
        root with neither keeps its match."""
        P, hangs_from = self.P, self.plans.hangs_from
        ambiguous = np.zeros(len(seen), bool)
        for m in np.flatnonzero(seen):
            spread = np.hypot(*(self._alike[m] - P[t, m]).T).max()
            ambiguous[m] = spread > self.tuning.ambiguous_spread * max(self.plans(m).size)
        firm_moves = moves_below(P, t, seen & ~ambiguous, hangs_from, direct=True)
        for m in np.flatnonzero(ambiguous):
            guess = self._placed_by_context(t, m)
            if guess is None:
                guess = carried_by_parent(P, t, m, coast, hangs_from, firm_moves[m])
            if guess is None:
                continue
            distance = np.hypot(*(self._alike[m] - guess).T)
            nearest = int(np.argmin(distance))
            P[t, m] = guess if distance[nearest] <= 1.0 else self._alike[m][nearest]

    def _placed_by_context(self, t, m):
        """Where ambiguous joint ``m``'s context places it at ``t``, looked for within twice its
        window of its match (the match may lie anywhere along the fill in its window, the joint as
        far beyond), if it matches at least ``match.context_confidence`` within
        ``tuning.ambiguous_spread`` of the rectangle from a place alike to the match; else None (also
        with no context)."""
        context = self.templates[m].context
        if context is None:
            return None
        assert self._pyramid is not None  # set by frame()
        radius, angle = 2 * self.plans(m, self._pace).radius, float(self.angles[t - 1, m])
        xy, sure = place_by_context(self._pyramid, context, self.P[t, m], angle, radius, self.match)
        # It chooses among the places alike to the joint's match: where it points elsewhere
        # (an elbow's context, the arm raised, found on the head), the two disagree.
        spread = self.tuning.ambiguous_spread * max(self.plans(m).size)
        near = float(np.hypot(*(self._alike[m] - xy).T).min()) <= spread
        return xy if sure >= self.match.context_confidence and near else None

    def _places_to_look(self, small, t, m, carried, angle, seen, hidden):
        """Where to look for joint ``m``, hidden for ``hidden`` drawings, at full resolution, with
        its rectangle's angle there: round its parent if that was found, else near ``carried``,
        where its parent carries it or it coasts, in a window as wide as this frame's pace makes
        it (module docstring). Places whose coarse match is hopeless are left out."""
        P, plans = self.P, self.plans
        joint = self._plan(m, self._pace)
        bone = self._bone_rule(t, m, seen, bounded=True)
        if bone is not None and math.isfinite(bone.longest):
            g = plans.hangs_from[m]
            start = math.atan2(*(P[t - 1, m] - P[t - 1, g])[::-1])
            span = min(math.pi, self.tuning.span_step * hidden)
            turned = float(self.angles[t - 1, m])
            found = search_round(small, self.templates[m], joint, bone, start, span, turned,
                                 count=self.tuning.places, figure=self._figure(m), by_look=self._textured[m])
            return [(xy, turned) for xy, coarse, turned in found if coarse >= self.tuning.coarse_confidence]
        radius = joint.radius * min(1.0 + self.tuning.widen_step * hidden, self.tuning.max_widen)
        if bone is None and plans.parents[m] >= 0:
            # Its parent not found, its bone gives no angle to go by: it is looked for at turns all round.
            xy, coarse, turned = locate_all_round(small, self._discs(m), carried, joint, radius,
                                                  figure=self._figure(m))
        else:
            xy, coarse, turned = locate(small, self.templates[m], carried, angle, joint, radius, bone,
                                        self._figure(m))
        return [(xy, turned)] if coarse >= self.tuning.coarse_confidence else []

    def _discs(self, m):
        """Joint ``m``'s anchor's coarse disc turned all round (made when first asked for)."""
        coarse = self.templates[m].coarse
        if self._turned[m] is None or self._turned[m].coarse is not coarse:
            self._turned[m] = TurnedDiscs(coarse, self.match.spin_turns)
        return self._turned[m]

    def _coarse_ranks(self, small, t, m, centre, angle, seen):
        """Hidden joint ``m``'s coarse confidences round ``centre`` at ``angle`` and turned by each of
        its plan's turns, as :func:`~toonmotion.capture.template_match.match` ranks them."""
        joint = self._plan(m)
        bone = self._bone_rule(t, m, seen, bounded=True)
        return rank_turns(small, self.templates[m], centre, angle, joint, bone, self._figure(m),
                          (0.0, *joint.turns))

    def _try(self, image, t, m, joint, centre, angle, needed, seen, agree, *, bounded=False, turn=True,
             expected=None, turn_ranks=None):
        """Match joint ``m`` round ``centre``; if at least ``needed`` confident (and, when weak, near
        where it is ``expected``: default ``centre``; a hidden joint with a textured template, given
        ``expected``, anywhere), write it into ``P[t]``, ``C[t]``, ``seen``
        and ``agree`` (its latest template may be re-cut there) and return True, else keep its best
        confidence so far (below ``match.visible_confidence``)."""
        # A hidden joint with a texture of its own is looked for again where it looks alike: not
        # held to its bone's last length (the bone may have come out of foreshortening meanwhile),
        # and a weak match taken wherever its search reached (tuning.weak_reach).
        by_look = expected is not None and self._textured[m]
        bone = self._bone_rule(t, m, seen, bounded=bounded, hold_length=not by_look)
        figure = self._figure(m)
        found = match(image, self.templates[m], centre, angle, joint, bone, turn=turn, figure=figure,
                      small=self._small(), turn_ranks=turn_ranks)
        poor = found.confidence < self.match.turn_confidence
        refit = self._refit_turn(t, m, found, seen) if turn and poor else None
        if refit is not None:
            other = match(image, self.templates[m], found.xy, refit, joint, bone, turn=False, figure=figure)
            if other.confidence > found.confidence:
                found = other
        if found.confidence < self.match.turn_confidence and turn and self._end_on(t, m):
            # A bone seen end-on gives no angle: the rectangle is looked for at turns all round.
            place, coarse, turned = locate(self._small(), self.templates[m], centre, angle, joint,
                                           joint.radius, bone, figure, turns=self.match.spin_turns)
            if coarse >= self.tuning.coarse_confidence:
                other = match(image, self.templates[m], place, turned, joint, bone, turn=False, figure=figure)
                if other.confidence > found.confidence:
                    found = other
        xy, confidence = found.xy, found.confidence
        far = math.hypot(*(xy - (centre if expected is None else expected)))
        weak_and_far = (confidence < self.tuning.weak_confidence and not by_look
                        and far > self.tuning.weak_reach * self._pace * max(joint.size))
        # Found plainly by a texture of its own, it may lie beside a joint that shows (a hand
        # before the face, a foot passing the other), though not on it: a textured patch moved a
        # few pixels no longer matches itself, so a plain match there is the joint that shows,
        # which may look the same (twin gloves).
        apart = self.tuning.weak_reach if by_look and confidence >= self.tuning.weak_confidence else 0.5
        if self._textured[m] and bounded and far <= joint.radius:
            # Within its window of where it is carried, a joint with a texture of its own is found
            # again as plainly as it showed (see SearchTuning.reacquire_confidence).
            needed = min(needed, self.match.visible_confidence)
        if confidence < needed or weak_and_far or (bounded and self._taken(t, m, xy, seen, apart)):
            self.C[t, m] = max(self.C[t, m], min(confidence, self._hidden))
            return False
        self.P[t, m], self.C[t, m], seen[m], agree[m] = xy, confidence, True, found.agree
        self._alike[m] = found.alike
        self.taken[m] = found
        return True

    def _learn(self, image, t, m):
        """Re-cut joint ``m``'s latest template where it was found at ``t``, its two templates
        agreeing: with a texture of its own, if the patch there looks like its anchor at least
        ``tuning.anchor_likeness`` (:func:`~toonmotion.capture.patches.likeness`); else if it
        was found plainly (``match.update_confidence``)."""
        textured = self._textured[m]
        if not textured and self.C[t, m] < self.match.update_confidence:
            return
        patch = sample(image, self.P[t, m], self.angles[t, m], self.plans(m).size)
        if not textured or likeness(self.templates[m].anchor, patch) >= self.tuning.anchor_likeness:
            self.templates[m].latest = patch

    def _refit_turn(self, t, m, found, seen):
        """For a textured joint ``m`` whose parent was found at ``t`` (``seen``): its rectangle's
        angle turned as its bone, from the parent to the place ``found``, turned since ``t - 1``,
        if that differs from the angle it was matched at by more than ``tuning.refit_turn``; else
        None."""
        g = self.plans.parents[m]
        if not self._textured[m] or g < 0 or not seen[g]:
            return None
        turn = bone_turn(self.P[t - 1, m] - self.P[t - 1, g], found.xy - self.P[t, g])
        if turn is None:
            return None
        angle = float(self.angles[t - 1, m]) + turn
        turned_enough = abs(math.remainder(angle - found.angle, 2 * math.pi)) > self.tuning.refit_turn
        return angle if turned_enough else None

    def _taken(self, t, m, xy, seen, apart=0.5):
        """Whether another joint showing at ``xy`` (found at ``t``, or not yet looked for at ``t`` and
        found at ``t - 1``) lies within ``apart`` of ``m``'s rectangle's larger side: a hidden joint
        is not found again on a joint that shows (on a cartoon the left leg looks like the right
        one); half a rectangle, or less for a joint with a texture of its own that matches plainly
        (:meth:`_try`)."""
        others = np.where(seen[:, None], self.P[t], self.P[t - 1])
        showing = seen | (self.lost == 0)
        showing[m] = False
        near = np.hypot(*(others[showing] - xy).T) < apart * max(self.plans(m).size)
        return bool(near.any())

    def _small(self):
        """This frame at half resolution (``cv2.pyrDown``), made once a frame when first asked for."""
        assert self._pyramid is not None  # set by frame()
        return self._pyramid.level(1)

    def _end_on(self, t, m):
        """Whether joint ``m``'s bone was shorter than its rectangle at ``t - 1`` (seen end-on)."""
        g = self.plans.hangs_from[m]
        return g >= 0 and float(np.hypot(*(self.P[t - 1, m] - self.P[t - 1, g]))) < max(self.plans(m).size)

    def _plan(self, m, pace=1.0):
        """Joint ``m``'s plan to match it by at this frame's ``pace``: with a texture of its own, its
        colour weighs ``tuning.textured_colour_weight`` times as much."""
        return self.plans(m, pace, self.tuning.textured_colour_weight if self._textured[m] else 1.0)

    def _figure(self, m):
        """This frame's figure (``near`` mask) if joint ``m`` is held to it, else None."""
        return self._near if self.held_to_figure[m] else None

    def _bone_rule(self, t, m, seen, *, bounded, hold_length=True):
        """The kinematic term for joint ``m`` at ``t`` if its parent was found there, else None:
        its bone's length at ``t - 1``, weight ``tuning.bone_weight * w_beta`` (of the window at this
        frame's pace; 0 without ``hold_length``), and with ``bounded`` a reach of ``tuning.reach_slack``
        times the longest the bone has been seen."""
        g = self.plans.hangs_from[m]
        if g < 0 or not seen[g]:
            return None
        P = self.P
        length = float(np.hypot(*(P[t - 1, m] - P[t - 1, g])))
        reach = self.tuning.reach_slack * self.longest[m] if bounded and self.longest[m] > 0 else math.inf
        weight = self.tuning.bone_weight * self.plans(m, self._pace).w_beta if hold_length else 0.0
        return BoneRule(P[t, g], length, weight, reach)


