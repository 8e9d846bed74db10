"""The whole-sequence pass of the joint tracker: hidden spans re-placed once both their ends are
known.

Frame by frame, a hidden joint can only be guessed from the past: carried by its parent, or by
the joints below it (:mod:`~toonmotion.capture.tracker`). Once the whole clip is tracked, a span
where a joint was hidden between two frames where it was found has a known end as well as a known
start, and the guesses inside it can be bent to meet both: for a joint with a parent, its bone
(the offset from the parent, as an angle and a length) is interpolated linearly in time from the
frame before the span to the frame after it; a root's guesses are corrected by the mismatch at the
span's end, growing linearly across the span (the correction of a smoother with a random-walk
model). Spans at the end of the clip, where the joint is never found again, keep their guesses,
and joints keep their confidence (below ``VISIBLE_CONFIDENCE``): they are still guesses, only
better ones.

Arrays are the tracker's: ``P`` ``(T, k, 2)`` joint centres, ``C`` ``(T, k)`` confidence.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.template_match import VISIBLE_CONFIDENCE


def fill_hidden_spans(P: NDArray[np.float64], C: NDArray[np.float64], parents: NDArray[np.int_],
                      tracked: NDArray[np.bool_], held: NDArray[np.bool_]) -> NDArray[np.float64]:
    """``P`` with every hidden span that has a found frame on both sides re-placed (module
    docstring); joints are taken parents first, so a child's bone is read off its parent's
    re-placed positions.

    Parameters
    ----------
    P : (T, k, 2) float
    C : (T, k) float
    parents : (k,) int
        Each joint's parent, -1 for a root; parents come before their children.
    tracked : (T,) bool
        Frames tracked; spans do not cross frames that were not.
    held : (T,) bool
        Frames that repeat the one before: they are given the positions of the frame they repeat.

    Returns
    -------
    (T, k, 2) float
        A new array.

    >>> P = np.array([[[0.0, 0.0]], [[9.0, 9.0]], [[9.0, 9.0]], [[3.0, 0.0]]])
    >>> C = np.array([[1.0], [0.1], [0.1], [1.0]])
    >>> fill_hidden_spans(P, C, np.array([-1]), np.ones(4, bool), np.zeros(4, bool))[:, 0].tolist()
    [[0.0, 0.0], [7.0, 6.0], [5.0, 3.0], [3.0, 0.0]]
    """
    out = np.array(P, dtype=float)
    drawings = np.flatnonzero(tracked & ~held)
    for m in range(out.shape[1]):
        found = C[drawings, m] >= VISIBLE_CONFIDENCE
        for a, b in _spans(found):
            before, inside, after = drawings[a], drawings[a + 1:b], drawings[b]
            if not (tracked[before:after + 1]).all():
                continue
            s = ((inside - before) / (after - before))[:, None]
            g = parents[m]
            if g < 0:
                # The guesses, bent to meet the found end: the mismatch there grows across the span.
                last = out[inside[-1], m]
                step = last - out[inside[-2], m] if len(inside) > 1 else 0.0
                out[inside, m] += s * (out[after, m] - (last + step))
            else:
                start = complex(*(out[before, m] - out[before, g]))
                end = complex(*(out[after, m] - out[after, g]))
                turn = np.angle(end / start) if start != 0 and end != 0 else 0.0
                length = abs(start) + s[:, 0] * (abs(end) - abs(start))
                bone = length * np.exp(1j * (np.angle(start) + s[:, 0] * turn))
                out[inside, m] = out[inside, g] + np.column_stack([bone.real, bone.imag])
    held_frames = np.flatnonzero(held)
    for t in held_frames:  # in order, so a drawing held three frames passes its place on
        out[t] = out[t - 1]
    return out


def _spans(found):
    """``(a, b)`` index pairs into ``found`` with ``found[a]`` and ``found[b]`` true and every
    index between them false (at least one)."""
    hits = np.flatnonzero(found)
    return [(int(a), int(b)) for a, b in zip(hits[:-1], hits[1:], strict=True) if b - a > 1]
