"""Joints out of sight in the joint tracker (thesis 4.4): where a hidden joint is carried (by its
parent, a root on its velocity, :func:`place_hidden`), how long each has been hidden
(:func:`hidden_for`), and how far a bone may reach from its parent (:func:`longest_bones`). A
joint is hidden where its confidence is under ``visible``, the run's
:attr:`~toonmotion.capture.match_tuning.MatchTuning.visible_confidence`."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.track_prediction import hidden_at


def place_hidden(P, t, coast, seen, hangs_from, reach):
    """Put every joint not found, parents first: at the mean of where its parent carries it and
    where its children found put it (for a root, the joints found anywhere below it,
    :func:`moves_below`); a root with neither coasts.
    None moves farther than its ``reach`` (pixels, ``(k,)``) beyond its parent's own move (its
    own move, for a root): a bone seen end-on that turns half round in one frame would otherwise
    fling it across the figure."""
    moves, direct = moves_below(P, t, seen, hangs_from), moves_below(P, t, seen, hangs_from, direct=True)
    for m in range(len(seen)):
        if seen[m]:
            continue
        g = hangs_from[m]
        # Only children found count, but for a root: a grandchild's move is mostly its parent's
        # turn about the joint (a hand sweeping round a shoulder).
        guess = carried_by_parent(P, t, m, coast, hangs_from, direct[m] if g >= 0 else moves[m])
        carried = P[t - 1, m] + (P[t, g] - P[t - 1, g] if g >= 0 else 0.0)
        step = (coast[m] if guess is None else guess) - carried
        length = float(np.hypot(*step))
        P[t, m] = carried + (step if length <= reach[m] else step * (reach[m] / length))


def carried_by_parent(P, t, m, coast, hangs_from, below):
    """Where joint ``m``'s neighbours carry it at ``t``: the mean of where its parent carries it
    (:func:`~toonmotion.capture.track_prediction.hidden_at`; a root has none) and where ``below``,
    its move by the joints below it (NaN: none), puts it; None with neither."""
    guesses = [] if hangs_from[m] < 0 else [hidden_at(P, t, m, coast[m], hangs_from)]
    if np.isfinite(below).all():
        guesses.append(P[t - 1, m] + below)
    return np.mean(guesses, axis=0) if guesses else None


def moves_below(P: NDArray[np.float64], t: int, seen: NDArray[np.bool_], hangs_from: NDArray[np.int_],
                *, direct: bool = False) -> NDArray[np.float64]:
    """How far each joint moved from ``t - 1`` to ``t`` by the joints hanging from it, ``(k, 2)``:
    the mean move of its children, a child found at ``t`` (``seen``) by its own move, one not
    found by its children's, recursively (with ``direct``, not at all); NaN where no joint below
    it (no child, with ``direct``) was found."""
    k = len(seen)
    # Plain Python over the joints: this runs three times a frame, and numpy's overhead on arrays
    # of a few joints was a tenth of the tracking time.
    found, parents = seen.tolist(), hangs_from.tolist()
    steps: list[list[float]] = (P[t] - P[t - 1]).tolist()
    kids: list[list[int]] = [[] for _ in range(k)]
    for m, g in enumerate(parents):
        if g >= 0:
            kids[g].append(m)
    moves: list[list[float] | None] = [None] * k
    for m in range(k - 1, -1, -1):  # children come after their parents
        ways = [steps[c] if found[c] else (None if direct else moves[c]) for c in kids[m]]
        below = [b for b in ways if b is not None and math.isfinite(b[0]) and math.isfinite(b[1])]
        if below:
            moves[m] = [sum(b[0] for b in below) / len(below), sum(b[1] for b in below) / len(below)]
    return np.array([[math.nan, math.nan] if move is None else move for move in moves])


def hidden_for(C: NDArray[np.float64], drawings: list[int], history: NDArray[np.int_], *,
               visible: float) -> NDArray[np.int_]:
    """For each joint, the drawings it has been hidden for up to ``drawings[-1]`` (0: visible),
    counting only frames in its history (from ``history``)."""
    hidden = (C[drawings] < visible) & (np.array(drawings)[:, None] >= history)
    return np.cumprod(hidden[::-1], axis=0).sum(axis=0)


def longest_bones(P: NDArray[np.float64], C: NDArray[np.float64], drawings: list[int],
                  hangs_from: NDArray[np.int_], *, visible: float) -> NDArray[np.float64]:
    """Each joint's bone (from its parent) at its longest over ``drawings``, pixels; 0 for roots."""
    longest = np.zeros(len(hangs_from))
    for s in drawings:
        lengthen(longest, P[s], C[s], hangs_from, visible=visible)
    return longest


def lengthen(longest: NDArray[np.float64], points: NDArray[np.float64], confidence: NDArray[np.float64],
             hangs_from: NDArray[np.int_], *, visible: float) -> None:
    """Raise ``longest`` to the bones seen (both ends visible) at ``points``."""
    child = np.flatnonzero(hangs_from >= 0)
    shows = confidence >= visible
    seen = child[shows[child] & shows[hangs_from[child]]]
    length = np.hypot(*(points[seen] - points[hangs_from[seen]]).T)
    longest[seen] = np.maximum(longest[seen], length)
