"""Where the joint tracker looks next: constant-acceleration prediction (thesis eq. 4.4), the
turn of each joint's rectangle with its bone (eq. 4.2), where a hidden joint is put, and which
frames only repeat the drawing before (animation on twos), which the prediction steps over.

Arrays are the tracker's: ``P`` ``(T, k, 2)`` joint centres, (x, y) pixels, y down, NaN at frames
not tracked; ``C`` ``(T, k)`` confidence; time in frames (the thesis' ``tau`` is 1).
``docs/capture.md`` (tracking) gives the reasons for each choice.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.rig.skeleton import MIN_BONE_LENGTH

Points = NDArray[np.float64]


def predict(P: Points, C: NDArray[np.float64], frames: NDArray[np.int_], history: NDArray[np.int_], *,
            tuning: ClipTuning | None = None, match: MatchTuning | None = None) -> tuple[Points, Points]:
    """Eq. 4.4 from each joint's last (up to) three positions, and where a hidden root coasts to.

    Parameters
    ----------
    P : (T, k, 2) float
        Joint centres; ``frames`` are tracked.
    C : (T, k) float
        Confidence of each joint-frame.
    frames : (n,) int
        The last (up to) ``tuning.coast_steps + 1`` tracked frames that showed a new drawing, oldest
        first; held frames (animation on twos) are left out, so a step is one drawing to the next.
    history : (k,) int
        The frame each joint's history starts at (where tracking started or it was corrected):
        its velocity there is 0.
    tuning, match : ClipTuning, MatchTuning, optional
        The clip's ``coast_steps``, and the matching's ``visible_confidence``, below which a
        position is a guess made while the joint was hidden; default their defaults.

    Returns
    -------
    predicted : (k, 2) float
        ``p + v + a / 2`` from the last three positions; ``p + v`` from two, ``p`` from one.
        A position guessed while hidden gives no acceleration, and the step from the last guess
        to a re-found joint is not a velocity: the guesses' velocity carries on.
    coast : (k, 2) float
        Where each joint goes if it hides at ``t``: on at its mean velocity over its last (up
        to) ``tuning.coast_steps`` visible steps, less swayed than one step by a rectangle already
        partly covered, and without acceleration.
    """
    steps = (ClipTuning() if tuning is None else tuning).coast_steps
    bar = (MatchTuning() if match is None else match).visible_confidence
    frames = np.asarray(frames)[-(steps + 1):]
    k, n = len(history), len(frames)
    mine = frames[:, None] >= history  # (n, k): frames in each joint's history
    seen = mine.sum(axis=0)[:, None]
    visible = (C[frames] >= bar) & mine
    v1, v2, v3 = (visible[-i][:, None] if i <= n else np.zeros((k, 1), bool) for i in (1, 2, 3))
    p1 = P[frames[-1]]
    p2 = np.where(seen >= 2, P[frames[max(n - 2, 0)]], p1)
    p3 = np.where(seen >= 3, P[frames[max(n - 3, 0)]], p2)
    v = np.where(v1 & ~v2 & (seen >= 2), p2 - p3, p1 - p2)
    a = np.where(v1 & v2 & v3, v - (p2 - p3), 0.0)
    steps = np.cumprod(visible[::-1], axis=0).sum(axis=0) - 1  # visible steps ending at the last
    mean = (p1 - P[frames[n - 1 - np.maximum(steps, 0)], np.arange(k)]) / np.maximum(steps, 1)[:, None]
    coast = np.where(v1 & (steps >= 1)[:, None], mean, v)
    return p1 + v + a / 2, p1 + coast


def turns(before: Points, after: Points, parents: NDArray[np.int_], rotating: bool) -> NDArray[np.float64]:
    """``(k,)`` signed angle (radians) each bone, parent to joint, turns from ``before`` to ``after``.

    ``before`` and ``after`` are ``(k, 2)`` joint centres. The angle is ``atan2(cross, dot)`` of
    the two bone vectors; 0 for roots (``parents`` -1), bones shorter than ``MIN_BONE_LENGTH``
    and with ``rotating`` False.

    >>> turns(np.array([[0.0, 0.0], [10.0, 0.0]]), np.array([[0.0, 0.0], [0.0, 10.0]]),
    ...       np.array([-1, 0]), True).round(6).tolist()
    [0.0, 1.570796]
    """
    out = np.zeros(len(parents))
    child = np.flatnonzero(parents >= 0) if rotating else np.array([], dtype=int)
    if child.size:
        a = before[child] - before[parents[child]]
        b = after[child] - after[parents[child]]
        cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        dot = (a * b).sum(axis=1)
        ok = (np.hypot(*a.T) > MIN_BONE_LENGTH) & (np.hypot(*b.T) > MIN_BONE_LENGTH)
        out[child] = np.where(ok, np.arctan2(cross, dot), 0.0)
    return out


def hidden_at(P: Points, t: int, m: int, coast: Points, hangs_from: NDArray[np.int_]) -> Points:
    """Where hidden joint ``m`` is put at frame ``t``: carried by its parent, else coasting.

    Parameters
    ----------
    P : (T, k, 2) float
        Joint centres; frame ``t - 1`` is tracked, and so is ``t`` for joints before ``m``
        (parents come first).
    t, m : int
        The frame and the joint.
    coast : (2,) float
        Where the joint coasts to (from :func:`predict`), taken for a root.
    hangs_from : (k,) int
        Each joint's parent, -1 for a root.

    Returns
    -------
    (2,) float
        A joint with a parent keeps its last offset from it, turned as the parent's own bone
        turned this frame (a hidden hand goes where its elbow takes it). Coasting on its own
        velocity would run away over a long occlusion (hundreds of pixels on the shared walking
        clips).
    """
    p = hangs_from[m]
    if p < 0:
        return coast
    offset = P[t - 1, m] - P[t - 1, p]
    g = hangs_from[p]
    turn = None if g < 0 else bone_turn(P[t - 1, p] - P[t - 1, g], P[t, p] - P[t, g])
    if turn is not None:
        # Turned by hand, not with kinematics.rotate: this runs per joint and frame.
        c, s = math.cos(turn), math.sin(turn)
        offset = np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
    return P[t, p] + offset


def bone_turn(before: Points, after: Points) -> float | None:
    """The signed angle (radians) from one bone vector ``(2,)`` to another, as :func:`turns` takes
    it for each bone; None if either is no longer than ``MIN_BONE_LENGTH``.

    >>> round(bone_turn(np.array([10.0, 0.0]), np.array([0.0, 10.0])), 6), bone_turn(np.zeros(2), np.ones(2))
    (1.570796, None)
    """
    if not (np.hypot(*before) > MIN_BONE_LENGTH and np.hypot(*after) > MIN_BONE_LENGTH):
        return None
    return math.atan2(before[0] * after[1] - before[1] * after[0], float(before @ after))


def is_held(image: NDArray[np.uint8], previous: NDArray[np.uint8], *,
            work: NDArray[np.uint8] | None = None, tuning: ClipTuning | None = None) -> bool:
    """Whether ``image`` repeats ``previous`` (both ``(h, w, 3)`` uint8) up to noise: the same
    drawing held another frame, as animation on twos or threes does (fewer than
    ``tuning.held_fraction`` of the values differ by more than ``tuning.held_level``). ``work``, an
    array of their shape and type, is worked in if given (a tracker asks every frame: a frame-sized array made
    afresh is mapped in from the system page by page, nine tenths of the time here).

    >>> still = np.full((40, 40, 3), 128, np.uint8)
    >>> moved = still.copy(); moved[10:20, 10:12] = 0
    >>> is_held(still + 3, still), is_held(moved, still, work=np.empty_like(still))
    (True, False)
    """
    h, w = image.shape[:2]
    diff = cv2.absdiff(image, previous, dst=work).reshape(h, -1)
    tuning = ClipTuning() if tuning is None else tuning
    changed = cv2.countNonZero(cv2.threshold(diff, tuning.held_level, 255, cv2.THRESH_BINARY, dst=diff)[1])
    return changed <= tuning.held_fraction * diff.size
