"""One frame of the joint tracker: where each joint is looked for, and where it is put when it is
not found (thesis 4.4, with re-acquisition).

A frame is searched in four passes over the skeleton:

1. **Down** (parents before children). A joint seen last drawing is matched round its
   prediction (eq. 4.4-4.6). A joint with a parent found this frame is held near its bone's last
   length, a kinematic term beside eq. 4.6 (:class:`~toonmotion.capture.joint_plan.BoneRule`);
   one with a texture of its own weighs its colour :data:`TEXTURED_COLOUR_WEIGHT` times as much.
   A *hidden* joint is looked for afresh: round its parent, if that was found, at every place its
   bone can reach in directions widening from where it was last (:data:`SPAN_STEP` a drawing),
   its rectangle turned with its bone there (:func:`~toonmotion.capture.coarse_search.search_round`);
   else near where its parent carries it (a parent hidden too is first put where its own parent
   carries it), in a window that widens for every drawing it stays hidden
   (:func:`~toonmotion.capture.coarse_search.locate`; with no bone to give its angle, at turns
   all round, :func:`~toonmotion.capture.template_spin.locate_all_round`); after a held drawing,
   as every window, as many times as wide as the frames it was held. A joint with a texture of its own not
   found round its prediction is looked for at once in the same way. The best places are then matched
   finely, and the joint is taken as found again only by a match at least
   :data:`REACQUIRE_CONFIDENCE` confident (a joint with a texture of its own, within its window
   of where it is carried, as plainly as a joint that shows), within :data:`REACH_SLACK` times the
   longest its bone has been seen. A joint with a texture of its own
   (:func:`~toonmotion.capture.patches.is_textured`) is looked for where it looks alike:
   its places are picked by look, it is not held to its bone's last length, a weak match is
   taken wherever it lies, and one at least :data:`WEAK_CONFIDENCE` confident even beside a joint
   that shows (not on it); a flat-coloured one, whose look-alikes are all over a cartoon, is held
   to where its bone and its guessed place put it.
2. **Up** (children before parents). A joint still not found is looked for where the joints
   hanging from it that were found put it (each moved as its child moved), if its coarse match
   there is at least :data:`UP_COARSE_CONFIDENCE`.
3. **Settle** (parents first). A joint found on a flat fill, where places along the fill match as
   well as its match (:data:`AMBIGUOUS_SPREAD`), is put among them where its parent and its
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
    UPDATE_CONFIDENCE,
    VISIBLE_CONFIDENCE,
    BoneRule,
    Plans,
    Templates,
)
from toonmotion.capture.patches import is_textured, likeness, sample
from toonmotion.capture.template_context import CONTEXT_CONFIDENCE, Pyramid, place_by_context
from toonmotion.capture.template_match import SPIN_TURNS, TURN_CONFIDENCE, Match, match
from toonmotion.capture.template_spin import TurnedDiscs, locate_all_round
from toonmotion.capture.track_figure import FigureMasks, onto_figure
from toonmotion.capture.track_hidden import carried_by_parent, lengthen, moves_below, place_hidden
from toonmotion.capture.track_prediction import bone_turn, hidden_at, turns

# A hidden joint's window widens by WIDEN_STEP of its search radius for every drawing it stays
# hidden, up to MAX_WIDEN times the radius.
WIDEN_STEP = 0.5
MAX_WIDEN = 3.0
# A hidden joint whose parent is found is looked for round it, in directions up to this many
# radians from where it was last for every drawing it has been hidden (all round at most).
SPAN_STEP = math.radians(45)
# Places whose coarse match is less confident than this are not looked at closely; of the others,
# a rectangle apart, the PLACES best are matched finely, best first, until one is found. The coarse
# match only ranks places (a quarter-rectangle grid misses a fine texture by up to an eighth of a
# rectangle): refining the best 2 instead of the best 64 lost joints on 4 of the 14 rendered
# clips (e.g. the flat walk's mean error 5.7 -> 7.7 px) at no gain in speed.
COARSE_CONFIDENCE = 0.1
PLACES = 64
# The up pass looks closely only where the coarse match, at the joint's angle or a turn, is at
# least this. At COARSE_CONFIDENCE it made a fifth of all matches and found a joint in about 4% of
# its tries; on the seed-0 renders 40 of the 43 textured joints it found (all within 0.4 px)
# matched at least 0.3 coarse, as did 64 of the 75 flat ones found within 3 px (and 51 of the 68
# found farther off), in a quarter of its tries. The textured zombie walk went from 68 to 84
# frames/s, the flat walk from 85 to 92 (the benchmark's first 120 frames); the textured renders
# from 48.5 to 49.1 px summed (whole clips, ones and twos at seeds 0 and 2; the zombie walk on twos
# 2.6 -> 3.0), the cel renders from 260.0 to 263.3, at seed 5 (used for nothing else) 23.0 -> 23.4
# and 257.4 -> 204.5; the drawings' footage did not move.
UP_COARSE_CONFIDENCE = 0.3
# A hidden joint is found again only by a match at least this confident, no farther from its
# parent than REACH_SLACK times the longest its bone has been seen. The anchor may have been cut
# with a neighbour overlapping the joint; 0.6 still tells a joint from a different texture (0.1
# at most) and from plain background.
REACQUIRE_CONFIDENCE = 0.35
REACH_SLACK = 1.2
# ... but a joint with a texture of its own matched within its window of where it is carried (or,
# in the up pass, of where the joints below put it) needs only VISIBLE_CONFIDENCE, as when it
# showed: a texture of its own is not found on another part there. An elbow half behind the body
# matched at 0.25-0.30 where it was; on twos it matched at 0.245 one drawing, and, needing 0.35
# to be found again, it was carried 18 px off for 20 frames (the walk on twos). On the
# textured renders (whole clips, ones and twos at seeds 0 and 2) 45.75 -> 43.18 px summed, 10 clips
# better by more than 3% and none worse; at seed 5, used for nothing else, 21.81 -> 20.39; the
# cel renders and the drawings' footage did not move. Anywhere its search reached (not only
# within its window), the zombie walk at seed 2 went from 2.6 to 7.4 px, an elbow taken 50 px off.
# A joint matched less confidently than WEAK_CONFIDENCE (but at least VISIBLE_CONFIDENCE, or
# REACQUIRE_CONFIDENCE when hidden) is taken as found only within WEAK_REACH of its rectangle's
# larger side from where it was expected (predicted; carried, when hidden), times the pace (as
# the windows widen after a held drawing): a weak match may refine where a joint is (its looks
# partly covered, or changed as its limb bends), but not carry it off along a flat limb that
# looks alike all the way. A hidden joint whose template is textured (patches.is_textured)
# is the exception: it is found again by a weak match wherever its search reaches, since where it
# is carried is only a guess, the longer it hides the worse, and a texture of its own is not found
# on another limb. (Held to its guess, a hand lost on twos as its arm swung down stayed 116 px off
# for the last 50 frames of the wave clip, in plain view, found there at 0.47 every drawing.)
WEAK_CONFIDENCE = 0.5
WEAK_REACH = 0.25
# A joint with a texture of its own matched less confidently than TURN_CONFIDENCE, whose parent was
# found this frame, is matched once more where it was found, its rectangle turned as its bone from
# the parent to there has turned, if that differs from the angle it was matched at by more than
# REFIT_TURN. The predicted angle comes from predicted places, which miss where a limb swings and
# stops within a drawing: on the jumping jacks on twos a hand was found in the right place at
# 0.08, turned 68 degrees wrong, and called hidden. (Done for flat-coloured joints too, the cel
# renders went from 409.7 to 386.2 px summed over ones and twos at seeds 0 and 2, but from 253.7
# to 287.6 at seed 5 and from 134.3 to 137.2 on footage of the shared drawings.)
REFIT_TURN = math.radians(5)
# A joint found is ambiguous when the places joined to its match that match as well as it
# (joint_plan.ALIKE_LEVEL) reach farther than this fraction of its rectangle's larger side from
# it: a flat fill, where the texture cannot say where along it the joint is. Its predicted motion
# does not know either, and a knee of the demo's flat-blue trousers slid 80 px up the leg going by
# it; the joint is put among those places where its neighbours carry it (FrameSearch._settle).
AMBIGUOUS_SPREAD = 0.125
# A joint with a texture of its own (patches.is_textured) weighs its colour this many times
# as much as eq. 4.6's w_alpha: its colour cost has one sharp minimum, which the distances from the
# prediction and from its bone's last length should not outweigh. At w_alpha = 1 / 255^2 a wave's
# hand swinging 21 px a drawing on twos was taken 11 px short of it, where it matched at 0.09, over
# where it matched at 0.67: there the prior cost 0.27 more (13 px farther from the prediction, 6 px
# more of bone shortened), the colour 0.17 less. 16 times and more all gave the same (colour decides
# but for near-ties); a flat-coloured joint's colour cost is flat along its fills, and the prior
# decides there.
TEXTURED_COLOUR_WEIGHT = 16.0
# A joint with a texture of its own re-cuts its latest template where the two agree and the place
# looks like its anchor, which never learns, with a likeness of at least this, whatever the light
# (patches.likeness); a flat-coloured one where it is found plainly (UPDATE_CONFIDENCE, the
# higher of the two templates' confidences). At 0.8 of either confidence, a textured square passing
# behind an occluder at 0.5-0.75 px a frame was lost to it, each frame's latest (a little more
# occluder) matching the next at 0.8 or better; at 0.6 of likeness still. Asked for 0.5 of the
# anchor's confidence instead, a picture darkening by 0.7 grey levels a frame lost its joint. A textured
# joint whose looks change as its limb bends keeps a latest that follows them (textured renders,
# ones and twos at seeds 0 and 2: 75.78 -> 72.15 px summed, 9 clips better, 8 worse). A flat
# joint's anchor is alike anywhere along its fill.
ANCHOR_LIKENESS = 0.8
# The kinematic term's weight per squared pixel of bone-length change, relative to w_beta (of the
# window widened after a held drawing: over a double step a bone changes twice as much).
BONE_WEIGHT = 1.0

# The confidence a joint taken to be hidden is saved with, at most: just under VISIBLE_CONFIDENCE.
_HIDDEN = float(np.nextafter(VISIBLE_CONFIDENCE, 0))


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
    """

    def __init__(self, plans: Plans, templates: list[Templates], P: NDArray[np.float64],
                 C: NDArray[np.float64], angles: NDArray[np.float64], lost: NDArray[np.int_],
                 longest: NDArray[np.float64], figure: FigureMasks | None = None,
                 on_figure: NDArray[np.bool_] | None = None) -> None:
        self.plans, self.templates = plans, templates
        self.P, self.C, self.angles = P, C, angles
        self.lost: NDArray[np.int_] = np.array(lost, dtype=int)
        self.longest: NDArray[np.float64] = np.array(longest, dtype=float)
        self.figure = figure
        self.held_to_figure = np.ones(len(plans), bool) if on_figure is None else np.asarray(on_figure, bool)
        self._near: NDArray[np.uint8] | None = None
        self._textured = [is_textured(t.anchor) for t in templates]
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
        P, plans = self.P, self.plans
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
                self._try(image, t, m, self._plan(m, pace), predicted[m], angle[m], VISIBLE_CONFIDENCE, seen,
                          agree)
                if seen[m]:
                    continue
            carried = hidden_at(P, t, m, coast[m], plans.hangs_from)
            if self.lost[m] or self._textured[m]:
                # A textured joint not found round its prediction is looked for at once as if hidden.
                hidden = max(int(self.lost[m]), 1)
                for centre, turned in self._places_to_look(self._small(), t, m, carried, angle[m], seen,
                                                           hidden):
                    if self._try(image, t, m, self._plan(m, pace), centre, turned, REACQUIRE_CONFIDENCE, seen,
                                 agree, bounded=True, turn=False, expected=carried):
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
                if max(ranks) >= UP_COARSE_CONFIDENCE:
                    self._try(image, t, m, self._plan(m), centre, angle[m], REACQUIRE_CONFIDENCE, seen, agree,
                              bounded=True, turn_ranks=ranks[1:])
        self._settle(t, coast, seen)
        # A joint not found goes no farther in one frame than its search could have reached.
        reach = np.array([plans(m, pace).radius * min(1.0 + WIDEN_STEP * self.lost[m], MAX_WIDEN)
                          for m in range(k)])
        place_hidden(P, t, coast, seen, plans.hangs_from, reach)
        # A joint leaving the picture stays at its edge.
        np.clip(P[t], 0.0, [image.shape[1] - 1, image.shape[0] - 1], out=P[t])
        if self._near is not None:  # a hidden joint is behind the figure, so on it
            for j in np.flatnonzero(~seen & self.held_to_figure):
                P[t, j] = onto_figure(self._near, P[t, j], reach[j])
        self.lost = np.where(seen, 0, self.lost + 1)
        self.angles[t] = self.angles[t - 1] + turns(P[t - 1], P[t], plans.parents, True)
        for j in np.flatnonzero(seen & agree):
            self._learn(image, t, int(j))
        lengthen(self.longest, P[t], self.C[t], plans.hangs_from)

    def _settle(self, t, coast, seen):
        """Put each ambiguous joint found at ``t`` (its alike places reach farther than
        :data:`AMBIGUOUS_SPREAD` of its rectangle from its match), parents first, among those places
        where its parent and its children found unambiguously carry it, as a hidden joint is placed
        (:func:`place_hidden`): at that place itself if it lies within a pixel of one, else at the
        nearest. Where its wider view (:mod:`~toonmotion.capture.template_context`) matches plainly
        enough, that places the joint instead (neighbours inside the same fill drift as it does). A
        root with neither keeps its match."""
        P, hangs_from = self.P, self.plans.hangs_from
        ambiguous = np.zeros(len(seen), bool)
        for m in np.flatnonzero(seen):
            spread = np.hypot(*(self._alike[m] - P[t, m]).T).max()
            ambiguous[m] = spread > AMBIGUOUS_SPREAD * max(self.plans(m).size)
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
        far beyond), if it matches at least :data:`CONTEXT_CONFIDENCE` within
        :data:`AMBIGUOUS_SPREAD` of the rectangle from a place alike to the match; else None (also
        with no context)."""
        context = self.templates[m].context
        if context is None:
            return None
        assert self._pyramid is not None  # set by frame()
        radius, angle = 2 * self.plans(m, self._pace).radius, float(self.angles[t - 1, m])
        xy, sure = place_by_context(self._pyramid, context, self.P[t, m], angle, radius)
        # It chooses among the places alike to the joint's match: where it points elsewhere
        # (an elbow's context, the arm raised, found on the head), the two disagree.
        near = float(np.hypot(*(self._alike[m] - xy).T).min()) <= AMBIGUOUS_SPREAD * max(self.plans(m).size)
        return xy if sure >= CONTEXT_CONFIDENCE and near else None

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
            span = min(math.pi, SPAN_STEP * hidden)
            turned = float(self.angles[t - 1, m])
            found = search_round(small, self.templates[m], joint, bone, start, span, turned, count=PLACES,
                                 figure=self._figure(m), by_look=self._textured[m])
            return [(xy, turned) for xy, coarse, turned in found if coarse >= COARSE_CONFIDENCE]
        radius = joint.radius * min(1.0 + WIDEN_STEP * hidden, MAX_WIDEN)
        if bone is None and plans.parents[m] >= 0:
            # Its parent not found, its bone gives no angle to go by: it is looked for at turns all round.
            xy, coarse, turned = locate_all_round(small, self._discs(m), carried, joint, radius,
                                                  figure=self._figure(m))
        else:
            xy, coarse, turned = locate(small, self.templates[m], carried, angle, joint, radius, bone,
                                        self._figure(m))
        return [(xy, turned)] if coarse >= COARSE_CONFIDENCE else []

    def _discs(self, m):
        """Joint ``m``'s anchor's coarse disc turned all round (made when first asked for)."""
        coarse = self.templates[m].coarse
        if self._turned[m] is None or self._turned[m].coarse is not coarse:
            self._turned[m] = TurnedDiscs(coarse)
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
        confidence so far (below VISIBLE_CONFIDENCE)."""
        # A hidden joint with a texture of its own is looked for again where it looks alike: not
        # held to its bone's last length (the bone may have come out of foreshortening meanwhile),
        # and a weak match taken wherever its search reached (WEAK_REACH).
        by_look = expected is not None and self._textured[m]
        bone = self._bone_rule(t, m, seen, bounded=bounded, hold_length=not by_look)
        figure = self._figure(m)
        found = match(image, self.templates[m], centre, angle, joint, bone, turn=turn, figure=figure,
                      small=self._small(), turn_ranks=turn_ranks)
        refit = self._refit_turn(t, m, found, seen) if turn and found.confidence < TURN_CONFIDENCE else None
        if refit is not None:
            other = match(image, self.templates[m], found.xy, refit, joint, bone, turn=False, figure=figure)
            if other.confidence > found.confidence:
                found = other
        if found.confidence < TURN_CONFIDENCE and turn and self._end_on(t, m):
            # A bone seen end-on gives no angle: the rectangle is looked for at turns all round.
            place, coarse, turned = locate(self._small(), self.templates[m], centre, angle, joint,
                                           joint.radius, bone, figure, turns=SPIN_TURNS)
            if coarse >= COARSE_CONFIDENCE:
                other = match(image, self.templates[m], place, turned, joint, bone, turn=False, figure=figure)
                if other.confidence > found.confidence:
                    found = other
        xy, confidence = found.xy, found.confidence
        far = math.hypot(*(xy - (centre if expected is None else expected)))
        weak_and_far = (confidence < WEAK_CONFIDENCE and not by_look
                        and far > WEAK_REACH * self._pace * max(joint.size))
        # Found plainly by a texture of its own, it may lie beside a joint that shows (a hand
        # before the face, a foot passing the other), though not on it: a textured patch moved a
        # few pixels no longer matches itself, so a plain match there is the joint that shows,
        # which may look the same (twin gloves).
        apart = WEAK_REACH if by_look and confidence >= WEAK_CONFIDENCE else 0.5
        if self._textured[m] and bounded and far <= joint.radius:
            # Within its window of where it is carried, a joint with a texture of its own is found
            # again as plainly as it showed (see REACQUIRE_CONFIDENCE).
            needed = min(needed, VISIBLE_CONFIDENCE)
        if confidence < needed or weak_and_far or (bounded and self._taken(t, m, xy, seen, apart)):
            self.C[t, m] = max(self.C[t, m], min(confidence, _HIDDEN))
            return False
        self.P[t, m], self.C[t, m], seen[m], agree[m] = xy, confidence, True, found.agree
        self._alike[m] = found.alike
        self.taken[m] = found
        return True

    def _learn(self, image, t, m):
        """Re-cut joint ``m``'s latest template where it was found at ``t``, its two templates
        agreeing: with a texture of its own, if the patch there looks like its anchor at least
        :data:`ANCHOR_LIKENESS` (:func:`~toonmotion.capture.patches.likeness`); else if it
        was found plainly (``UPDATE_CONFIDENCE``)."""
        textured = self._textured[m]
        if not textured and self.C[t, m] < UPDATE_CONFIDENCE:
            return
        patch = sample(image, self.P[t, m], self.angles[t, m], self.plans(m).size)
        if not textured or likeness(self.templates[m].anchor, patch) >= ANCHOR_LIKENESS:
            self.templates[m].latest = patch

    def _refit_turn(self, t, m, found, seen):
        """For a textured joint ``m`` whose parent was found at ``t`` (``seen``): its rectangle's
        angle turned as its bone, from the parent to the place ``found``, turned since ``t - 1``,
        if that differs from the angle it was matched at by more than :data:`REFIT_TURN`; else
        None."""
        g = self.plans.parents[m]
        if not self._textured[m] or g < 0 or not seen[g]:
            return None
        turn = bone_turn(self.P[t - 1, m] - self.P[t - 1, g], found.xy - self.P[t, g])
        if turn is None:
            return None
        angle = float(self.angles[t - 1, m]) + turn
        return angle if abs(math.remainder(angle - found.angle, 2 * math.pi)) > REFIT_TURN else None

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
        colour weighs :data:`TEXTURED_COLOUR_WEIGHT` times as much."""
        return self.plans(m, pace, TEXTURED_COLOUR_WEIGHT if self._textured[m] else 1.0)

    def _figure(self, m):
        """This frame's figure (``near`` mask) if joint ``m`` is held to it, else None."""
        return self._near if self.held_to_figure[m] else None

    def _bone_rule(self, t, m, seen, *, bounded, hold_length=True):
        """The kinematic term for joint ``m`` at ``t`` if its parent was found there, else None:
        its bone's length at ``t - 1``, weight ``BONE_WEIGHT * w_beta`` (of the window at this
        frame's pace; 0 without ``hold_length``), and with ``bounded`` a reach of REACH_SLACK
        times the longest the bone has been seen."""
        g = self.plans.hangs_from[m]
        if g < 0 or not seen[g]:
            return None
        P = self.P
        length = float(np.hypot(*(P[t - 1, m] - P[t - 1, g])))
        reach = REACH_SLACK * self.longest[m] if bounded and self.longest[m] > 0 else math.inf
        weight = BONE_WEIGHT * self.plans(m, self._pace).w_beta if hold_length else 0.0
        return BoneRule(P[t, g], length, weight, reach)


