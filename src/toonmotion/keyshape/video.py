"""Video capture (Bregler et al. 3.3, eq. 8-16): a cartoon layer's affine motion and key-image
weights, straight from the frames.

*The layer image.* Every frame is turned into ``matte * (0.25 + 0.75 * grey)``: the layer's
colour matte (:mod:`~toonmotion.keyshape.matte`) times its grey level, so the background and
any occluder are 0 and the layer keeps its inner lines. The paper cuts the sum to the layer's
pixels (eq. 16); a flat-coloured layer has no gradient inside, so its position lies in its
outline, and the outline is seen from both sides here: the template holds a band round the
layer, where everything counts, and inside the layer (away from the band) a pixel counts as
much as the current frame's matte says it belongs to the layer. Anywhere, a pixel counts as
much as its colour is familiar (an occluder's is not). Residuals are weighed by Huber's
function besides.

*Key-images and eigen-images* (eq. 14-15): :mod:`~toonmotion.keyshape.image_model`.
*Tracking*, one frame at a time from the frames before: :mod:`~toonmotion.keyshape.layer_fit`.
The intermediate pyramid levels were measured to add time, not accuracy (docs/keyshapes.md). A
layer more than ``LARGEST`` px across is captured on shrunk frames.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.image_model import ImageModel, build_image_model, key_frame_indices
from toonmotion.keyshape.image_ops import (
    FloatArray,
    apply_affine,
    check_inside,
    fill_polygon,
    inverse3,
    square_affine,
)
from toonmotion.keyshape.layer_fit import Level, track_frame
from toonmotion.keyshape.matte import ColourMatte, fit_matte
from toonmotion.keyshape.model import check_shapes
from toonmotion.progress import Progress

LARGEST = 200.0  # px: a layer wider or taller is captured on frames shrunk by a whole factor


@dataclass(frozen=True)
class VideoCapture:
    """What video capture found, per frame.

    Attributes
    ----------
    affine : (T, 2, 3) float
        From the first key frame's pixels to this frame's.
    weights : (T, L) float
        The eigen-image weights.
    shapes : (T, N, 2) float
        The captured shape in the frame: the affine of the weights' shape.
    residual : (T,) float
        Root-mean-square of the weighted residual at the finest level (layer-image units).
    iterations : (T,) int
        Levenberg-Marquardt steps, every start's and the refinement's together.
    """

    affine: FloatArray
    weights: FloatArray
    shapes: FloatArray
    residual: FloatArray
    iterations: NDArray[np.int64]


def track_layer(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], model: ImageModel,
                matte: ColourMatte, *, start: ArrayLike | None = None, first: int = 0,
                progress: Callable[[], None] | None = None) -> VideoCapture:
    """Track the layer ``model`` describes through ``frames``, from frame ``first`` (at affine
    ``start``, the identity by default: the model is in that frame's pixels) to the last."""
    fine, coarse = Level.of(model, 0), Level.of(model, model.levels - 1)
    reach = float(np.ptp(fine.corners, axis=0).max())  # a window's size
    A = np.eye(2, 3) if start is None else np.array(start, dtype=float)
    a = np.zeros(len(model.eigen))
    affines: list[FloatArray] = []
    weights, shapes, residuals, iterations = [], [], [], []
    for t in range(first, len(frames)):
        rgb = np.asarray(frames[t])
        starts = [A]
        if len(affines) >= 2:  # moved on at the same rate, unless that flies off
            ahead = (square_affine(A) @ inverse3(affines[-2]) @ square_affine(A))[:2]
            if np.abs(apply_affine(ahead, fine.corners) - apply_affine(A, fine.corners)).max() < reach:
                starts.insert(0, ahead)
        A, a, residual, steps = track_frame(rgb, matte, model, fine, coarse, starts, a)
        affines.append(A)
        weights.append(a)
        shapes.append(apply_affine(A, model.shape(a)))
        residuals.append(residual)
        iterations.append(steps)
        if progress is not None:
            progress()
    return VideoCapture(affine=np.array(affines), weights=np.array(weights).reshape(len(affines), -1),
                        shapes=np.array(shapes), residual=np.array(residuals),
                        iterations=np.array(iterations, dtype=np.int64))


def capture_video(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], shapes: ArrayLike, *,
                  key_frames: Sequence[int] = (0,), closed: bool = True, inbetweens: int = 5, eigen: int = 10,
                  largest: float = LARGEST, progress: Progress | None = None) -> VideoCapture:
    """Capture the layer drawn as ``shapes`` (K, N, 2) at ``key_frames`` through ``frames``: its
    colour matte from the first key frame, its image model, and tracking from the first key
    frame to the end and back to the start.

    A layer more than ``largest`` px across is captured on frames shrunk by the smallest whole
    factor that brings it within (the cost grows with the layer's area); the result is given
    in the frames' own pixels.

    Examples
    --------
    >>> from toonmotion.sample_cartoons import bouncing_ball
    >>> ball = bouncing_ball(frames=24)
    >>> found = capture_video(ball.frames, ball.contours[:1])  # affine only: one key
    >>> found.shapes.shape, bool(np.hypot(*(found.shapes - ball.contours).T).mean() < 1)
    ((24, 64, 2), True)
    """
    _check_frames(frames)
    S = check_shapes(shapes, what="the key frames' shapes")
    keys = key_frame_indices(key_frames, len(frames), len(S))
    if not (np.isfinite(largest) and largest >= 16):
        raise KeyShapeError(f"the largest layer tracked at full size must be at least 16 px, got {largest!r}")
    frames, S, factor = shrunk(frames, S, largest)
    first = keys[0]
    picture = np.asarray(frames[first])
    matte = fit_matte(picture, region_mask(S[0], picture.shape[:2]))
    model = build_image_model(frames, keys, S, matte, closed=closed, inbetweens=inbetweens, eigen=eigen)
    done, total = 0, len(frames) + (first > 0)  # the first key frame is tracked both ways

    def one_more() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress("capturing", done, total)

    found = track_layer(frames[first:], model, matte, progress=one_more)
    if first > 0:
        back = track_layer(frames[first::-1], model, matte, progress=one_more)
        found = VideoCapture(**{name: np.concatenate([getattr(back, name)[:0:-1], getattr(found, name)])
                                for name in ("affine", "weights", "shapes", "residual", "iterations")})
    if factor == 1:
        return found
    # Back to the frames' pixels: x = factor * x_small + centre, on both sides of each affine.
    centre = (factor - 1) / 2
    grow = np.array([[factor, 0, centre], [0, factor, centre], [0, 0, 1.0]])
    affine = np.stack([(grow @ square_affine(A) @ np.linalg.inv(grow))[:2] for A in found.affine])
    return VideoCapture(affine=affine, weights=found.weights, shapes=found.shapes * factor + centre,
                        residual=found.residual, iterations=found.iterations)


def shrunk(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], shapes: FloatArray, largest: float
           ) -> tuple[Sequence[NDArray[np.uint8]] | NDArray[np.uint8], FloatArray, int]:
    """``frames`` and ``shapes`` (K, N, 2) shrunk by the smallest whole factor that brings the
    shapes within ``largest`` px across (area averaging: pixel i covers pixels ``factor * i`` to
    ``factor * i + factor - 1``), and the factor (1: as they were)."""
    factor = max(1, int(np.ceil(float(np.ptp(shapes, axis=1).max()) / largest)))  # the widest shape
    if factor == 1:
        return frames, shapes, 1
    small = [np.asarray(cv2.resize(np.asarray(f), None, fx=1 / factor, fy=1 / factor,
                                   interpolation=cv2.INTER_AREA), dtype=np.uint8) for f in frames]
    return small, (shapes - (factor - 1) / 2) / factor, factor


def region_mask(polygon: ArrayLike, shape: tuple[int, int]) -> NDArray[np.bool_]:
    """Pixels (h, w) whose centres lie inside ``polygon`` (N, 2)."""
    P = check_shapes(polygon, what="the layer's region")[0]
    check_inside(P, shape, "the layer's region")
    return fill_polygon(P, shape)


def _check_frames(frames) -> None:
    if len(frames) < 1:
        raise KeyShapeError("video capture needs at least one frame")
    first = np.asarray(frames[0])
    if first.dtype != np.uint8 or first.ndim != 3 or first.shape[2] != 3:
        raise KeyShapeError("frames must be RGB images, (h, w, 3) of bytes")
    if any(np.asarray(frame).shape != first.shape for frame in frames):
        raise KeyShapeError("every frame must be the same size")


