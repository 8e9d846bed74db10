"""The whole-sequence pass of the joint tracker: each joint's best path through the places its
search found, by dynamic programming (Viterbi over candidates, the hidden Markov model the thesis'
future work names, 7.2 item 2).

Frame by frame the tracker commits to one place per joint, and a wrong choice is followed: the
next search is centred on it. Its searches also see where else the joint's texture is found (the
other local minima of the colour cost, :class:`~toonmotion.capture.template_match.Match`). Once
the clip is tracked, every joint's path is chosen again among those places, parents first, as
the path of least total cost over the drawings (held frames are left out and repeat the frame
before):

- each place costs ``-log(confidence)`` (a joint not found has the place the tracker put it at,
  with its confidence, which is below ``MatchTuning.visible_confidence``; tracked both ways, it also has the
  place the tracking backwards gave it);
- each step costs ``|e|^2 / (2 s^2)``, ``e`` the change from one drawing to the next of the
  joint's velocity relative to its parent (its own, for a root), in pixels a frame, and
  ``s`` the tuning's ``smoothness`` times the joint's search radius;
- a joint with a parent also pays ``d^2 / (2 (s n)^2)`` for ``d``, its bone's change of length over
  the ``n`` frames from the last drawing.

These are eq. 4.6's two terms, the colour and the distance from a prediction (here of constant
velocity), on one scale, over the whole clip: a place that fits the frames after it as well as those
before is preferred. No step is longer than the joint's widest search reaches (the tuning's
``max_widen`` times its radius a frame), as in the tracking itself. Joints keep their places where
the path goes through them, so the pass can only swap a place for another the searches found.

Tracked both ways (``TrackSettings.both_ways``), each joint also has, on every frame, the place
the tracking backwards from the clip's last frame gave it. A joint the tracking forwards lost for
a stretch and found again, but the tracking backwards held, is then put on the backward path for
that stretch: the forward path jumps where it is found again, the backward one does not.

Arrays are the tracker's: ``P`` ``(T, k, 2)`` joint centres, ``C`` ``(T, k)`` confidence,
``options`` ``(T, k, n, 3)`` the other places, ``(x, y, confidence)``, NaN where none.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.search_tuning import SearchTuning

# Places less confident than this cost as much as this (log of zero).
_FLOOR = 1e-3


def best_paths(P: NDArray[np.float64], C: NDArray[np.float64], options: NDArray[np.float64],
               parents: NDArray[np.int_], drawings: NDArray[np.int_], radius: NDArray[np.float64], *,
               tuning: SearchTuning | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Every joint's best path through its places over ``drawings`` (module docstring).

    Parameters
    ----------
    P : (T, k, 2) float
    C : (T, k) float
    options : (T, k, n, 3) float
        Other places each joint was found at (or, tracked both ways, put at backwards),
        ``(x, y, confidence)``; NaN rows are none.
    parents : (k,) int
        Each joint's parent, -1 for a root; parents come before their children.
    drawings : (d,) int
        The frames to choose places on, increasing; the first keeps its places (the frame the
        run starts from).
    radius : (k,) float
        Each joint's search radius, pixels.
    tuning : SearchTuning, optional
        Its ``smoothness`` and ``max_widen``; default its defaults.

    Returns
    -------
    P, C : new arrays
        With each joint moved to its path's places (and their confidence) on ``drawings``.

    Examples
    --------
    A still joint matched at a look-alike 10 px away on one frame is put back where it was seen
    found the frames either side, as the search found it there too:

    >>> P = np.zeros((4, 1, 2)); P[2, 0] = (10.0, 0.0)
    >>> C = np.full((4, 1), 0.9)
    >>> options = np.full((4, 1, 1, 3), np.nan); options[2, 0, 0] = (0.0, 0.0, 0.85)
    >>> found, _ = best_paths(P, C, options, np.array([-1]), np.arange(4), np.array([8.0]))
    >>> found[:, 0, 0].tolist()
    [0.0, 0.0, 0.0, 0.0]
    """
    P, C = np.array(P, dtype=float), np.array(C, dtype=float)
    tuning = SearchTuning() if tuning is None else tuning
    drawings = np.asarray(drawings, dtype=int)
    if len(drawings) < 3:
        return P, C
    gaps = np.diff(drawings).astype(float)
    for m in range(P.shape[1]):
        places, costs = _candidates(P, C, options, m, drawings)
        if all(len(x) == 1 for x in places):
            continue  # nothing to choose
        g = parents[m]
        # Places relative to the parent's (already chosen) path: a bone turning steadily is smooth.
        relative = [x - (P[t, g] if g >= 0 else 0.0) for x, t in zip(places, drawings, strict=True)]
        chosen = _viterbi(relative, places, costs, gaps, tuning.smoothness * float(radius[m]),
                          tuning.max_widen * float(radius[m]), bone=g >= 0)
        for t, x, cost, i in zip(drawings, places, costs, chosen, strict=True):
            if i:  # 0 is the tracker's own choice
                P[t, m], C[t, m] = x[i], np.exp(-cost[i])
    return P, C


def _candidates(P, C, options, m, drawings):
    """Per drawing, joint ``m``'s places ``(n, 2)`` (the tracker's first) and their costs ``(n,)``;
    the first drawing has only the tracker's."""
    places, costs = [], []
    for index, t in enumerate(drawings):
        x, c = P[t, m][None], [C[t, m]]
        if index:
            rows = options[t, m]
            rows = rows[np.isfinite(rows).all(axis=1)]
            x, c = np.concatenate([x, rows[:, :2]]), np.concatenate([c, rows[:, 2]])
        places.append(x)
        costs.append(-np.log(np.maximum(c, _FLOOR)))
    return places, costs


def _viterbi(places, absolute, costs, gaps, scale, reach, *, bone):
    """Index of the chosen place per drawing: the least total cost of places, velocity changes
    and (with ``bone``) bone-length changes, over pairs of consecutive places (a second-order
    chain), no step longer than ``reach`` a frame. ``places``: relative to the parent's path,
    ``absolute``: in the picture; ``gaps``: frames between consecutive drawings."""
    d = len(places)
    # total[i, j]: least cost of a path ending at place i on drawing s - 1 and j on drawing s.
    total = _step_cost(places, absolute, 1, gaps[0], scale, reach, bone)
    total += costs[0][:, None] + costs[1][None, :]
    back = []
    for s in range(2, d):
        a, b, c = places[s - 2], places[s - 1], places[s]
        # Velocity change per frame: (c - b) / gap2 - (b - a) / gap1, scaled by gap2 to a place error.
        v1 = (b[None, :, :] - a[:, None, :]) / gaps[s - 2]  # (i, j, 2)
        v2 = (c[None, :, :] - b[:, None, :]) / gaps[s - 1]  # (j, l, 2)
        e = v2[None, :, :, :] - v1[:, :, None, :]  # (i, j, l, 2)
        accel = (e**2).sum(axis=-1) / (2 * scale**2)
        through = total[:, :, None] + accel  # (i, j, l)
        best = np.argmin(through, axis=0)  # (j, l)
        total = np.take_along_axis(through, best[None], axis=0)[0]
        total += _step_cost(places, absolute, s, gaps[s - 1], scale, reach, bone) + costs[s][None, :]
        back.append(best)
    before, last = np.unravel_index(int(np.argmin(total)), total.shape)
    chosen = [int(last), int(before)]
    for best in reversed(back):
        i = int(best[chosen[-1], chosen[-2]])
        chosen.append(i)
    return chosen[::-1]


def _step_cost(places, absolute, s, gap, scale, reach, bone):
    """The cost of each step from a place on drawing ``s - 1`` to one on ``s``, ``gap`` frames on,
    ``(n, n')``: the bone's change of length (with ``bone``; none for a root), and infinite where
    the step is longer than ``reach`` a frame, but for the tracker's own step (a joint found
    again may have moved farther), so its path is always there to take."""
    b, c = places[s - 1], places[s]
    cost = np.zeros((len(b), len(c)))
    if bone:
        cost += (np.hypot(*c.T)[None, :] - np.hypot(*b.T)[:, None]) ** 2 / (2 * (scale * gap) ** 2)
    step = absolute[s][None, :, :] - absolute[s - 1][:, None, :]
    too_far = np.hypot(step[..., 0], step[..., 1]) > reach * gap
    too_far[0, 0] = False
    cost[too_far] = np.inf
    return cost
