"""The whole-sequence pass of the joint tracker: hidden spans re-placed once both their ends are
known.

Frame by frame, a hidden joint can only be guessed from the past: carried by its parent, or by
the joints below it (:mod:`~toonmotion.capture.track_search`). Once the whole clip is tracked, a
span where a joint was hidden between two frames where it was found has a known end as well as a
known start, and the guesses inside it can be bent to meet both. For a joint with a parent, its
guessed bones (offsets from the parent) are turned and scaled by a blend, linear in time, of the
turn and scale that take the guesses, carried on one frame each way as they went, to the bones
found before and after the span, when they meet both within a tenth of the bone
(``ClipTuning.trusted``): guesses that were right (a hand carried by an elbow that turned) stay as they
were. Guesses that miss are dropped: the bone found before the span turns and stretches steadily
into the bone found after it (exact for a limb turning steadily about a still joint). A root
with children found at every drawing of its span is put where they hold it: each one's bone to
the root turns and stretches steadily from the bone found before the span into the one found
after it (a hidden pelvis between hip joints that show); the mean of those places. Otherwise a
root's guesses are corrected by the mismatch at the span's end, growing linearly across the span
(the correction of a smoother with a random-walk model). Spans at the end of the clip, where the joint
is never found again, keep their guesses, and joints keep their confidence (below
``MatchTuning.visible_confidence``, the bar of a joint found): they are still guesses, only better
ones.

Arrays are the tracker's: ``P`` ``(T, k, 2)`` joint centres, ``C`` ``(T, k)`` confidence.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.geometry.coordinates import as_complex, as_points


def fill_hidden_spans(P: NDArray[np.float64], C: NDArray[np.float64], parents: NDArray[np.int_],
                      tracked: NDArray[np.bool_], held: NDArray[np.bool_], since: int = 0, *,
                      tuning: ClipTuning | None = None, match: MatchTuning | None = None
                      ) -> NDArray[np.float64]:
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
    since : int
        Frames before this one are kept as they are in ``P`` (those before a correction): a span
        that ends after it is re-placed from it on only.
    tuning : ClipTuning, optional
        Its ``trusted``; default its defaults.
    match : MatchTuning, optional
        Its ``visible_confidence``: a joint less confident was hidden; default its defaults.

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
    trusted = (ClipTuning() if tuning is None else tuning).trusted
    visible = (MatchTuning() if match is None else match).visible_confidence
    drawings = np.flatnonzero(tracked & ~held)
    for m in range(out.shape[1]):
        found = C[drawings, m] >= visible
        for a, b in _spans(found):
            before, inside, after = drawings[a], drawings[a + 1:b], drawings[b]
            if not (tracked[before:after + 1]).all():
                continue
            s = ((inside - before) / (after - before))[:, None]
            g = parents[m]
            held_by = [] if g >= 0 else _found_throughout(out, C, drawings[a:b + 1], m, parents, visible)
            if held_by:
                out[inside, m] = np.mean([out[inside, c] + as_points(_blend(start, 1.0, end / start, s[:, 0]))
                                          for c, start, end in held_by], axis=0)
            elif g < 0:
                # The guesses, bent to meet the found end: the mismatch there grows across the span.
                # (Where the frame-by-frame guesses were right until the span's last drawings, this
                # spreads their late error over all of it: a root's children found throughout
                # carry it instead, above.)
                last = out[inside[-1], m]
                step = last - out[inside[-2], m] if len(inside) > 1 else 0.0
                out[inside, m] += s * (out[after, m] - (last + step))
            else:
                # The guessed bones (offsets from the parent, as guessed), turned and scaled by a
                # blend of the two ends' mismatches: what takes the guesses, carried on one frame
                # each way as they went, to the bones found before and after the span.
                guess = as_complex(P[inside, m] - P[inside, g])
                start = as_complex(out[before, m] - out[before, g])
                end = as_complex(out[after, m] - out[after, g])
                if start == 0 or end == 0:
                    continue
                first = last = 0.0
                if (guess != 0).all():
                    step_in = guess[0] / guess[1] if len(guess) > 1 else 1.0
                    step_out = guess[-1] / guess[-2] if len(guess) > 1 else 1.0
                    first = start / (guess[0] * step_in)
                    last = end / (guess[-1] * step_out)
                if abs(first - 1) > trusted or abs(last - 1) > trusted:
                    # Guesses that missed an end by more than that: the bone found before the span
                    # turns and stretches steadily into the bone found after it.
                    guess = np.full(len(inside), start)
                    first, last = 1.0, end / start
                out[inside, m] = out[inside, g] + as_points(_blend(guess, first, last, s[:, 0]))
    out[:since] = P[:since]
    held_frames = np.flatnonzero(held[since:]) + since
    for t in held_frames:  # in order, so a drawing held three frames passes its place on
        out[t] = out[t - 1]
    return out


def _blend(guess, first, last, t):
    """The bones ``guess`` (complex, one per ``t``) turned and scaled by a blend, linear in ``t``
    from 0 to 1, of the turn-and-scales ``first`` and ``last`` (complex, non-zero)."""
    scale = (1 - t) * abs(first) + t * abs(last)
    # The two turns within half a turn of each other, so the blend goes the short way.
    start_turn = np.angle(first)
    end_turn = start_turn + np.angle(last / first)
    return guess * scale * np.exp(1j * ((1 - t) * start_turn + t * end_turn))


def _found_throughout(P, C, span, m, parents, visible):
    """The children of root ``m`` found (at least ``visible`` confident) at every frame of ``span``
    (its ends included), each with its bone to ``m`` (complex, child to root) at the span's first
    and last frames; none whose bone is zero at either."""
    held_by = []
    for c in np.flatnonzero(parents == m):
        if (C[span, c] >= visible).all():
            start, end = (complex(as_complex(P[f, m] - P[f, c])) for f in (span[0], span[-1]))
            if start != 0 and end != 0:
                held_by.append((int(c), start, end))
    return held_by


def _spans(found):
    """``(a, b)`` index pairs into ``found`` with ``found[a]`` and ``found[b]`` true and every
    index between them false (at least one)."""
    hits = np.flatnonzero(found)
    return [(int(a), int(b)) for a, b in zip(hits[:-1], hits[1:], strict=True) if b - a > 1]
