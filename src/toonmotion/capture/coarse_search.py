"""Finding a hidden joint again (thesis 4.4): a coarse search at half resolution, round where it
was predicted (:func:`locate`, at a few turns) or round its parent within its bone's reach
(:func:`search_round`). It only says where to look again; :func:`toonmotion.capture.template_match.match`
places the joint there."""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.joint_plan import BoneRule, JointPlan, Templates, bone_cost
from toonmotion.capture.patches import (
    confidence,
    patches,
    sample,
    ssd_at,
)
from toonmotion.capture.track_figure import figure_cells, on_figure


def locate(small: NDArray[np.uint8], templates: Templates, centre: NDArray[np.float64], angle: float,
           joint: JointPlan, radius: float, bone: BoneRule | None = None,
           figure: NDArray[np.uint8] | None = None, turns: tuple[float, ...] | None = None
           ) -> tuple[NDArray[np.float64], float, float]:
    """Look for a hidden joint at half resolution, up to ``radius`` pixels (full resolution) from
    ``centre``: the anchor's coarse template is matched in ``small`` (the frame after
    ``cv2.pyrDown``) at the rectangle's angle turned by each of ``turns`` (radians; default the
    ``coarse_turns`` of the plan's :class:`~toonmotion.capture.match_tuning.MatchTuning`), by eq.
    4.6's mixed cost with ``joint``'s colour weight, ``w_beta = 1 / radius^2`` and the kinematic
    term (``bone``), among the plain cells if there are any (as
    :func:`~toonmotion.capture.template_match.match`). Only where to look again: the place is to be
    refined by :func:`~toonmotion.capture.template_match.match`.

    Returns
    -------
    xy : (2,) float
        The best place, full-resolution (x, y) pixels, to about a pixel.
    confidence : float
        The coarse match's confidence.
    angle : float
        The rectangle's angle there, radians.
    """
    turns = joint.tuning.coarse_turns if turns is None else turns
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
    plain_ssd = ssd_at(joint.tuning.update_confidence, (tw, th), joint.tuning)
    centre = np.asarray(centre, dtype=float)
    # Pixel centres: full-resolution x is half-resolution 2 x + 0.5.
    middle = (centre - 0.5) / 2
    angles = [angle + turn for turn in turns]
    size = (tw + 2 * R, th + 2 * R)
    windows = [sample(small, middle, a, size) for a in angles]
    ssd = np.stack([cv2.matchTemplate(window, template, cv2.TM_SQDIFF) for window in windows])
    cost = w_alpha * ssd + coarse_geometric(R, radius)
    if bone is not None:
        cost += bone_cost(centre, angles, R, bone, step=2.0)
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
        confidences.append(confidence(float(turn_ssd[i, j]), (tw, th), joint.tuning))
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
    again, to be refined by :func:`~toonmotion.capture.template_match.match`. With ``figure`` (full
    resolution), places off the figure are left out. With ``by_look`` (a joint with a texture of its
    own, :func:`~toonmotion.capture.patches.is_textured`), the places are picked by their look alone
    and ordered by that cost.

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
    cut = patches(small, (xy - 0.5) / 2, angles, (tw, th))
    d = cut - template[None]
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
    return [(xy[i], confidence(float(ssd[i]), (tw, th), joint.tuning), float(angles[i])) for i in picked]
