"""Contour capture (Bregler et al. 3.2, eq. 4-7): the affine motion and key weights of each
frame of a contour sequence in correspondence with the key-shapes.

Per frame: the affine by least squares (eq. 6) against the shape the starting weights blend,
then rounds of a quadratic programme (eq. 7) in the weights — summing to 1, each within its
bounds, at most ``support`` of them non-zero — until the error stops falling (relative change
below 1e-12) or 50 rounds. The paper alternates affine and weights; alternating converges
slowly where the two trade off (a taller shape or a stretched one), so each round here solves
the model linearised in both at once (a constrained Gauss-Newton step: the affine free, the
weights constrained exactly), which reaches the same minimum in a few rounds. The first frame starts from the
first key, each later frame from the frame before. The QP is DAQP's (MIT), made for small dense
problems. The support: every subset of ``support`` keys is tried when there are at most 500,
else the QP over all keys picks the ``support`` largest weights and is solved again on them
(the method is ours; docs/keyshapes.md).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import daqp
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.model import check_shapes, fit_affine, warp
from toonmotion.progress import Progress

FloatArray = NDArray[np.float64]
ROUNDS = 50
SUBSETS = 500


@dataclass(frozen=True)
class ContourCapture:
    """What contour capture found, per frame.

    Attributes
    ----------
    affine : (T, 2, 3) float
    weights : (T, K) float
    error : (T,) float
        The root-mean-square point distance between each contour and its model shape, px.
    rounds : (T,) int
        Affine-then-weights rounds until converged.
    """

    affine: FloatArray
    weights: FloatArray
    error: FloatArray
    rounds: NDArray[np.int64]


def capture_contours(contours: ArrayLike, shapes: ArrayLike, *, lower: ArrayLike = -0.5,
                     upper: ArrayLike = 1.5, support: int | None = None, straight: bool = False,
                     progress: Progress | None = None) -> ContourCapture:
    """Capture ``contours`` (T, N, 2) with key-shapes ``shapes`` (K, N, 2).

    Parameters
    ----------
    lower, upper : float or (K,) float
        Each weight's bounds (the paper's T1 = -0.5, T2 = 1.5); ``-inf``/``inf`` for none.
    support : int, optional
        At most this many non-zero weights (the paper's J); default all K.
    straight : bool
        Open lines, which may be straight (lines of action). A straight blend is a saddle of
        the model (a bend's weight and a stretch across the line have no gradient there), so
        each frame is then solved from the previous frame's weights, the even blend and each
        key alone, and the least error kept.

    Examples
    --------
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)],   # a house
    ...               [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])  # a taller roof
    >>> truth = 0.3 * S[0] + 0.7 * S[1]
    >>> found = capture_contours([truth + [5, 1]], S)
    >>> found.weights.round(9).tolist(), found.affine[0, :, 2].round(9).tolist()
    ([[0.3, 0.7]], [5.0, 1.0])
    """
    S = check_shapes(shapes, allow_straight=straight)
    V = check_shapes(contours, what="contours", allow_straight=straight)
    K, N = S.shape[:2]
    if V.shape[1] != N:
        raise KeyShapeError(f"the contours have {V.shape[1]} points but the key-shapes {N}: "
                            "they must be in correspondence, point for point")
    low = np.broadcast_to(np.asarray(lower, dtype=float), (K,)).copy()
    high = np.broadcast_to(np.asarray(upper, dtype=float), (K,)).copy()
    if np.isnan(low).any() or np.isnan(high).any() or (low > high).any() or low.sum() > 1 or high.sum() < 1:
        raise KeyShapeError("the weight bounds must hold weights that sum to 1 (lower <= upper)")
    J = K if support is None else support
    if not (isinstance(J, int) and 1 <= J <= K):
        raise KeyShapeError(f"the support must be a whole number of keys from 1 to {K}, got {support!r}")
    subsets = _subsets(K, J)
    affine = np.zeros((len(V), 2, 3))
    weights = np.zeros((len(V), K))
    error = np.zeros(len(V))
    rounds = np.zeros(len(V), dtype=np.int64)
    w = np.full(K, 1 / K) if straight else np.eye(K)[0]
    for t, contour in enumerate(V):
        starts = [w, np.full(K, 1 / K), *np.eye(K)] if straight else [w]
        w, A, e, n = _best_frame(contour, S, starts, low, high, J, subsets)
        affine[t], weights[t], error[t], rounds[t] = A, w, e, n
        if progress is not None:
            progress("capturing", t + 1, len(V))
    return ContourCapture(affine=affine, weights=weights, error=error, rounds=rounds)


def _best_frame(contour, S, starts, low, high, J, subsets):
    """:func:`_frame` from each of ``starts``, the least error kept (a start that finds no
    weights within the bounds is passed over, unless every one does)."""
    best, refused = None, None
    for start in starts:
        try:
            found = _frame(contour, S, np.asarray(start, dtype=float), low, high, J, subsets)
        except KeyShapeError as error:
            refused = error
            continue
        if best is None or found[2] < best[2]:
            best = found
    if best is None:
        assert refused is not None
        raise refused
    return best


def solve_weights(A: FloatArray, contour: FloatArray, S: FloatArray, low: FloatArray, high: FloatArray,
                  keys: ArrayLike | None = None) -> tuple[FloatArray, float]:
    """The weights (K,) minimising eq. 7 for a fixed affine ``A``, with the bounds and summing to
    1, only ``keys`` (indices) allowed non-zero; and the squared error."""
    K = len(S)
    chosen = np.arange(K) if keys is None else np.asarray(keys)
    B = (S[chosen] @ A[:, :2].T + A[:, 2]).reshape(len(chosen), -1).T  # (2N, k): each key, aligned
    v = contour.ravel()
    x = _least_squares(B, v, 0, low[chosen], high[chosen])
    if x is None:
        return np.full(K, np.nan), math.inf
    w = np.zeros(K)
    w[chosen] = x
    residual = B @ x - v
    return w, float(residual @ residual)


def _least_squares(M: FloatArray, v: FloatArray, free: int, low: FloatArray, high: FloatArray
                   ) -> FloatArray | None:
    """``x`` minimising ``|M x - v|^2`` whose first ``free`` entries are unbounded and whose
    other entries (the weights) lie within ``low``, ``high`` and sum to 1: DAQP's QP; None when
    no such ``x`` exists."""
    n = M.shape[1]
    H = M.T @ M
    H += np.eye(n) * 1e-12 * max(np.trace(H), 1e-300)  # keys that the affine can mimic: still solvable
    sense = np.zeros(n + 1, dtype=np.int32)
    sense[-1] = 5  # the weights' sum: an equality
    row = np.concatenate([np.zeros(free), np.ones(n - free)])[None]
    unbounded = np.full(free, 1e30)
    x, _, flag, _ = daqp.solve(H, -M.T @ v, row, np.concatenate([unbounded, high, [1.0]]),
                               np.concatenate([-unbounded, low, [1.0]]), sense)
    return None if flag < 1 else np.asarray(x, dtype=float)


def _subsets(K: int, J: int) -> list[tuple[int, ...]] | None:
    if J == K:
        return [tuple(range(K))]
    return list(itertools.combinations(range(K), J)) if math.comb(K, J) <= SUBSETS else None


def _frame(contour, S, w, low, high, J, subsets):
    A = fit_affine(contour, np.tensordot(w, S, axes=1))
    n = 0
    last = math.inf
    while n < ROUNDS:
        n += 1
        if subsets is None:  # many keys: the J largest weights of the full QP, then again on them
            full = _step(contour, S, A, w, low, high, np.arange(len(S)))[1]
            options = [tuple(np.argsort(-np.abs(full))[:J])]
        else:
            options = subsets
        best = None
        for keys in options:
            found = _step(contour, S, A, w, low, high, np.asarray(keys))
            if found is not None and (best is None or found[2] < best[2]):
                best = found
        if best is None:
            raise KeyShapeError("no weights within the bounds reach a shape summing to 1: widen the bounds")
        A, w, squared = best
        if squared <= 1e-24 or (math.isfinite(last) and last - squared <= 1e-12 * last):
            break
        last = squared
    residual = warp(A, w, S) - contour
    return w, A, float(np.sqrt((residual ** 2).sum(axis=1).mean())), n


def _step(contour, S, A, w, low, high, keys):
    """One constrained Gauss-Newton step on the affine and the weights together (the bilinear
    model linearised at ``A``, ``w``; the weights' bounds and sum kept exactly by the QP), only
    ``keys`` allowed non-zero; returns the new affine, weights and squared error, or None."""
    blend = np.tensordot(w, S, axes=1)
    homogeneous = np.column_stack([blend, np.ones(len(blend))])  # (N, 3)
    linear = A[:, :2]
    N, k = len(blend), len(keys)
    J = np.zeros((2 * N, 6 + k))
    J[0::2, 0:3] = homogeneous  # x rows: a1 a2 dx
    J[1::2, 3:6] = homogeneous  # y rows: a3 a4 dy
    J[:, 6:] = (S[keys] @ linear.T).reshape(k, -1).T  # each key through the current linear part
    goal = (contour - homogeneous @ A.T + blend @ linear.T).ravel()
    x = _least_squares(J, goal, 6, low[keys], high[keys])
    if x is None:
        return None
    A_new = A + x[:6].reshape(2, 3)
    w_new = np.zeros(len(S))
    w_new[keys] = x[6:]
    residual = warp(A_new, w_new, S) - contour
    return A_new, w_new, float((residual ** 2).sum())
