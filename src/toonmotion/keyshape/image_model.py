"""Key-images and eigen-images (Bregler et al. 3.3, eq. 14-15): the layer image of a frame, and
the model video capture fits (:class:`ImageModel`).

The key frames' shapes (contours in correspondence) are put in the first key's frame by their
least-squares affine; every pair gets ARAP in-between shapes (:mod:`~toonmotion.keyshape.arap`),
and the in-between image is the two key images warped onto it piecewise-affinely (a Delaunay
mesh of the shape and a ring of fixed points round it) and cross-dissolved. PCA over key and
in-between images gives a mean image and ``eigen`` eigen-images; each is scaled so the
examples' coefficients span [-1, 1], and the shapes are regressed on the same coefficients, so
every captured frame also has a shape.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import Delaunay

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.image_ops import (
    FloatArray,
    apply_affine,
    check_inside,
    fill_polygon,
    inverse_affine,
    sample_at,
)
from toonmotion.keyshape.matte import ColourMatte
from toonmotion.keyshape.model import check_shapes, fit_affine


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
    >>> from toonmotion.keyshape.video import region_mask
    >>> ball = bouncing_ball(frames=4)
    >>> matte = fit_matte(ball.frames[0], region_mask(ball.contours[0], ball.frames.shape[1:3]))
    >>> model = build_image_model(ball.frames, [0], ball.contours[:1], matte)
    >>> model.eigen.shape[0], model.mask.shape == model.mean.shape
    (0, True)
    """
    shapes = check_shapes(key_shapes, what="the key frames' shapes")
    keys = key_frame_indices(key_frames, len(frames), len(shapes))
    if not (isinstance(inbetweens, int) and 0 <= inbetweens <= 100):
        raise KeyShapeError(f"in-betweens per pair must be a whole number from 0 to 100, got {inbetweens!r}")
    if not (isinstance(eigen, int) and 0 <= eigen <= 100):
        raise KeyShapeError(f"eigen-images must be a whole number from 0 to 100, got {eigen!r}")
    height, width = np.asarray(frames[keys[0]]).shape[:2]
    for k, shape in zip(keys, shapes, strict=True):
        check_inside(shape, (height, width), f"the layer's shape in key frame {k}")
    placed = [fit_affine(shape, shapes[0]) for shape in shapes]  # first key's frame -> key frame
    normal = np.stack([apply_affine(inverse_affine(A), shape)
                       for A, shape in zip(placed, shapes, strict=True)])
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
            source = apply_affine(placed[k], on_key)
            images[e] += share * sample_at(pictures[k], source)
            seen &= (source >= 0).all(axis=1) & (source[:, 0] <= width - 1) & (source[:, 1] <= height - 1)
    inside = [fill_polygon(shape - low, (h, w)) for shape, _ in examples]
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


def key_frame_indices(key_frames: Sequence[int], count: int, shapes: int) -> list[int]:
    keys = [int(k) for k in key_frames]
    if len(set(keys)) != len(keys):
        raise KeyShapeError(f"the key frames {keys} name a frame twice")
    if len(keys) != shapes:
        raise KeyShapeError(f"give one shape per key frame: {len(keys)} key frames, {shapes} shapes")
    for k in keys:
        if not 0 <= k < count:
            raise KeyShapeError(f"key frame {k} is outside the sequence's {count} frames (0 to {count - 1})")
    return keys
