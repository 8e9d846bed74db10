"""The tuning of how the figure is found in footage and how big a rectangle each suggested joint
gets (:mod:`~toonmotion.capture.foreground`, :mod:`~toonmotion.capture.setup`): the foreground's
threshold, the cleaning of its masks, a frame drawn round the picture, and the suggested
rectangles' sizes. :class:`FigureTuning`, given as ``tuning=`` to the functions that find the
figure or suggest joints (:func:`~toonmotion.capture.footage.suggest_joints` and the rest), and
as ``TrackSettings(cutout=...)`` for the figure the tracker holds joints to."""

from __future__ import annotations

from dataclasses import dataclass

from toonmotion.capture.track_checks import Tuning, above, at_least, check_order, share, whole
from toonmotion.capture.track_scale import WORKING_SIDE


@dataclass(frozen=True)
class FigureTuning(Tuning):
    """How the figure is cut out of the footage and its joints' rectangles suggested (thesis 4.3).

    The defaults are the library's. The measurements given are those on record (the comments the
    values were module constants with, and ``docs/capture.md``, "Foreground and suggested
    joints"); where none is, it says so. Each value's range is checked when the tuning is made
    (:class:`~toonmotion.capture.track_checks.Tuning`), and each range's low end must be at most
    its high end.

    Attributes
    ----------
    threshold_low : float
        Colour distance, >= 0: the foreground threshold's lowest. On a flat colour it is the
        summed channel difference from the colour (0 to 765) and the threshold is the border's own
        spread (its 99th percentile) within the range; on a background image, the RGB distance
        (0 to 441) and Otsu's threshold within the range. 20 stays above video compression noise;
        digital art on white gets it, paper photographed under uneven light about 55. No
        measurement of another low end on record.
    threshold_high : float
        Colour distance, >= ``threshold_low``: the threshold's highest; border pixels farther from
        a flat colour than this are not paper (a frame round the picture, the figure cut by the
        edge) and do not count. 100 keeps a figure close in colour to its background from being
        thrown away wholesale when the distances are spread wide. Before such border pixels were
        left out, a dark frame round the bundled character took the threshold to 100 and lost its
        light fills (IoU 0.961 -> 0.949).
    clean_fraction : float
        0 to 1: specks (8-connected parts) smaller than this share of the largest part, and holes
        smaller than this share of the foreground, are cleaned away. No measurement on record.
    frame_fill : float
        0 to 1: a part of the mask touching all four sides of the picture while covering less than
        this share of it is a frame drawn round the picture, not the figure. No measurement on
        record.
    frame_line : float
        0 to 1: lines along an edge that are at least this share figure, up to ``frame_depth``
        deep, are a frame's (one the figure touches) and are cleared. No measurement on record.
    frame_depth : float
        Of the picture's smaller side, 0 to 1: see ``frame_line``. No measurement on record.
    size_low : float
        Pixels, > 0: a suggested rectangle (a square twice the figure's thickness at the joint) is
        at least this on a frame up to ``frame_side``, so that a small joint still has some
        texture. No measurement on record.
    size_high : float
        Pixels, >= ``size_low``: and at most this, so that a big joint does not drag in much of
        the background. No measurement on record.
    frame_side : float
        Pixels, >= 1: the size range is for frames up to this on their larger side, and doubles
        each time the frame does beyond it; the default is the tracker's working side
        (:data:`~toonmotion.capture.track_scale.WORKING_SIDE`), where it tracks such frames halved
        and the rectangles are within the range again. With the range's cap at 48 px on the
        drawings' footage doubled (5 clips), the windows were too small for the motion: 102.5 px
        summed, against 32.8 at the footage's own size.
    thickness_reach : int
        Pixels, >= 0: the figure's thickness at a joint is the largest distance to its outline
        within this of the joint (a branch's end point sits near the tip, where the figure is
        thinnest). No measurement on record.

    Examples
    --------
    >>> FigureTuning().size_high, FigureTuning(size_low=4, size_high=32).size_low
    (48.0, 4.0)
    """

    threshold_low: float = at_least(0.0, 20.0)
    threshold_high: float = at_least(0.0, 100.0)
    clean_fraction: float = share(0.01)
    frame_fill: float = share(0.25)
    frame_line: float = share(0.9)
    frame_depth: float = share(0.03)
    size_low: float = above(0.0, 8.0)
    size_high: float = above(0.0, 48.0)
    frame_side: float = at_least(1.0, WORKING_SIDE)
    thickness_reach: int = whole(3, least=0)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_order(self, "threshold_low", "threshold_high")
        check_order(self, "size_low", "size_high")
