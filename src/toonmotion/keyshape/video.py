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

*Key-images and eigen-images* (eq. 14-15). The key frames' shapes (contours in correspondence)
are put in the first key's frame by their least-squares affine; every pair gets ARAP
in-between shapes (:mod:`~toonmotion.keyshape.arap`), and the in-between image is the two key
images warped onto it piecewise-affinely (a Delaunay mesh of the shape and a ring of fixed
points round it) and cross-dissolved. PCA over key and in-between images gives a mean image
and ``eigen`` eigen-images; each is scaled so the examples' coefficients span [-1, 1], and the
shapes are regressed on the same coefficients, so every captured frame also has a shape.

*Tracking.* Each frame is started from the one before moved on at the same rate (the affines'
constant velocity), from the one before, and from the affine that matches the layer's area
moments; each start as it is and after a translation search on the pyramid's coarsest level,
judged at full resolution. The best is refined there: affine plus eigen weights by
Levenberg-Marquardt on eq. 15 (forward additive, the frame's gradients by Gaussian
derivatives, sigma 1). The intermediate levels were measured to add time, not accuracy
(docs/keyshapes.md). A layer more than ``LARGEST`` px across is captured on shrunk frames.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import Delaunay

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.matte import ColourMatte, fit_matte
from toonmotion.keyshape.model import check_shapes, fit_affine
from toonmotion.progress import Progress

FloatArray = NDArray[np.float64]
ITERATIONS = 20  # Levenberg-Marquardt steps per solve, at most
SETTLED = 0.05  # px (at the level's scale): a step that moves no window corner further has converged
HUBER = 0.35  # Huber's function's knee, as a share of the layer's typical value in the layer image
SEEN = 0.2  # a start from which the frame shows less of the layer than this share is no start
LARGEST = 200.0  # px: a layer wider or taller is captured on frames shrunk by a whole factor
WEIGHT_BOUND = 1.5  # eigen weights stay within +-this (the examples span +-1)


@dataclass(frozen=True, eq=False)
class ImageModel:
    """A layer's appearance model: mean and eigen-images over a window in the first key's frame.

    Attributes
    ----------
    origin : (2,) float
        Where the window's pixel (0, 0) is, in the first key frame's pixels.
    mean : (h, w) float32
    eigen : (L, h, w) float32
        The eigen-images, scaled so the examples' coefficients span [-1, 1].
    mask : (h, w) bool
        The template's pixels: the layer in any example, and a band round it.
    core : (h, w) bool
        Pixels inside the layer in every example, away from its edge: they count as much as the
        frame's matte says they belong to the layer.
    inside : (h, w) float32
        The share of the examples whose layer covers each pixel.
    shape_mean : (N, 2) float
    shape_eigen : (L, N, 2) float
        The shape that goes with each eigen-image's weight: the shape at weights ``a`` is
        ``shape_mean + a @ shape_eigen``.
    levels : int
        Pyramid levels: the coarsest (``levels - 1``) is where each start's translation is
        searched, the layer about 8 px across there.
    """

    origin: FloatArray
    mean: NDArray[np.float32]
    eigen: NDArray[np.float32]
    mask: NDArray[np.bool_]
    core: NDArray[np.bool_]
    inside: NDArray[np.float32]
    shape_mean: FloatArray
    shape_eigen: FloatArray
    levels: int

    def shape(self, weights: ArrayLike) -> FloatArray:
        """The shape (N, 2) at eigen weights ``weights`` (L,), in the first key's frame."""
        a = np.asarray(weights, dtype=float)
        return self.shape_mean + np.tensordot(a, self.shape_eigen, axes=1)


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


def layer_image(rgb: NDArray[np.uint8], matte: ColourMatte,
                belongs: NDArray[np.float32] | None = None) -> NDArray[np.float32]:
    """The image tracked: ``matte * (0.25 + 0.75 * grey)``, (h, w) float32 in [0, 1]
    (``belongs``: the matte, when already made)."""
    grey = cv2.cvtColor(np.ascontiguousarray(rgb), cv2.COLOR_RGB2GRAY).astype(np.float32) / 255
    layer = matte(rgb) if belongs is None else belongs
    return np.asarray(layer * (0.25 + 0.75 * grey), dtype=np.float32)


def build_image_model(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], key_frames: Sequence[int],
                      key_shapes: ArrayLike, matte: ColourMatte, *, closed: bool = True, inbetweens: int = 5,
                      eigen: int = 10) -> ImageModel:
    """The appearance model of a layer drawn as ``key_shapes`` (K, N, 2) at ``key_frames``.

    Examples
    --------
    >>> from toonmotion.sample_cartoons import bouncing_ball
    >>> from toonmotion.keyshape.matte import fit_matte
    >>> ball = bouncing_ball(frames=4)
    >>> matte = fit_matte(ball.frames[0], region_mask(ball.contours[0], ball.frames.shape[1:3]))
    >>> model = build_image_model(ball.frames, [0], ball.contours[:1], matte)
    >>> model.eigen.shape[0], model.mask.shape == model.mean.shape
    (0, True)
    """
    shapes = check_shapes(key_shapes, what="the key frames' shapes")
    keys = _key_frames(key_frames, len(frames), len(shapes))
    if not (isinstance(inbetweens, int) and 0 <= inbetweens <= 100):
        raise KeyShapeError(f"in-betweens per pair must be a whole number from 0 to 100, got {inbetweens!r}")
    if not (isinstance(eigen, int) and 0 <= eigen <= 100):
        raise KeyShapeError(f"eigen-images must be a whole number from 0 to 100, got {eigen!r}")
    height, width = np.asarray(frames[keys[0]]).shape[:2]
    for k, shape in zip(keys, shapes, strict=True):
        _check_inside(shape, (height, width), f"the layer's shape in key frame {k}")
    placed = [fit_affine(shape, shapes[0]) for shape in shapes]  # first key's frame -> key frame
    normal = np.stack([_apply(_inverse(A), shape) for A, shape in zip(placed, shapes, strict=True)])
    pictures = [layer_image(np.asarray(frames[k]), matte) for k in keys]
    # Each example: its shape, and the key images it cross-dissolves (share, key).
    examples: list[tuple[FloatArray, list[tuple[float, int]]]] = [(s, [(1.0, k)])
                                                                  for k, s in enumerate(normal)]
    if len(normal) > 1 and inbetweens:
        triangles = triangulate_shape(normal[0], closed=closed)
        ts = np.linspace(0, 1, inbetweens + 2)[1:-1]
        for i in range(len(normal)):
            for j in range(i + 1, len(normal)):
                pair = ArapPair(normal[i], normal[j], closed=closed, triangles=triangles)
                examples.extend((pair.at(t), [(1 - t, i), (t, j)]) for t in ts)
    every = np.concatenate([shape for shape, _ in examples])
    size = float(np.ptp(every, axis=0).max())
    band = max(4.0, 0.1 * size)
    low = np.floor(every.min(axis=0) - 2 * band)
    high = np.ceil(every.max(axis=0) + 2 * band)
    w, h = (high - low).astype(int) + 1
    if w * h > 4_000_000:
        raise KeyShapeError(f"the layer spans {w}x{h} px: video capture takes layers up to 2,000x2,000 px")
    ys, xs = np.mgrid[0:h, 0:w]
    grid = np.column_stack([xs.ravel(), ys.ravel()]).astype(float) + low
    ring = _ring(low - band, high + band)
    images = np.zeros((len(examples), h * w), dtype=np.float32)
    seen = np.ones(h * w, dtype=bool)  # window pixels every example saw inside its key frame
    for e, (shape, blend) in enumerate(examples):
        for share, k in blend:
            on_key = _piecewise_affine(np.vstack([shape, ring]), np.vstack([normal[k], ring]), grid)
            source = _apply(placed[k], on_key)
            images[e] += share * _sample(pictures[k], source)
            seen &= (source >= 0).all(axis=1) & (source[:, 0] <= width - 1) & (source[:, 1] <= height - 1)
    inside = [_fill(shape - low, (h, w)) for shape, _ in examples]
    union, common = np.logical_or.reduce(inside), np.logical_and.reduce(inside)
    radius = int(round(band))
    disc = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))
    mask = cv2.dilate(union.astype(np.uint8), disc).astype(bool) & seen.reshape(h, w)
    core = cv2.erode(common.astype(np.uint8), disc).astype(bool)
    mean, scaled, coefficients = _pca(images, eigen)
    shape_stack = np.stack([shape for shape, _ in examples]).reshape(len(examples), -1)
    shape_mean = shape_stack.mean(axis=0)
    if len(scaled):
        shape_eigen = np.linalg.lstsq(coefficients, shape_stack - shape_mean, rcond=None)[0]
    else:
        shape_eigen = np.zeros((0, shape_stack.shape[1]))
    smallest = float(np.ptp(normal[0], axis=0).max())
    levels = int(np.clip(np.floor(np.log2(max(smallest, 1.0) / 8)) + 1, 1, 5))
    return ImageModel(origin=low, mean=mean.reshape(h, w), eigen=scaled.reshape(-1, h, w), mask=mask,
                      core=core, inside=np.mean(inside, axis=0, dtype=np.float32),
                      shape_mean=shape_mean.reshape(-1, 2),
                      shape_eigen=shape_eigen.reshape(len(scaled), len(shapes[0]), 2), levels=levels)


def track_layer(frames: Sequence[NDArray[np.uint8]] | NDArray[np.uint8], model: ImageModel,
                matte: ColourMatte, *, start: ArrayLike | None = None, first: int = 0,
                progress: Callable[[], None] | None = None) -> VideoCapture:
    """Track the layer ``model`` describes through ``frames``, from frame ``first`` (at affine
    ``start``, the identity by default: the model is in that frame's pixels) to the last."""
    fine, coarse = _Level.of(model, 0), _Level.of(model, model.levels - 1)
    reach = float(np.ptp(fine.corners, axis=0).max())  # a window's size
    A = np.eye(2, 3) if start is None else np.array(start, dtype=float)
    a = np.zeros(len(model.eigen))
    affines: list[FloatArray] = []
    weights, shapes, residuals, iterations = [], [], [], []
    for t in range(first, len(frames)):
        rgb = np.asarray(frames[t])
        starts = [A]
        if len(affines) >= 2:  # moved on at the same rate, unless that flies off
            ahead = (_square(A) @ _inverse3(affines[-2]) @ _square(A))[:2]
            if np.abs(_apply(ahead, fine.corners) - _apply(A, fine.corners)).max() < reach:
                starts.insert(0, ahead)
        A, a, residual, steps = _track_frame(rgb, matte, model, fine, coarse, starts, a)
        affines.append(A)
        weights.append(a)
        shapes.append(_apply(A, model.shape(a)))
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
    keys = _key_frames(key_frames, len(frames), len(S))
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
    affine = np.stack([(grow @ _square(A) @ np.linalg.inv(grow))[:2] for A in found.affine])
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
    _check_inside(P, shape, "the layer's region")
    return _fill(P, shape)


@dataclass(frozen=True)
class _Level:
    """One pyramid level of the template: its pixels' places in the first key's frame."""

    level: int
    scale: float
    origin: FloatArray  # (2,) the window's pixel (0, 0), in the first key's frame
    full: tuple[int, int]  # the window's (h, w) at full size
    index: tuple[NDArray[np.int64], NDArray[np.int64]]  # the template's pixels in the level's image
    points: NDArray[np.float32]  # (n, 2)
    mean: NDArray[np.float32]  # (n,)
    eigen: NDArray[np.float32]  # (L, n)
    core: NDArray[np.bool_]  # (n,)
    corners: FloatArray  # (4, 2) the window's corners
    centre: NDArray[np.float32]  # (2,) the window's centre
    contrast: float  # the layer's typical value in the layer image
    layer: NDArray[np.float32]  # (n,) how far each pixel is the layer, in the mean template
    count: NDArray[np.float32]  # (n,) how many pixels each stands for (flat parts are thinned)

    @classmethod
    def of(cls, model: ImageModel, level: int) -> _Level:
        images = [_smooth(model.mean), *map(_smooth, model.eigen), model.mask.astype(np.float32),
                  model.core.astype(np.float32), model.inside.astype(np.float32)]
        for _ in range(level):
            images = [cv2.pyrDown(image) for image in images]
        mean, *eigen, mask, core, inside = images
        keep = mask > 0.05
        count = np.ones(mean.shape, np.float32)
        if level == 0:  # where the template is flat, one pixel in four stands for its block
            slope = np.zeros(mean.shape, np.float32)
            for image in (mean, *eigen):
                gx, gy = _gradients(image)
                slope = np.maximum(slope, np.hypot(gx, gy))
            flat = slope < 0.01 * max(float(np.abs(mean).max()), 1e-6)
            sparse = np.zeros_like(flat)
            sparse[::2, ::2] = True
            count[flat & sparse] = 4
            keep &= ~flat | sparse
        ys, xs = np.nonzero(keep)
        scale = 2.0**level
        points = (np.column_stack([xs, ys]) * scale + model.origin).astype(np.float32)
        h, w = model.mean.shape
        corners = model.origin + np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=float)
        return cls(level=level, scale=scale, origin=model.origin, full=model.mean.shape, index=(ys, xs),
                   points=points, mean=mean[keep],
                   eigen=np.array([e[keep] for e in eigen], dtype=np.float32).reshape(len(eigen), len(ys)),
                   core=core[keep] > 0.95, corners=corners, centre=corners.mean(axis=0).astype(np.float32),
                   contrast=float(np.median(model.mean[model.core])) if model.core.any() else 0.5,
                   layer=inside[keep], count=count[keep])


def _track_frame(rgb, matte, model, fine_level, coarse_level, starts, a):
    """One frame. Each start (``starts``, and the affine that matches the layer's area moments)
    as it is and moved by a translation search on the coarsest level; the one the finest level
    likes best is refined there, affine and weights together."""
    frame = _Frame(rgb, matte, [_apply(A, fine_level.corners) for A in starts], coarse_level.level + 1)
    moments = _moment_start(frame, model.shape(a), starts[0])
    robust = _Huber(HUBER * fine_level.contrast)
    fine, coarse = _Look(fine_level, frame, robust), _Look(coarse_level, frame, robust)
    steps, best = 0, None
    for start in [*starts, *([moments] if moments is not None else [])]:
        moved, b, _, taken = _solve(coarse, start, a, _TRANSLATION)
        steps += taken
        for A in (start, moved):
            cost, seen = _cost(fine, A, b, seen=True)
            # A window over empty background costs less than one half over the layer.
            if seen >= SEEN and (best is None or cost < best[0]):
                best = (cost, A, b)
    if best is None:
        raise KeyShapeError(f"video capture lost the layer: from no start does the frame show "
                            f"{SEEN:.0%} of it")
    _, A, a = best
    A, a, residual, taken = _solve(fine, A, a, np.arange(6 + len(a)))
    return A, a, residual, steps + taken


class _Frame:
    """A frame's layer image, matte and familiarity (how far each pixel's colour is the layer's
    or its surroundings', not an occluder's), over the part of the frame the windows cover; the
    layer image's gradients; and a pyramid of the three."""

    def __init__(self, rgb, matte, windows, levels):
        corners = np.concatenate(windows)
        margin = 0.5 * float(np.ptp(corners, axis=0).max()) + 16
        height, width = rgb.shape[:2]
        x0, y0 = (int(np.clip(np.floor(v - margin), 0, limit - 1)) for v, limit in
                  zip(corners.min(axis=0), (width, height), strict=True))
        x1 = int(np.clip(np.ceil(corners[:, 0].max() + margin), x0 + 1, width))
        y1 = int(np.clip(np.ceil(corners[:, 1].max() + margin), y0 + 1, height))
        if x1 - x0 < 8 or y1 - y0 < 8:
            x0, y0, x1, y1 = 0, 0, width, height  # lost outside the frame: look everywhere
        crop = np.ascontiguousarray(rgb[y0:y1, x0:x1])
        self.offset = np.array([x0, y0], dtype=float)
        self.matte = matte(crop)
        image = _smooth(layer_image(crop, matte, self.matte))
        channels = [image, self.matte, _smooth(matte.familiar(crop))]
        self.pyramid = [cv2.merge(channels)]
        for _ in range(levels - 1):
            self.pyramid.append(cv2.pyrDown(self.pyramid[-1]))
        self.finest = cv2.merge([*channels, *_gradients(image)])  # and d/dx, d/dy

    def at(self, points, A):
        """The five channels (layer image, matte, familiarity, d/dx, d/dy) at the template's
        ``points`` (n, 2) moved by ``A``: (5, n)."""
        X = points @ A[:, :2].T.astype(np.float32) + (A[:, 2] - self.offset).astype(np.float32)
        return _sample(self.finest, X, border=(0, 0, 1, 0)).T  # off the frame: no layer, no occluder

    def warped(self, level, A):
        """The frame pulled back by ``A`` into the template's window, then brought down to
        ``level`` (so blurred in the template's coordinates, like the template, however ``A``
        stretches): layer image, matte and familiarity (h, w, 3)."""
        # From the frame's level two below (a quarter of the template's blur there: too little
        # to matter, and sixteen times fewer pixels to pull back at the coarsest levels).
        start = min(max(level.level - 2, 0), len(self.pyramid) - 1)
        step = 2.0**start
        M = _square(A) @ np.array([[step, 0, level.origin[0]], [0, step, level.origin[1]], [0, 0, 1]])
        M[:2, 2] -= self.offset
        M[:2] /= step  # into the frame's level
        h, w = level.full
        size = (-(-w // int(step)), -(-h // int(step)))
        image = cv2.warpAffine(self.pyramid[start], M[:2], size,  # off the frame: no layer, no occluder
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_CONSTANT,
                               borderValue=(0, 0, 1))
        for _ in range(level.level - start):
            image = cv2.pyrDown(image)
        return image


@dataclass(frozen=True)
class _Look:
    """Where :func:`_linearise` looks: a template level, a frame, a robust function."""

    level: _Level
    frame: _Frame
    robust: _Huber


class _Huber:
    def __init__(self, scale):
        self.k = self.scale = scale

    def weight(self, size):
        return np.minimum(1, self.k / np.maximum(size, 1e-12)).astype(np.float32)

    def cost(self, size, count):
        rho = np.where(size <= self.k, 0.5 * size * size, self.k * (size - 0.5 * self.k))
        return float((rho * count).sum())


def _moment_start(frame, shape, near):
    """The affine that takes ``shape``'s area moments (mean, covariance) onto those of the
    layer's blobs in the frame (those ``near`` puts the shape over, else the largest), turned as
    near to ``near`` as the moments allow; None when no blob is seen."""
    count, labels, stats, _ = cv2.connectedComponentsWithStats((frame.matte > 0.5).astype(np.uint8),
                                                               connectivity=8)
    if count < 2:
        return None
    h, w = frame.matte.shape
    placed = _fill(_apply(near, shape) - frame.offset, (h, w))
    overlap = np.bincount(labels[placed], minlength=count)[1:]
    blobs = 1 + (np.flatnonzero(overlap) if overlap.max() > 0 else
                 np.array([int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))]))
    seen = _moments(cv2.moments(np.isin(labels, blobs).astype(np.uint8), binaryImage=True), frame.offset)
    drawn = _moments(cv2.moments(shape.astype(np.float32)), np.zeros(2))
    if seen is None or drawn is None:
        return None
    (frame_mean, frame_cov), (shape_mean, shape_cov) = seen, drawn
    root_f, root_s = _sqrtm(frame_cov), _sqrtm(shape_cov)
    U, _, Vt = np.linalg.svd(np.linalg.inv(root_f) @ near[:, :2] @ root_s)  # the nearest turn
    if np.linalg.det(U @ Vt) < 0:
        U[:, 1] *= -1
    linear = root_f @ U @ Vt @ np.linalg.inv(root_s)
    return np.column_stack([linear, frame_mean - linear @ shape_mean])


def _moments(m, offset):
    """Mean and covariance from OpenCV's moments ``m``; None for an area under 6 px."""
    if abs(m["m00"]) < 6:
        return None
    mean = np.array([m["m10"], m["m01"]]) / m["m00"] + offset
    cov = np.array([[m["mu20"], m["mu11"]], [m["mu11"], m["mu02"]]]) / m["m00"]
    return mean, cov + np.eye(2) / 12  # a pixel's own spread


def _sqrtm(C):
    values, vectors = np.linalg.eigh(C)
    return vectors @ np.diag(np.sqrt(np.maximum(values, 1e-12))) @ vectors.T


_TRANSLATION = np.array([2, 5])


def _solve(look, A, a, free):
    """Levenberg-Marquardt on one level: a step is taken only if it lowers the robust cost."""
    level = look.level
    H, g, cost, residual = _linearise(look, A, a, free)
    damping, steps = 1e-3, 0
    for _ in range(ITERATIONS):
        steps += 1
        delta = np.zeros(6 + len(a))
        delta[free] = np.linalg.solve(H + damping * np.diag(np.diag(H)), -g)
        delta[[2, 5]] -= delta[[0, 3]] * level.centre[0] + delta[[1, 4]] * level.centre[1]  # uncentred
        step = delta[:6].reshape(2, 3)
        moved = float(np.abs(level.corners @ step[:, :2].T + step[:, 2]).max())
        trial_A, trial_a = A + step, np.clip(a + delta[6:], -WEIGHT_BOUND, WEIGHT_BOUND)
        trial = _linearise(look, trial_A, trial_a, free)
        if trial[2] <= cost:
            A, a = trial_A, trial_a
            H, g, cost, residual = trial
            damping = max(damping / 4, 1e-6)
        else:
            damping *= 8
        if moved < SETTLED * level.scale or damping > 1e6:
            break
    return A, a, residual, steps


def _cost(look, A, a, *, seen=False):
    """The robust cost of :func:`_linearise` alone; with ``seen``, also the share of the
    template's layer that the frame's matte shows, or leaves to an occluder, there."""
    r, belongs, familiar, _ = _residual(look, A, a, slopes=False)
    cost = _counted(look, np.abs(r), familiar)
    if not seen:
        return cost
    layer = look.level.layer * look.level.count
    shown = float((np.maximum(belongs, 1 - familiar) * layer).sum() / max(float(layer.sum()), 1e-12))
    return cost, shown


def _residual(look, A, a, *, slopes):
    """At the template's pixels: the residual against the template at weights ``a``, the
    frame's matte and familiarity, and (with ``slopes``) its gradients d/dx, d/dy. The finest
    level samples the frame at the moved pixels; a coarser one pulls the frame's pyramid back
    into the window, where the gradients are ``grad(I o A) A^-1``."""
    level = look.level
    model = level.mean + a.astype(np.float32) @ level.eigen if len(a) else level.mean
    if level.level == 0:
        value, belongs, familiar, ix, iy = look.frame.at(level.points, A)
        return value - model, belongs, familiar, (ix, iy)
    image = look.frame.warped(level, A)
    ys, xs = level.index
    value, belongs, familiar = image[ys, xs].T
    gradients = None
    if slopes:
        gu, gv = _gradients(np.ascontiguousarray(image[..., 0]))
        inverse = np.linalg.inv(A[:, :2]).astype(np.float32) / np.float32(level.scale)
        gu, gv = gu[ys, xs], gv[ys, xs]
        gradients = (gu * inverse[0, 0] + gv * inverse[1, 0], gu * inverse[0, 1] + gv * inverse[1, 1])
    return value - model, belongs, familiar, gradients


def _counted(look, size, familiar):
    """The cost that accepts steps. Every pixel counts, not weighed by the matte (a window that
    slid off the layer would look cheap); a pixel of an unseen colour (an occluder) costs a
    small constant whatever the residual, so an occluder neither pulls nor hides the layer."""
    robust = look.robust
    return robust.cost(size * familiar + (1 - familiar) * 0.25 * robust.scale, look.level.count)


def _linearise(look, A, a, free):
    """Eq. 15 linearised at ``A``, ``a``: the normal equations (in the window-centred affine and
    the weights of ``free``), the robust cost and the rms weighted residual."""
    level, robust = look.level, look.robust
    r, belongs, familiar, (ix, iy) = _residual(look, A, a, slopes=True)
    trust = np.where(level.core, belongs, familiar)
    size = np.abs(r)
    weight = trust * robust.weight(size) * level.count
    cost = _counted(look, size, familiar)
    P = level.points
    px, py = P[:, 0] - level.centre[0], P[:, 1] - level.centre[1]  # centred: well conditioned
    J = np.column_stack([ix * px, ix * py, ix, iy * px, iy * py, iy, -level.eigen.T])[:, free]
    Jw = J * weight[:, None]
    H = (Jw.T @ J).astype(np.float64)
    H[np.diag_indices_from(H)] += 1e-9 * max(float(np.trace(H)), 1e-12)
    g = (Jw.T @ r).astype(np.float64)
    residual = float(np.sqrt((weight * r * r).sum() / max(float(weight.sum()), 1e-12)))
    return H, g, cost, residual


_RADIUS = 3
_TAPS = np.arange(-_RADIUS, _RADIUS + 1, dtype=np.float64)
_GAUSS = np.exp(-0.5 * _TAPS**2)
_SMOOTH = (_GAUSS / _GAUSS.sum()).astype(np.float32)
_DERIVATIVE = (_TAPS * _GAUSS / (_TAPS**2 * _GAUSS).sum()).astype(np.float32)  # correlation: a ramp's slope


def _smooth(image):
    """Gaussian blur, sigma 1: drawn edges are steps, and Gauss-Newton needs slopes to follow."""
    return cv2.sepFilter2D(np.ascontiguousarray(image, dtype=np.float32), cv2.CV_32F, _SMOOTH, _SMOOTH,
                           borderType=cv2.BORDER_CONSTANT)


def _gradients(image):
    """Gaussian-derivative gradients (sigma 1) of ``image``: d/dx, d/dy per pixel."""
    gx = cv2.sepFilter2D(image, cv2.CV_32F, _DERIVATIVE, _SMOOTH, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.sepFilter2D(image, cv2.CV_32F, _SMOOTH, _DERIVATIVE, borderType=cv2.BORDER_REPLICATE)
    return gx, gy


def _pca(images, eigen):
    """Mean image, eigen-images scaled so the examples' coefficients span [-1, 1], and those
    coefficients (E, L)."""
    mean = images.mean(axis=0)
    centred = (images - mean).astype(np.float64)
    if eigen == 0 or len(images) < 2:
        return mean, np.zeros((0, images.shape[1]), np.float32), np.zeros((len(images), 0))
    _, sigma, Vt = np.linalg.svd(centred, full_matrices=False)
    keep = int(min(eigen, (sigma > 1e-6 * max(float(sigma[0]), 1e-300)).sum()))
    basis = Vt[:keep]
    coefficients = centred @ basis.T
    scale = np.abs(coefficients).max(axis=0)
    scale[scale == 0] = 1.0
    return mean, (basis * scale[:, None]).astype(np.float32), coefficients / scale


def _piecewise_affine(source: FloatArray, target: FloatArray, points: FloatArray) -> FloatArray:
    """``points`` moved by the piecewise-affine map of ``source``'s Delaunay mesh onto ``target``."""
    mesh = Delaunay(source)
    simplex = mesh.find_simplex(points)
    simplex[simplex < 0] = 0  # outside the ring: cannot happen for the window's pixels
    T = mesh.transform[simplex]
    b = np.einsum("nij,nj->ni", T[:, :2], points - T[:, 2])
    bary = np.column_stack([b, 1 - b.sum(axis=1)])
    return np.einsum("ni,nij->nj", bary, target[mesh.simplices[simplex]])


def _ring(low: FloatArray, high: FloatArray) -> FloatArray:
    """Fixed points round the window: corners and edge thirds."""
    t = np.linspace(0, 1, 4)[:-1]
    (x0, y0), (x1, y1) = low, high
    top = np.column_stack([x0 + t * (x1 - x0), np.full(3, y0)])
    right = np.column_stack([np.full(3, x1), y0 + t * (y1 - y0)])
    bottom = np.column_stack([x1 - t * (x1 - x0), np.full(3, y1)])
    left = np.column_stack([np.full(3, x0), y1 - t * (y1 - y0)])
    return np.vstack([top, right, bottom, left])


def _sample(image: NDArray[np.float32], points: ArrayLike, border: Sequence[float] = (0,)
            ) -> NDArray[np.float32]:
    """``image``'s channels at ``points`` (n, 2), bilinearly: (n,) or (n, channels); ``border``
    outside the image."""
    P = np.asarray(points, dtype=np.float32)
    n = len(P)
    rows = -(-n // 1024)  # OpenCV's maps must be under 32,767 a side
    flat = np.zeros((rows * 1024, 2), np.float32)
    flat[:n] = P
    m = flat.reshape(rows, 1024, 2)
    out = cv2.remap(image, m[..., 0].copy(), m[..., 1].copy(), cv2.INTER_LINEAR,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=tuple(border))
    return np.asarray(out.reshape(rows * 1024, -1)[:n].squeeze(axis=1) if out.ndim == 2 else
                      out.reshape(rows * 1024, -1)[:n], dtype=np.float32)


def _fill(polygon: FloatArray, shape: tuple[int, int]) -> NDArray[np.bool_]:
    canvas = np.zeros(shape, np.uint8)
    cv2.fillPoly(canvas, [np.rint(polygon * 16).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=4)
    return canvas.astype(bool)


def _check_inside(shape: FloatArray, frame: tuple[int, int], what: str) -> None:
    h, w = frame
    low, high = shape.min(axis=0), shape.max(axis=0)
    if high[0] < 0 or high[1] < 0 or low[0] >= w or low[1] >= h:
        raise KeyShapeError(f"{what} lies outside the {w}x{h} frame")


def _check_frames(frames) -> None:
    if len(frames) < 1:
        raise KeyShapeError("video capture needs at least one frame")
    first = np.asarray(frames[0])
    if first.dtype != np.uint8 or first.ndim != 3 or first.shape[2] != 3:
        raise KeyShapeError("frames must be RGB images, (h, w, 3) of bytes")
    if any(np.asarray(frame).shape != first.shape for frame in frames):
        raise KeyShapeError("every frame must be the same size")


def _key_frames(key_frames: Sequence[int], count: int, shapes: int) -> list[int]:
    keys = [int(k) for k in key_frames]
    if len(set(keys)) != len(keys):
        raise KeyShapeError(f"the key frames {keys} name a frame twice")
    if len(keys) != shapes:
        raise KeyShapeError(f"give one shape per key frame: {len(keys)} key frames, {shapes} shapes")
    for k in keys:
        if not 0 <= k < count:
            raise KeyShapeError(f"key frame {k} is outside the sequence's {count} frames (0 to {count - 1})")
    return keys


def _apply(A: FloatArray, points: FloatArray) -> FloatArray:
    return np.asarray(np.asarray(points, dtype=float) @ np.asarray(A)[:2, :2].T + np.asarray(A)[:2, 2],
                      dtype=float)


def _square(A: FloatArray) -> FloatArray:
    return np.vstack([A[:2], [0.0, 0.0, 1.0]])


def _inverse3(A: FloatArray) -> FloatArray:
    return np.asarray(np.linalg.inv(_square(A)), dtype=float)


def _inverse(A: FloatArray) -> FloatArray:
    return _inverse3(A)[:2]
