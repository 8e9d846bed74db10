"""The pixel and affine helpers of video capture (:mod:`toonmotion.keyshape.video`): Gaussian
smoothing and derivatives (sigma 1), bilinear sampling, polygons filled, and affines as 2 x 3
matrices (applied, squared up to 3 x 3, inverted)."""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError

FloatArray = NDArray[np.float64]


_RADIUS = 3


_TAPS = np.arange(-_RADIUS, _RADIUS + 1, dtype=np.float64)


_GAUSS = np.exp(-0.5 * _TAPS**2)


_SMOOTH = (_GAUSS / _GAUSS.sum()).astype(np.float32)


_DERIVATIVE = (_TAPS * _GAUSS / (_TAPS**2 * _GAUSS).sum()).astype(np.float32)  # correlation: a ramp's slope


def gaussian_smooth(image):
    """Gaussian blur, sigma 1: drawn edges are steps, and Gauss-Newton needs slopes to follow."""
    return cv2.sepFilter2D(np.ascontiguousarray(image, dtype=np.float32), cv2.CV_32F, _SMOOTH, _SMOOTH,
                           borderType=cv2.BORDER_CONSTANT)


def image_gradients(image):
    """Gaussian-derivative gradients (sigma 1) of ``image``: d/dx, d/dy per pixel."""
    gx = cv2.sepFilter2D(image, cv2.CV_32F, _DERIVATIVE, _SMOOTH, borderType=cv2.BORDER_REPLICATE)
    gy = cv2.sepFilter2D(image, cv2.CV_32F, _SMOOTH, _DERIVATIVE, borderType=cv2.BORDER_REPLICATE)
    return gx, gy


def sample_at(image: NDArray[np.float32], points: ArrayLike, border: Sequence[float] = (0,)
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


def fill_polygon(polygon: FloatArray, shape: tuple[int, int]) -> NDArray[np.bool_]:
    canvas = np.zeros(shape, np.uint8)
    cv2.fillPoly(canvas, [np.rint(polygon * 16).astype(np.int32)], 1, lineType=cv2.LINE_8, shift=4)
    return canvas.astype(bool)


def check_inside(shape: FloatArray, frame: tuple[int, int], what: str) -> None:
    h, w = frame
    low, high = shape.min(axis=0), shape.max(axis=0)
    if high[0] < 0 or high[1] < 0 or low[0] >= w or low[1] >= h:
        raise KeyShapeError(f"{what} lies outside the {w}x{h} frame")


def apply_affine(A: FloatArray, points: FloatArray) -> FloatArray:
    return np.asarray(np.asarray(points, dtype=float) @ np.asarray(A)[:2, :2].T + np.asarray(A)[:2, 2],
                      dtype=float)


def square_affine(A: FloatArray) -> FloatArray:
    return np.vstack([A[:2], [0.0, 0.0, 1.0]])


def inverse3(A: FloatArray) -> FloatArray:
    return np.asarray(np.linalg.inv(square_affine(A)), dtype=float)


def inverse_affine(A: FloatArray) -> FloatArray:
    return inverse3(A)[:2]
