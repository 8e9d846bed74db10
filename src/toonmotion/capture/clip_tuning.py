"""The tuning of how the tracker reads a clip around its search for joints: which frames repeat a
drawing, how a hidden root coasts, how hidden spans are filled, how near the figure a joint must
be, and when a frame's light is matched. :class:`ClipTuning`, given as
``TrackSettings(clip=...)``."""

from __future__ import annotations

from dataclasses import dataclass

from toonmotion.capture.track_checks import Tuning, at_least, share, whole


@dataclass(frozen=True)
class ClipTuning(Tuning):
    """How the tracker reads the clip: held drawings, coasting, hidden spans, the figure, the light.

    Each value was chosen by a measurement, given with it. The defaults are the tracker's. Each
    value's range is checked when the tuning is made (:class:`~toonmotion.capture.track_checks.Tuning`).

    Attributes
    ----------
    coast_steps : int
        A hidden root coasts at its mean velocity over its last (up to) this many visible steps,
        >= 1 (:mod:`~toonmotion.capture.track_prediction`).
    held_level : float
        Grey levels, >= 0: a frame repeats the one before (a drawing held on twos) when fewer than
        ``held_fraction`` of its values differ from it by more than this. Noise and compression
        stay under it, and a figure moving half a pixel changes hundreds of values.
    held_fraction : float
        Of the frame's values (every channel), 0 to 1: see ``held_level``.
    trusted : float
        Of a bone, >= 0: where the guesses over a hidden span miss the bone found at either end
        by more than this, they are dropped for the found bones' steady turn
        (:mod:`~toonmotion.capture.track_gaps`).
    figure_slack : float
        Pixels, >= 0: a point within this of the figure's mask is on the figure
        (:mod:`~toonmotion.capture.track_figure`).
    pull_reach : float
        Times a joint's limit (the farthest it may move), >= 1: a hidden joint off the figure by
        more than its limit is moved that far towards the figure when the figure is within this
        many limits (farther, it is left where it is carried). Moved only onto a figure within
        its limit, a hand that went behind the body stayed on the paper 30 px off for 10 frames;
        the flat renders restarted every 30 frames went 179.6 -> 176.9 px summed on twos.
    light_tolerance : float
        Grey levels, >= 0: a frame is relit only where matching its light moves a colour between
        its quartiles by more than this (:mod:`~toonmotion.capture.track_light`).
    min_spread : float
        Grey levels, >= 0: a channel whose quartiles lie closer than this has no contrast to
        match, and is scaled to the reference's median.
    light_border : float
        Of the shorter side, 0 to 1: the light is read off a band this wide round the border.
        Read off the whole frame it moved with a drawing swung across it, and two clips of the
        drawings' footage went from 2.0 and 1.3 px to 42 and 35.
    light_samples : int
        About this many pixels of the band are read, >= 1.

    Examples
    --------
    >>> ClipTuning().coast_steps, ClipTuning(held_level=24).held_level
    (4, 24.0)
    """

    coast_steps: int = whole(4)
    held_level: float = at_least(0.0, 16.0)
    held_fraction: float = share(1e-4)
    trusted: float = at_least(0.0, 0.1)
    figure_slack: float = at_least(0.0, 2.0)
    pull_reach: float = at_least(1.0, 4.0)
    light_tolerance: float = at_least(0.0, 6.0)
    min_spread: float = at_least(0.0, 8.0)
    light_border: float = share(0.15)
    light_samples: int = whole(8000)
