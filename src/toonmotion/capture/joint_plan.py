"""What the joint tracker keeps for each joint over a run (thesis 4.4): its plan (template size,
search radius, eq. 4.6's weights, the turns it tries), its templates, and the kinematic rule of
its bone (:class:`BoneRule`, :func:`bone_cost`). A plan carries the run's
:class:`~toonmotion.capture.match_tuning.MatchTuning` to every match made by it."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.patches import (
    Patch,
    sample,
    ssd_at,
)


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
        The turns (radians) tried when the predicted angle matches badly (see
        :func:`~toonmotion.capture.template_match.match`).
    geometric : (2R+1, 2R+1) float
        ``w_beta`` times the squared offset of each cell from the window centre.
    plain : float
        The SSD of a match with confidence ``tuning.update_confidence``.
    tie : float
        SSDs closer than this are equal: half a grey level per pixel and channel.
    alike : float
        Cells within this SSD of the match's match as well as it: ``tuning.alike_level`` per pixel
        and channel.
    visible : float
        The SSD of a match with confidence ``tuning.visible_confidence``.
    tuning : MatchTuning
        The run's matching tuning, which the matches made by this plan read.
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
    tuning: MatchTuning


def plan_joint(size: tuple[int, int], r: float, w_alpha: float, w_beta: float, parent: int,
               hangs_from: int, pace: float = 1.0, tuning: MatchTuning | None = None) -> JointPlan:
    """A :class:`JointPlan` for a ``size`` template searched within radius ``r`` (pixels, >= 1),
    trying ``tuning.turns`` times ``pace`` (the frames a step spans: 2 after a drawing held on
    twos); ``tuning`` default its defaults."""
    tuning = MatchTuning() if tuning is None else tuning
    R = int(math.floor(r))
    offsets = np.arange(-R, R + 1, dtype=float) ** 2
    return JointPlan(size=size, radius=R, w_alpha=w_alpha / (size[0] * size[1]), w_beta=w_beta,
                     parent=parent, hangs_from=hangs_from, turns=tuple(pace * turn for turn in tuning.turns),
                     geometric=w_beta * (offsets[:, None] + offsets[None, :]),
                     plain=ssd_at(tuning.update_confidence, size, tuning), tie=0.25 * 3 * size[0] * size[1],
                     alike=tuning.alike_level**2 * 3 * size[0] * size[1],
                     visible=ssd_at(tuning.visible_confidence, size, tuning), tuning=tuning)


@dataclass(frozen=True)
class Context:
    """A joint's wider view: ``patch`` ``(s, s, 3)`` float32 at pyramid level ``level``, in the
    rectangle's own frame (:func:`~toonmotion.capture.patches.sample`); cut by
    :func:`~toonmotion.capture.template_context.cut_context`."""

    patch: Patch
    level: int


@dataclass
class Templates:
    """A joint's anchor (cut where tracking started) and latest (last confident match).

    Both ``(th, tw, 3)`` float32, in the rectangle's own frame (see
    :func:`~toonmotion.capture.patches.sample`); the same array while the latest has not been
    re-cut. ``coarse`` is the anchor at half resolution (``cv2.pyrDown``), for
    :func:`~toonmotion.capture.coarse_search.locate`. ``context``, the wider view cut with the
    anchor (:mod:`~toonmotion.capture.template_context`), if one was.
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


def bone_cost(predicted, angle, R, bone, step=1.0):
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


class Plans:
    """Each joint's :class:`~toonmotion.capture.joint_plan.JointPlan`, and its plan with the
    search widened, and with its colour weighed more: ``plans(m)``, ``plans(m, factor)``,
    ``plans(m, factor, colour)`` (cached).

    Parameters
    ----------
    sizes : (k, 2) int
        Template widths and heights, whole pixels (at least 1).
    parents : (k,) int
        Each joint's parent, -1 for a root.
    radius : (k,) float
        Each joint's search radius, pixels.
    w_alpha : float
    w_beta : float or None
        As :class:`~toonmotion.capture.track_settings.TrackSettings`; None: ``1 / r^2``.
    rotate : bool
        Rectangles turn with their bones.
    frame_shape : tuple
        ``(h, w, ...)`` of the frames: no search goes wider than the frame.
    tuning : MatchTuning, optional
        The matching's tuning, carried by every plan; default its defaults.

    Attributes
    ----------
    parents : (k,) int
        The joint whose bone turns each rectangle, -1 for none.
    hangs_from : (k,) int
        Each joint's parent in the skeleton, -1 for a root.
    tuning : MatchTuning
    """

    def __init__(self, sizes: Sequence[tuple[int, int]], parents: ArrayLike, radius: ArrayLike, *,
                 w_alpha: float, w_beta: float | None, rotate: bool, frame_shape: tuple[int, ...],
                 tuning: MatchTuning | None = None) -> None:
        self._w_alpha, self._w_beta = w_alpha, w_beta
        self.tuning = MatchTuning() if tuning is None else tuning
        self._widest = math.hypot(frame_shape[0], frame_shape[1])
        radii = np.asarray(radius, dtype=float)
        self._joints = [((int(w), int(h)), float(r)) for (w, h), r in zip(sizes, radii, strict=True)]
        self.hangs_from = np.asarray(parents, dtype=int)
        self.parents = self.hangs_from if rotate else np.full(len(self.hangs_from), -1)
        self._cache: dict[tuple[int, float, float], JointPlan] = {}

    def __len__(self) -> int:
        return len(self._joints)

    def __call__(self, m: int, factor: float = 1.0, colour: float = 1.0) -> JointPlan:
        if (m, factor, colour) not in self._cache:
            size, r = self._joints[m]
            r = min(r * factor, self._widest)
            w_beta = (1.0 / r) ** 2 if self._w_beta is None else self._w_beta
            parent, hangs_from = int(self.parents[m]), int(self.hangs_from[m])
            self._cache[m, factor, colour] = plan_joint(size, r, colour * self._w_alpha, w_beta, parent,
                                                        hangs_from, pace=factor, tuning=self.tuning)
        return self._cache[m, factor, colour]
