"""Matching a joint's templates in a frame: the colour search of the joint tracker (thesis 4.4).

A joint's rectangle is matched by sampling a search window round its predicted centre, turned
by the rectangle's angle, and finding its templates in it with ``cv2.matchTemplate``
(``TM_SQDIFF``, RGB sum of squared differences, eq. 4.1). The mixed cost of eq. 4.6 picks a
whole-pixel cell; the colour cost alone then places the match to sub-pixel precision. Each joint
keeps two templates, an *anchor* and a *latest*, matched every frame. ``docs/capture.md``
(tracking) gives the reasons for each choice.

Coordinates are (x, y) pixels, y down; the pixel in row ``i``, column ``j`` is centred on
``(j, i)``. Patches and windows are ``(h, w, 3)`` float32 in the rectangle's own frame: patch
pixel ``(u, v)`` is the image at ``centre + rotation(angle) (u - (w-1)/2, v - (h-1)/2)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

# Confidence is exp(-d^2 / (2 CONFIDENCE_SCALE^2)), d the RMS difference per channel (grey levels).
CONFIDENCE_SCALE = 30.0

# Cells matching at least this confidently are plain; a match this confident, where both templates
# agree, re-cuts the joint's latest template.
UPDATE_CONFIDENCE = 0.8

# A joint whose best match is less confident than this is hidden: it is carried by its parent
# (a root coasts on its velocity) and its templates are left alone.
VISIBLE_CONFIDENCE = 0.5

# The anchor's and the latest template's matches agree when they lie within this many pixels.
DRIFT_TOLERANCE = 2.0

# A turning rectangle matching less confidently than this at its predicted angle tries TURNS too
# (radians).
TURN_CONFIDENCE = 0.6
TURNS = tuple(math.radians(sign * step) for step in (5, 10, 15) for sign in (1, -1))

_WARP = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP

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
    geometric : (2R+1, 2R+1) float
        ``w_beta`` times the squared offset of each cell from the window centre.
    plain : float
        The SSD of a match with confidence :data:`UPDATE_CONFIDENCE`.
    tie : float
        SSDs closer than this are equal: half a grey level per pixel and channel.
    """

    size: tuple[int, int]
    radius: int
    w_alpha: float
    w_beta: float
    parent: int
    hangs_from: int
    geometric: NDArray[np.float64]
    plain: float
    tie: float


def plan_joint(size: tuple[int, int], r: float, w_alpha: float, w_beta: float, parent: int,
               hangs_from: int) -> JointPlan:
    """A :class:`JointPlan` for a ``size`` template searched within radius ``r`` (pixels, >= 1)."""
    R = int(math.floor(r))
    offsets = np.arange(-R, R + 1, dtype=float) ** 2
    return JointPlan(size=size, radius=R, w_alpha=w_alpha / (size[0] * size[1]), w_beta=w_beta,
                     parent=parent, hangs_from=hangs_from,
                     geometric=w_beta * (offsets[:, None] + offsets[None, :]),
                     plain=ssd_at(UPDATE_CONFIDENCE, size), tie=0.25 * 3 * size[0] * size[1])


@dataclass
class Templates:
    """A joint's anchor (cut where tracking started) and latest (last confident match).

    Both ``(th, tw, 3)`` float32, in the rectangle's own frame (see :func:`sample`); the same
    array while the latest has not been re-cut.
    """

    anchor: Patch
    latest: Patch

    @classmethod
    def cut(cls, image: NDArray[np.uint8], centre: NDArray[np.float64], angle: float,
            size: tuple[int, int]) -> Templates:
        """Both templates cut from ``image`` at ``centre``, turned by ``angle`` radians."""
        patch = sample(image, centre, angle, size)
        return cls(anchor=patch, latest=patch)


def match(image: NDArray[np.uint8], templates: Templates, predicted: NDArray[np.float64], angle: float,
          joint: JointPlan) -> tuple[NDArray[np.float64], float, bool]:
    """Match a joint's templates round ``predicted``, its rectangle turned by ``angle`` radians.

    A rectangle that turns and matches less confidently than :data:`TURN_CONFIDENCE` also tries
    :data:`TURNS` more; the most confident match is kept.

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

    Returns
    -------
    xy : (2,) float
        The centre found, (x, y) pixels, sub-pixel.
    confidence : float in [0, 1]
    agree : bool
        Whether the anchor's match lies within :data:`DRIFT_TOLERANCE` of the latest's.
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
    """:func:`match` at one angle: the anchor's match where it is trusted, else the latest's."""
    R, (tw, th) = joint.radius, joint.size
    window = sample(image, predicted, angle, (tw + 2 * R, th + 2 * R))
    latest = _best(window, templates.latest, joint)
    (offset, confidence), agree = latest, True
    if templates.anchor is not templates.latest:
        anchor = _best(window, templates.anchor, joint)
        agree = bool(np.hypot(*(anchor[0] - latest[0])) <= DRIFT_TOLERANCE)
        if anchor[1] >= latest[1] or (agree and anchor[1] >= VISIBLE_CONFIDENCE):
            offset, confidence = anchor
    # The offset, in the window's frame, turned into the image's (a per-joint hot path: by hand).
    c, s = math.cos(angle), math.sin(angle)
    return predicted + [c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]], confidence, agree


def _best(window, template, joint):
    """Best match of ``template`` in ``window``: sub-pixel ``(dx, dy)`` from the centre, confidence.

    The mixed cost picks the cell among the plain ones, if any; the colour cost alone then
    places the match: a descent to its local minimum and a parabola through it in x and in y.
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
    return np.array([j - R + dx, i - R + dy]), confidence(exact, joint.size)


def _descend(cost, i, j, tie):
    """From cell ``(i, j)``, step to the lowest of the 8 neighbours while ``cost`` drops by > ``tie``."""
    while True:
        i0, j0 = max(i - 1, 0), max(j - 1, 0)
        block = cost[i0:i + 2, j0:j + 2]
        a, b = np.unravel_index(int(np.argmin(block)), block.shape)
        if not block[a, b] < cost[i, j] - tie:
            return i, j
        i, j = i0 + a, j0 + b


def confidence(ssd: float, size: tuple[int, int]) -> float:
    """Confidence of a match whose sum of squared RGB differences over a ``size`` rectangle is ``ssd``.

    ``exp(-d^2 / (2 CONFIDENCE_SCALE^2))``, ``d`` the root mean square difference per channel.

    >>> round(confidence(20.0**2 * 3 * 4, (2, 2)), 2)  # 20 grey levels off in every channel
    0.8
    """
    return math.exp(-ssd / (size[0] * size[1] * 3) / (2 * CONFIDENCE_SCALE**2))


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


def sample(image: NDArray[np.uint8], centre: NDArray[np.float64], angle: float,
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
