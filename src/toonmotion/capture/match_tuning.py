"""The tuning of the tracker's matching core: how a match's confidence is read and the bars it is
held to, the turns a rectangle is tried at, which cells match as well as the match, when a
template is distinct or textured, and a joint's wider view (:mod:`~toonmotion.capture.patches`,
:mod:`~toonmotion.capture.joint_plan`, :mod:`~toonmotion.capture.template_match`,
:mod:`~toonmotion.capture.coarse_search`, :mod:`~toonmotion.capture.template_context`).
:class:`MatchTuning`, given as ``TrackSettings(match=...)``."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from functools import cached_property

from toonmotion.capture.track_checks import Tuning, above, at_least, share, whole


@dataclass(frozen=True)
class MatchTuning(Tuning):
    """How the tracker matches a joint's templates in a frame and reads the match.

    The defaults are the tracker's. The measurements given are those on record (the comments the
    values were module constants with, and ``docs/capture.md``, "Tracking"); where none is, it says
    so. Each value's range is checked when the tuning is made
    (:class:`~toonmotion.capture.track_checks.Tuning`).

    Attributes
    ----------
    confidence_scale : float
        Grey levels, > 0: a match's confidence is ``exp(-d^2 / (2 s^2))``, ``d`` the root mean
        square difference per channel (at 30: 1 exact, 0.8 at ``d`` = 20, 0.5 at 35, 0.25 at 50).
        Every confidence bar here and in ``SearchTuning`` is read on this scale. No measurement on
        record.
    update_confidence : float
        0 to 1: cells matching at least this confidently are *plain*: the mixed cost (eq. 4.6)
        picks among them first, in the fine and the coarse searches; an anchor matching so is
        taken without matching the latest template; a flat-coloured joint found so, its templates
        agreeing, re-cuts its latest template; a correction re-cuts templates at the last frame a
        joint was this confident. No measurement on record.
    visible_confidence : float
        0 to 1: a joint whose best match is less confident than this is hidden: carried by its
        parent (a root coasts), its templates left alone; the other places a search keeps are at
        least this confident. The bar was 0.5: a joint whose anchor was cut with a neighbour over
        half of it matches at 0.3-0.5 in the right place (the textured walk's left elbow was hidden
        77 of 78 frames). Of the matches within 3 px of the joint on the 7 shared clips, 0.5 kept
        94 % (textured) and 84 % (flat), 0.25 keeps 97 % and 92 %.
    turn_confidence : float
        0 to 1: a turning rectangle matching less confidently than this at its predicted angle
        tries the extra turns (``turn_step``), a textured one its bone's turn
        (``SearchTuning.refit_turn``), one on a bone seen end-on turns all round (``spin_step``).
        At the plain bar, 0.8, a joint partly covered (0.6-0.8 at the right angle) tried six turns
        every frame: the jumping jacks went 174 -> 64 frames/s, no more accurate.
    turn_step : float
        Degrees, > 0: the extra turns are ``turn_step``, twice that, ... ``turn_count`` times
        that, each way (times the pace after a held drawing). A limb that sets off at 12 degrees a
        frame is lost without them and tracked within 0.03 px with them; no other step measured.
    turn_count : int
        How many extra turns each way, >= 1 (see ``turn_step``). No measurement on record.
    fine_turns : int
        How many of the extra turns, ranked at half resolution, are matched finely, best first,
        until one reaches ``turn_confidence``, >= 1. At 1 the rendered clips measured 90.8 px
        summed against 92.6 at 2, but a grey level and a half of noise took the flat jumping jacks
        from 1.3 to 7.8 px (2.9 at 2).
    spin_step : float
        Degrees, > 0: a rectangle on a bone seen end-on (shorter than the rectangle) matching
        below ``turn_confidence`` is looked for coarsely at turns all round this far apart (every
        20: 18 turns). Looking all round took the textured zombie walk from 4.0 to 2.4 px mean
        error; no other step measured.
    coarse_turn_step : float
        Degrees, > 0: the coarse search round where a hidden joint is carried tries its
        rectangle's angle and turns of this, twice this, ... ``coarse_turn_count`` times this, each
        way. No measurement on record.
    coarse_turn_count : int
        How many such turns each way, >= 0 (0: the angle alone). No measurement on record.
    drift_tolerance : float
        Pixels, >= 0: the anchor's and the latest template's matches agree when they lie within
        this (the anchor's place is taken, and the latest may be re-cut there). No measurement on
        record.
    alike_level : float
        Grey levels (root mean square per channel), >= 0: cells whose sum of squared differences
        exceeds the match's by less than this squared per pixel and channel match as well as it;
        joined to it, they are where the texture cannot tell the joint's place apart (a stretch of
        a flat fill, ``SearchTuning.ambiguous_spread``); and an anchor within it is found again as
        cut (``exact_cells``). A video's compression noise is 1-2. No measurement on record.
    exact_cells : int
        Cells, >= 1: an anchor found again as cut (every cell within ``alike_level``) at no more
        than this many whole-pixel cells (a place between cells takes up to 2 x 2) is there,
        however far from the prediction. The demo went 3.74 -> 3.04 px; without the bound (a flat
        anchor is found as cut all along its fill) one drawing's clip went 13.3 -> 14.4 px.
    others : int
        How many other places, >= 0: besides its match a search keeps up to this many local minima
        of the colour cost, at least ``visible_confidence`` confident, for the whole-clip pass
        (:mod:`~toonmotion.capture.track_path`) to choose among. No measurement on record.
    other_spacing : int
        Pixels, >= 1: those places are the least of the cells this far round them. No measurement
        on record.
    distinct_shift : int
        Pixels, >= 1: how far a patch is moved to tell whether it is distinct or textured. No
        measurement on record.
    distinct_ratio : float
        0 to 1: a patch that, moved ``distinct_shift`` in the direction it changes least, changes
        by less than this share of its change in the direction it changes most (or by less than
        ``distinct_level``) is not distinct: its template grows (``max_growth``). Chosen on the demo
        clip: mean error 4.9 px; 0.15 gave 10.4 px, 0.2 21 px (feet grew to take in the floor).
    distinct_level : float
        Grey levels (root mean square per channel), >= 0: see ``distinct_ratio``. No measurement
        on record.
    max_growth : float
        Times the rectangle's sides, >= 1: a template that is not distinct grows by half again
        (1, 1.5, 2.25, ...) while it is not, up to this. No measurement on record.
    texture_level : float
        Grey levels, >= 0: a template has a texture of its own when at least ``textured_fraction``
        of its pixels change by more than this in some channel when it is moved ``distinct_shift``
        along x or y. One drawn in flat fills and outlines changes along its outlines only:
        22-48 % of its pixels on the tracking benchmark's cel renders, 93-98 % on its textured
        ones, with camera noise of 5 grey levels or without.
    textured_fraction : float
        0 to 1: see ``texture_level``.
    context_growth : float
        Times the rectangle's larger side, >= 1: the side of a joint's wider view
        (:mod:`~toonmotion.capture.template_context`). Over the drawings' footage (43 clips,
        287.2 px summed without a context) 2 placed the joints 236.0 px off summed, 2.5 241.7,
        3 259.1 and 4 265.3; at 1.5 the demo went 28.2 px off (1.9 at 2.5), which 2.5 keeps away
        from.
    context_side : int
        Pixels, >= 1: the context is matched at the first pyramid level where it is at most this
        wide. At 32 (with contexts 3 rectangles wide) the demo went 3.4 px off.
    context_turn_step : float
        Degrees, > 0: the context is matched at the rectangle's angle and turned this, twice
        this, ... ``context_turn_count`` times this, each way (a root's rectangle does not turn,
        but a body leans). At the angle alone, a flat body leaning 14 degrees lost its joints
        (the tests: 30-36 px off).
    context_turn_count : int
        How many such turns each way, >= 0. No measurement on record beyond ``context_turn_step``'s.
    context_confidence : float
        0 to 1: a context matching less confidently does not place its joint. On the drawings'
        footage, where it matched at least 0.7 (near a place alike to the joint's match) it was
        5.0 px from the joint on average, where the neighbours carried it 7.4 px; below 0.3,
        39 px. A bar of 0.6 or 0.8 placed the joints 247.1 and 249.1 px off summed (241.7 at 0.7).

    Examples
    --------
    >>> [round(math.degrees(turn)) for turn in MatchTuning().turns]
    [5, -5, 10, -10, 15, -15]
    >>> wider = MatchTuning(coarse_turn_step=20, coarse_turn_count=2)
    >>> [round(math.degrees(turn)) for turn in wider.coarse_turns]
    [0, 20, -20, 40, -40]
    """

    confidence_scale: float = above(0.0, 30.0)
    update_confidence: float = share(0.8)
    visible_confidence: float = share(0.25)
    turn_confidence: float = share(0.6)
    turn_step: float = above(0.0, 5.0)
    turn_count: int = whole(3)
    fine_turns: int = whole(2)
    spin_step: float = above(0.0, 20.0)
    coarse_turn_step: float = above(0.0, 25.0)
    coarse_turn_count: int = whole(1, least=0)
    drift_tolerance: float = at_least(0.0, 2.0)
    alike_level: float = at_least(0.0, 3.0)
    exact_cells: int = whole(9)
    others: int = whole(4, least=0)
    other_spacing: int = whole(2)
    distinct_shift: int = whole(2)
    distinct_ratio: float = share(0.1)
    distinct_level: float = at_least(0.0, 1.0)
    max_growth: float = at_least(1.0, 3.0)
    texture_level: float = at_least(0.0, 12.0)
    textured_fraction: float = share(0.75)
    context_growth: float = at_least(1.0, 2.5)
    context_side: int = whole(48)
    context_turn_step: float = above(0.0, 10.0)
    context_turn_count: int = whole(2, least=0)
    context_confidence: float = share(0.7)

    @cached_property
    def turns(self) -> tuple[float, ...]:
        """The extra turns a turning rectangle matching badly tries, radians: ``turn_step``,
        ``-turn_step``, twice that either way, ... (``turn_count`` each way)."""
        return _either_way(self.turn_step, self.turn_count)

    @cached_property
    def spin_turns(self) -> tuple[float, ...]:
        """The turns all round a rectangle on a bone seen end-on is looked for at, radians: 0,
        ``spin_step``, twice that, ... under a whole turn."""
        steps = itertools.takewhile(lambda a: a < 360, (self.spin_step * i for i in itertools.count()))
        return tuple(math.radians(a) for a in steps)

    @cached_property
    def coarse_turns(self) -> tuple[float, ...]:
        """The turns the coarse search round a hidden joint's guessed place tries, radians: 0, then
        ``coarse_turn_step`` either way, ... (``coarse_turn_count`` each way)."""
        return (0.0, *_either_way(self.coarse_turn_step, self.coarse_turn_count))

    @cached_property
    def context_turns(self) -> tuple[float, ...]:
        """The turns of the rectangle's angle a joint's context is matched at, radians: 0, then
        ``context_turn_step`` either way, ... (``context_turn_count`` each way)."""
        return (0.0, *_either_way(self.context_turn_step, self.context_turn_count))


def _either_way(step: float, count: int) -> tuple[float, ...]:
    """``step``, ``-step``, ``2 step``, ``-2 step``, ... ``count`` steps each way, degrees, as radians."""
    return tuple(math.radians(sign * i * step) for i in range(1, count + 1) for sign in (1, -1))
