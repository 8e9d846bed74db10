"""Cartoon capture by key-shapes (Bregler et al. 2002): the calls behind key-shape models and
contour capture (docs/keyshapes.md)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.contour import capture_contours as _capture
from toonmotion.keyshape.matte import pick_layer as _pick_layer
from toonmotion.keyshape.parts import capture_parts as _capture_parts
from toonmotion.keyshape.space import KeyShapeSpace, build_space
from toonmotion.keyshape.video import VideoCapture
from toonmotion.keyshape.video import capture_video as _capture_video
from toonmotion.progress import Progress
from toonmotion.render.keyshape_sheet import inbetween_sheet

# The bounds on the eigen-shapes' weights in an extended space: half as much again as any
# example (docs/keyshapes.md).
EIGEN_BOUND = 1.5


def keyshape_space(keys: ArrayLike, *, closed: bool = True, inbetweens: int = 5,
                   tolerance: float = 0.5) -> KeyShapeSpace:
    """The extended key-shape space of hand-picked ``keys``: ARAP in-betweens of every pair, PCA.

    Parameters
    ----------
    keys : (K, N, 2) float
        Key-shapes, points in correspondence, drawing pixels.
    closed : bool
        The points run round a closed contour (its inside is triangulated for the in-betweens).
    inbetweens : int
        In-betweens per pair of keys (the paper's M).
    tolerance : float
        The largest reconstruction error of any key or in-between, px; fixes the number of
        eigen-shapes.

    Returns
    -------
    KeyShapeSpace
        ``extended`` is the key-shapes to capture with (eq. 3).

    Raises
    ------
    KeyShapeError
        For keys of different point counts, too few, collinear or non-finite points.

    Examples
    --------
    >>> ball = np.stack([(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)]) * 20
    >>> space = keyshape_space([ball, ball * [1.4, 0.7], ball * [0.8, 1.25] + [0, -5]])
    >>> space.extended.shape[1:], space.error <= 0.5
    ((24, 2), True)
    """
    return build_space(keys, closed=closed, inbetweens=inbetweens, tolerance=tolerance)


def capture_contours(contours: ArrayLike, shapes: ArrayLike | KeyShapeSpace, *, lower: float = -0.5,
                     upper: float = 1.5, support: int | None = None, progress: Progress | None = None
                     ) -> ContourCapture:
    """The affine motion and key weights of each contour (eq. 4-7).

    Parameters
    ----------
    contours : (T, N, 2) float
        The contour of every frame, in correspondence with the key-shapes.
    shapes : (K, N, 2) float or KeyShapeSpace
        Hand-picked key-shapes, or an extended space (then its eigen-shapes' weights are bounded
        to [-1.5, 1.5], the mean's is free, and ``lower``, ``upper`` and ``support`` are not used).
    lower, upper : float
        Each key's weight bounds (the paper's T1, T2).
    support : int, optional
        At most this many non-zero weights (the paper's J).
    progress : callable, optional
        ``progress("capturing", index, count)`` after each frame (the editor's progress bar).

    Returns
    -------
    ContourCapture
        ``affine`` (T, 2, 3), ``weights`` (T, K), ``error`` (rms px) and ``rounds`` per frame.

    Raises
    ------
    KeyShapeError
        For contours out of correspondence, bad points, or bounds no weights summing to 1 fit.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)], [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])
    >>> found = capture_contours([warp([[0, -1, 9], [1, 0, 2]], [0.25, 0.75], S)], S)
    >>> found.weights.round(9).tolist()
    [[0.25, 0.75]]
    """
    if isinstance(shapes, KeyShapeSpace):
        L = len(shapes.eigen)
        low = np.append(np.full(L, -EIGEN_BOUND), -np.inf)
        high = np.append(np.full(L, EIGEN_BOUND), np.inf)
        return _capture(contours, shapes.extended, lower=low, upper=high, progress=progress)
    return _capture(contours, shapes, lower=lower, upper=upper, support=support, progress=progress)


def capture_video(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], shapes: ArrayLike, *,
                  key_frames: Sequence[int] = (0,), closed: bool = True, inbetweens: int = 5, eigen: int = 10,
                  largest: float = 200.0, progress: Progress | None = None) -> VideoCapture:
    """Capture a cartoon layer straight from footage (eq. 8-16): each frame's affine motion and
    eigen-image weights, and the shape they give.

    The layer's colour matte is learnt from the first key frame (its shape's pixels against
    their surroundings); the key frames' images, warped through the as-rigid-as-possible
    in-betweens of their shapes, give the eigen-images; each frame is then tracked from the
    one before (from the first key frame to the end, and back to the start), affine and weights
    together (docs/keyshapes.md, "Video capture").

    Parameters
    ----------
    frames : (T, h, w, 3) uint8, or a sequence of such images
        The footage (:func:`toonmotion.io.frames.load_frames` reads videos, GIFs and folders).
    shapes : (K, N, 2) float
        The layer's outline at each key frame, points in correspondence (one shape: affine
        motion only).
    key_frames : sequence of int
        The frames the shapes are drawn on, from 0.
    closed : bool
        Whether the shapes are closed contours.
    inbetweens : int
        ARAP in-betweens per pair of keys.
    eigen : int
        Eigen-images kept at most (the paper's L = 10).
    largest : float
        A layer more than this many px across is captured on frames shrunk by the smallest
        whole factor that brings it within (the time grows with the layer's area); the result
        is in the frames' own pixels.
    progress : callable, optional
        ``progress("capturing", index, count)`` after each frame.

    Returns
    -------
    VideoCapture
        ``affine`` (T, 2, 3) from the first key frame's pixels, ``weights`` (T, L), ``shapes``
        (T, N, 2), ``residual`` and ``iterations`` per frame.

    Raises
    ------
    KeyShapeError
        For shapes out of correspondence or outside the frame, a key frame outside the
        sequence, frames of different sizes, or a layer lost from every start.

    Examples
    --------
    >>> from toonmotion.sample_cartoons import morphing_character
    >>> hero = morphing_character(frames=24)
    >>> keys = list(hero.key_frames)
    >>> found = capture_video(hero.frames, hero.contours[keys], key_frames=keys)
    >>> float(np.hypot(*(found.shapes - hero.contours).T).mean()) < 1  # mean point error, px
    True
    """
    return _capture_video(frames, shapes, key_frames=key_frames, closed=closed, inbetweens=inbetweens,
                          eigen=eigen, largest=largest, progress=progress)


def pick_layer(frame: NDArray[np.uint8], point: ArrayLike, *, tolerance: int = 24, points: int = 100
               ) -> NDArray[np.float64]:
    """The outline of the layer under ``point`` (x, y) in ``frame``, by its colour: the
    connected region of colours within ``tolerance`` of their neighbours, holes filled,
    resampled to ``points`` points from its topmost one. For :func:`capture_video`'s shapes.

    Parameters
    ----------
    frame : (h, w, 3) uint8
    point : (2,) float
    tolerance : int
        Colour step allowed between neighbouring pixels, per channel.
    points : int
        Points in the outline.

    Returns
    -------
    (points, 2) float

    Raises
    ------
    KeyShapeError
        For a point outside the frame, or a region under 16 px or filling the frame.

    Examples
    --------
    >>> from toonmotion.sample_cartoons import morphing_character
    >>> hero = morphing_character(frames=6)
    >>> outline = pick_layer(hero.frames[0], hero.contours[0].mean(axis=0), points=60)
    >>> outline.shape
    (60, 2)
    """
    return _pick_layer(frame, point, tolerance=tolerance, points=points)


def capture_parts(contours: ArrayLike, shapes: ArrayLike, parts: Mapping[str, Sequence[int]], *,
                  lower: float = -0.5, upper: float = 1.5, support: int | None = None
                  ) -> dict[str, ContourCapture]:
    """Contour capture part by part (3.1.4): each part — a list of point numbers — of the
    contours gets its own affine and key weights, as a character's legs, arms and head move
    on their own.

    Parameters
    ----------
    contours : (T, N, 2) float
    shapes : (K, N, 2) float
        Hand-picked key-shapes.
    parts : mapping of str to sequence of int
        Each part's points (at least 3; parts may share points; every point in one).
    lower, upper : float
        Each key's weight bounds.
    support : int, optional
        At most this many non-zero weights per part.

    Returns
    -------
    dict of str to ContourCapture

    Raises
    ------
    KeyShapeError
        For a point in no part, a part of fewer than 3 points or naming a point out of range,
        and as :func:`capture_contours`.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (0, 4), (2, 8), (3, 6)],
    ...               [(0.0, 0), (6, 0), (4, 4), (0, 4), (2, 12), (4, 7)]])
    >>> frame = np.vstack([warp(np.eye(2, 3), [1, 0], S)[:4], warp(np.eye(2, 3), [0, 1], S)[4:]])
    >>> found = capture_parts([frame], S, {"body": [0, 1, 2, 3], "head": [2, 3, 4, 5]})
    >>> found["head"].weights.round(6).tolist()
    [[0.0, 1.0]]
    """
    return _capture_parts(contours, shapes, parts, lower=lower, upper=upper, support=support)


def keyshape_sheet(space: KeyShapeSpace) -> NDArray[np.uint8]:
    """A preview sheet of the space's keys and their in-betweens, one row per pair of keys.

    Parameters
    ----------
    space : KeyShapeSpace
        From :func:`keyshape_space`; its ``inbetweens`` per pair are drawn (at least 3).

    Returns
    -------
    (h, w, 3) uint8
        Outlines on white: keys dark, in-betweens blue.

    Examples
    --------
    >>> ball = np.stack([(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 24, endpoint=False)]) * 20
    >>> keyshape_sheet(keyshape_space([ball, ball * [1.4, 0.7]], inbetweens=3)).shape
    (160, 800, 3)
    """
    keys = space.keys
    triangles = triangulate_shape(keys[0], closed=space.closed)
    rows = []
    for i in range(len(keys)):
        for j in range(i + 1, len(keys)):
            pair = ArapPair(keys[i], keys[j], closed=space.closed, triangles=triangles)
            between = pair.inbetweens(max(3, space.inbetweens))
            rows.append(np.concatenate([keys[i][None], between, keys[j][None]]))
    if not rows:  # one key: itself
        rows.append(keys[:1])
    return inbetween_sheet(rows, closed=space.closed)


