"""The tuning of the tracker's search for its joints, in each frame
(:mod:`toonmotion.capture.track_search`) and over the whole clip
(:mod:`toonmotion.capture.track_path`): how wide the windows are, where a hidden joint is looked
for, how confident a match must be to count, and how colour is weighed against the skeleton.
:class:`SearchTuning`, given as ``TrackSettings(tuning=...)``."""

from __future__ import annotations

import math
from dataclasses import dataclass

from toonmotion.capture.track_checks import Tuning, above, at_least, share, whole


@dataclass(frozen=True)
class SearchTuning(Tuning):
    """How the tracker searches for its joints: each frame (eq. 4.4-4.6 and re-acquisition) and
    the whole clip's paths.

    Each value was chosen by a measurement on the tracker's benchmark clips (the 14 rendered
    clips of ``benchmarks/track.py``, textured and cel, on ones and twos, at seeds 0 and 2, with
    seed 5 held out) and the shared drawings' footage; the measurement is given with each. The
    defaults are the tracker's; change one to see what it does, not to tune for one clip. Each
    value's range is checked when the tuning is made
    (:class:`~toonmotion.capture.track_checks.Tuning`).

    Attributes
    ----------
    search_fraction : float
        Of a joint's rectangle's larger side: its search radius ``r`` when
        ``TrackSettings.search`` is not given, > 0.
    min_search : float
        Pixels, >= 1: the least default search radius.
    max_hold : int
        How many times as wide every window is, at most, after a drawing held that many frames
        (on twos, twice), >= 1: a held drawing moves that many frames' worth by the next.
    max_widen : float
        Search radii a hidden joint's window widens to at most, and the longest step a joint's
        path may take in a frame in the whole-clip pass, >= 1.
    smoothness : float
        Search radii: the scale of a step's cost in the whole-clip pass, the change of a
        joint's velocity relative to its parent (and of its bone's length) from one drawing to
        the next, > 0. On 10 footage clips of the shared drawings 0.5 and 0.2 made them worse
        (111.7 -> 112.2 px summed), 1.5 better (110.9), 3 and 8 lost one clip (4.7 -> 9.4 px).
    widen_step : float
        Search radii a hidden joint's window widens by for every drawing it stays hidden (up to
        ``max_widen``), >= 0. 0: a hidden joint is looked for only where it is carried, within
        one radius.
    span_step : float
        Radians: a hidden joint whose parent is found is looked for round the parent, in
        directions up to this far either way from where it was last for every drawing it has
        been hidden (all round at most), > 0.
    coarse_confidence : float
        0 to 1: places whose coarse match (a quarter-rectangle grid) is below this are not
        matched finely.
    places : int
        How many of the best coarse places, a rectangle apart, are matched finely, best first,
        until one is found, >= 1. The coarse match only ranks places (it misses a fine texture
        by up to an eighth of a rectangle): refining the best 2 instead of 64 lost joints on 4
        of the 14 rendered clips (the flat walk's mean error 5.7 -> 7.7 px) at no gain in speed.
    up_coarse_confidence : float
        0 to 1: the up pass (a joint placed by the joints hanging from it) matches finely only
        where the coarse match is at least this. At ``coarse_confidence`` it made a fifth of all
        matches and found a joint in 4 % of its tries; at 0.3 the textured zombie walk went from
        68 to 84 frames/s, the errors within 0.5 px summed over the textured renders.
    reacquire_confidence : float
        0 to 1: a hidden joint is found again only by a match at least this confident (0.6
        still tells a joint from a different texture, 0.1 at most, and from plain background;
        the anchor may have been cut with a neighbour overlapping the joint).
    reach_slack : float
        A hidden joint is found again no farther from its parent than this many times the
        longest its bone has been seen, > 0.
    weak_confidence : float
        0 to 1: a joint matched less confidently than this is taken as found only within
        ``weak_reach`` of where it was expected (a weak match may refine where a joint is, not
        carry it along a flat limb that looks alike all the way); a hidden textured joint is
        the exception (a hand lost on twos stayed 116 px off in plain view without it).
    weak_reach : float
        Of the rectangle's larger side, times the pace after a held drawing: how far from where
        it was expected a weak match may put a joint, > 0.
    refit_turn : float
        Radians: a textured joint matched below ``MatchTuning.turn_confidence`` whose parent
        was found is matched again turned as its bone has turned, when that differs by more
        than this, > 0. On the jumping jacks on twos a hand was found in the right place at
        0.08, turned 68 degrees wrong, and called hidden.
    ambiguous_spread : float
        Of the rectangle's larger side: a joint whose equally good places reach farther than
        this is on a flat fill, and is put among them where its neighbours carry it (a knee of
        the demo's flat-blue trousers slid 80 px up the leg without it), > 0.
    textured_colour_weight : float
        How many times eq. 4.6's ``w_alpha`` a joint with a texture of its own weighs its colour,
        > 0. At 1 a wave's hand swinging 21 px a drawing on twos was taken 11 px short of it;
        16 and more all gave the same.
    anchor_likeness : float
        0 to 1: a textured joint re-cuts its latest template only where the place looks like
        its first (anchor) template at least this much. Lower, a textured square passing
        behind an occluder was lost to it; the textured renders went 75.78 -> 72.15 px summed.
    bone_weight : float
        The kinematic term's weight per squared pixel of bone-length change, relative to
        ``w_beta``, >= 0. 0: bones may stretch freely.

    Examples
    --------
    >>> SearchTuning().places, SearchTuning(places=8).places
    (64, 8)
    """

    search_fraction: float = above(0.0, 0.5)
    min_search: float = at_least(1.0, 8.0)
    max_hold: int = whole(3)
    max_widen: float = at_least(1.0, 3.0)
    smoothness: float = above(0.0, 1.5)
    widen_step: float = at_least(0.0, 0.5)
    span_step: float = above(0.0, math.radians(45))
    coarse_confidence: float = share(0.1)
    places: int = whole(64)
    up_coarse_confidence: float = share(0.3)
    reacquire_confidence: float = share(0.35)
    reach_slack: float = above(0.0, 1.2)
    weak_confidence: float = share(0.5)
    weak_reach: float = above(0.0, 0.25)
    refit_turn: float = above(0.0, math.radians(5))
    ambiguous_spread: float = above(0.0, 0.125)
    textured_colour_weight: float = above(0.0, 16.0)
    anchor_likeness: float = share(0.8)
    bone_weight: float = at_least(0.0, 1.0)
