"""Time alignment of the motion prior to the drawing (section 3.1.2): dynamic time warping.

The prior may be slower, faster or longer than the drawing. Dynamic time warping [Sakoe and
Chiba] finds the monotone path through the (drawn frame, prior frame) grid, from the first pair
to the last, that minimises the summed squared distance between the frames' pose descriptors
(:func:`~toonmotion.proxy3d.descriptor.descriptor_features`: each limb's angle as a unit vector,
so the local cost is ``sum(2 - 2 cos dtheta)``), with steps (1, 1), (1, 0) and (0, 1).

A Sakoe-Chiba band keeps the path near the diagonal: drawn frame ``i`` meets prior frame ``j``
only when ``j - i`` lies within ``w`` frames of the strip between the diagonals ``j = i`` and
``j = i + (m - n)`` (``m`` prior frames, ``n`` drawn), ``w = ceil(band * m)``; the strip holds
every uniform stretch from corner to corner. This is dtaidistance's band (its ``window`` is
``w + 1``), so both implementations find the same path.

:func:`dtw` calls dtaidistance (Apache-2.0, C; measured about ten times faster on 1,000 x 1,000
frames with a 10% band, see ``benchmarks/proxy3d.py`` and docs/proxy3d.md). ``method="numpy"`` is
our vectorised implementation, row by row: with ``e_j = C_ij + min(D_{i-1,j-1}, D_{i-1,j})`` a
row's horizontal steps make ``D_ij = min_{k<=j}(e_k + C_{i,k+1} + ... + C_ij)``, which is
``S_j + minimum.accumulate(e - S)_j`` with ``S`` the row's running sum of costs: one pass of array
operations per drawn frame. It is the benchmark's peer and the tests' second opinion.

The warped prior (:func:`warp_prior`) gives each drawn frame the prior at the mean of the prior
frames the path pairs it with, interpolated linearly between frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.descriptor import descriptor_features
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.prior import Prior, at_times, resample_prior

# A drawn frame may stand for at most this many prior frames on average, and the other way round
# (the prior's length after resampling to the drawing's rate): beyond it the prior is too short.
MAX_STRETCH = 2.0


@dataclass(frozen=True, eq=False)
class Alignment:
    """A dynamic time warping of a prior to a drawing.

    Attributes
    ----------
    path : (L, 2) int
        ``(drawn frame, prior frame)`` pairs from ``(0, 0)`` to ``(n - 1, m - 1)``, each step
        (1, 1), (1, 0) or (0, 1).
    frames : (n,) float
        For each drawn frame, the prior frame it is shown (the mean of its pairs on the path).
    cost : float
        The path's summed local cost.
    """

    path: NDArray[np.int64]
    frames: NDArray[np.float64]
    cost: float


METHODS = ("dtaidistance", "numpy")


def dtw(
    query: ArrayLike, reference: ArrayLike, *, band: float = 0.1, method: str = "dtaidistance"
) -> Alignment:
    """Dynamic time warping of two feature sequences within a Sakoe-Chiba band.

    Parameters
    ----------
    query : (n, d) float
        The drawing's features, one row per frame.
    reference : (m, d) float
        The prior's features.
    band : float
        The band's half-width beyond the strip between the diagonals, as a fraction of ``m``, in
        ``(0, 1]`` (module docstring; :func:`band_limits`).
    method : {"dtaidistance", "numpy"}
        dtaidistance's C implementation, or ours in NumPy; the same band, path and cost.

    Returns
    -------
    Alignment

    Examples
    --------
    A sequence against itself slowed down two times: each frame meets its two copies.

    >>> a = np.array([[0.0], [1.0], [3.0]])
    >>> found = dtw(np.repeat(a, 2, axis=0), a, band=1.0)
    >>> found.path.tolist(), found.frames.tolist(), found.cost
    ([[0, 0], [1, 0], [2, 1], [3, 1], [4, 2], [5, 2]], [0.0, 0.0, 1.0, 1.0, 2.0, 2.0], 0.0)
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    A = _features(query, "query")
    B = _features(reference, "reference")
    if A.shape[1] != B.shape[1]:
        raise ProxyError(f"the drawing's and the prior's features differ in size: {A.shape[1]} and "
                         f"{B.shape[1]}")
    if not (np.isfinite(band) and 0 < band <= 1):
        raise ProxyError(f"band must be a fraction of the prior's length in (0, 1], got {band!r}")
    n = len(A)
    if method == "dtaidistance":
        path = _dtaidistance_path(A, B, band)
    else:
        path = _numpy_path(A, B, *band_limits(n, len(B), band))
    frames = np.bincount(path[:, 0], weights=path[:, 1], minlength=n) / np.bincount(path[:, 0], minlength=n)
    cost = float(((A[path[:, 0]] - B[path[:, 1]]) ** 2).sum())
    return Alignment(path=path, frames=frames, cost=cost)


def _dtaidistance_path(A, B, band):
    from dtaidistance import dtw as dtai

    window = _window(len(B), band) + 1
    if A.shape[1] == 1:  # one feature: dtaidistance wants 1-D series
        A, B = A[:, 0], B[:, 0]
    A, B = np.ascontiguousarray(A, dtype=np.float64), np.ascontiguousarray(B, dtype=np.float64)
    path = dtai.warping_path(A, B, use_c=True, use_ndim=A.ndim == 2, window=window)
    return np.asarray(path, dtype=np.int64).reshape(-1, 2)


def _window(m, band):
    return max(1, int(np.ceil(band * m - 1e-9)))


def _numpy_path(A, B, lo, hi):
    n, m = len(A), len(B)
    W = int((hi - lo).max()) + 1
    columns = lo[:, None] + np.arange(W)
    inside = columns <= hi[:, None]
    columns = np.minimum(columns, m - 1)
    # Local costs in the band, (n, W): |a|^2 + |b|^2 - 2 a.b, one gather and one product.
    cost = (np.einsum("id,id->i", A, A)[:, None] + np.einsum("id,id->i", B, B)[columns]
            - 2 * np.einsum("id,iwd->iw", A, B[columns]))
    cost = np.where(inside, np.maximum(cost, 0.0), np.inf)
    D = np.full((n, W), np.inf)
    S = np.cumsum(np.where(inside[0], cost[0], 0.0))
    D[0] = np.where(inside[0], S, np.inf)  # row 0 starts at column 0 (lo[0] == 0)
    pad = np.full(W + 2, np.inf)
    for i in range(1, n):
        shift = int(lo[i] - lo[i - 1])  # >= 0: the band moves right or stays
        pad[1:-1] = D[i - 1]
        # previous row at columns j (up) and j - 1 (diagonal), for j = lo[i] + t
        up = pad[np.minimum(np.arange(W) + shift + 1, W + 1)]
        diagonal = pad[np.minimum(np.arange(W) + shift, W + 1)]
        c = cost[i]
        e = c + np.minimum(up, diagonal)
        finite_c = np.where(inside[i], c, 0.0)
        S = np.cumsum(finite_c)
        D[i] = np.where(inside[i], S + np.minimum.accumulate(e - S), np.inf)
    return _backtrack(D, lo, hi)


def band_limits(n: int, m: int, band: float) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """The first and last prior frame each drawn frame may meet, ``(n,)`` each.

    Drawn frame ``i`` meets prior frames
    ``max(0, i - max(0, n - m) - w) <= j <= min(m - 1, i + max(0, m - n) + w)``, with
    ``w = ceil(band * m)`` (at least 1): the strip between the diagonals ``j = i`` and
    ``j = i + m - n``, widened by ``w`` on both sides.

    >>> [v.tolist() for v in band_limits(3, 5, 0.2)]
    [[0, 0, 1], [3, 4, 4]]
    """
    w = _window(m, band)
    i = np.arange(n)
    lo = np.clip(i - max(0, n - m) - w, 0, m - 1).astype(np.int64)
    hi = np.clip(i + max(0, m - n) + w, 0, m - 1).astype(np.int64)
    return lo, hi


def align_prior(
    markers: Markers, prior: Prior, R: ArrayLike, *, band: float = 0.1, relative: bool = False,
    max_stretch: float = MAX_STRETCH,
) -> Alignment:
    """Align a prior to the drawn markers in time, on pose descriptors seen through a camera.

    The prior is resampled to the drawing's frame rate (:func:`resample_prior`), projected by the
    orthographic camera ``R`` (:func:`~toonmotion.proxy3d.orthographic.camera`), and its pose
    descriptors matched to the drawing's by :func:`dtw`.

    Parameters
    ----------
    markers : Markers
    prior : Prior
        With the markers' names, in their order.
    R : (2, 3) float
        The orthographic camera's rows (image x, image y down) in the prior's world.
    band : float
        Sakoe-Chiba half-width as a fraction of the resampled prior's length.
    relative : bool
        Relative descriptors (each limb from its parent limb) instead of absolute ones.
    max_stretch : float
        How much longer or shorter than the drawing the resampled prior may be, as a ratio.

    Returns
    -------
    Alignment
        Prior frames are frames of the *resampled* prior (the drawing's frame rate); give it to
        :func:`warp_prior`.

    Raises
    ------
    ProxyError
        The prior's markers are not the drawing's, or it is too short (or too long) to align.
    """
    _check_names(markers, prior)
    at_rate = resample_prior(prior, markers.fps)
    n, m = markers.frame_count, at_rate.frame_count
    if m * max_stretch < n or m < 2 and n > 1:
        raise ProxyError(
            f"the prior is too short to align: {prior.frame_count / prior.fps:.3g} s ({m} frames at "
            f"{markers.fps:g} fps) for {n} drawn frames; give a prior at least {n / max_stretch:.0f} frames "
            f"({n / max_stretch / markers.fps:.3g} s) long"
        )
    if n * max_stretch < m:
        most = n * max_stretch
        own = f", {most * prior.fps / markers.fps:.0f} of its own at {prior.fps:g} fps"
        raise ProxyError(f"the prior is too long to align: {m} frames at {markers.fps:g} fps for {n} drawn "
                         "frames; cut it to the part that matches the drawing (at most "
                         f"{most:.0f} frames{own if prior.fps != markers.fps else ''})")
    projection = np.asarray(R, dtype=float)
    if projection.shape != (2, 3) or not np.isfinite(projection).all():
        raise ProxyError(f"the camera must be a finite 2x3 matrix, got shape {projection.shape}")
    limbs = prior.limbs
    if len(limbs) == 0:
        raise ProxyError("the prior's markers form no limb (no marker has a parent); nothing to align on")
    drawn = descriptor_features(markers.positions, limbs, relative=relative)
    seen = descriptor_features(at_rate.positions @ projection.T, limbs, relative=relative)
    return dtw(drawn, seen, band=band)


def warp_prior(prior: Prior, alignment: Alignment, fps: float) -> Prior:
    """The prior shown at the drawing's frames: ``X~`` of the paper, one pose per drawn frame.

    ``prior`` is resampled to ``fps`` (the drawing's rate, as in :func:`align_prior`), then
    sampled at ``alignment.frames`` by linear interpolation.

    >>> p = Prior(("a",), [-1], np.arange(3.0)[:, None, None] * [1.0, 0, 0], fps=12)
    >>> found = Alignment(path=np.array([[0, 0], [1, 1], [1, 2]]), frames=np.array([0.0, 1.5]), cost=0.0)
    >>> warp_prior(p, found, 12).positions[:, 0, 0].tolist()
    [0.0, 1.5]
    """
    at_rate = resample_prior(prior, fps)
    return at_times(at_rate, alignment.frames, at_rate.fps)


def _features(values, what):
    F = np.asarray(values, dtype=float)
    if F.ndim == 1:
        F = F[:, None]
    if F.ndim != 2 or len(F) == 0 or F.shape[1] == 0:
        raise ProxyError(f"the {what} must be (frames, features) with at least one frame, got {F.shape}")
    if not np.isfinite(F).all():
        raise ProxyError(f"the {what} has a non-finite feature (NaN or infinity)")
    return F


def _check_names(markers, prior):
    if tuple(prior.names) != tuple(markers.names):
        missing = [n for n in markers.names if n not in prior.names]
        if missing:
            raise ProxyError(f"the motion prior lacks the markers {', '.join(missing)}; build it from the "
                             "markers' names (prior_from_bvh)")
        raise ProxyError("the prior's markers are in another order than the drawing's; build it from the "
                         "markers' names (prior_from_bvh)")


def _backtrack(D, lo, hi):
    """The optimal path from the last cell back to (0, 0), ``(L, 2)``, first pair first."""
    i, j = len(D) - 1, int(hi[-1])
    path = [(i, j)]

    def at(r, c):
        return D[r, c - lo[r]] if r >= 0 and lo[r] <= c <= hi[r] else np.inf

    while i > 0 or j > 0:
        steps = ((i - 1, j - 1), (i - 1, j), (i, j - 1))  # ties prefer the diagonal
        i, j = min(steps, key=lambda s: at(*s))
        path.append((i, j))
    return np.array(path[::-1], dtype=np.int64)
