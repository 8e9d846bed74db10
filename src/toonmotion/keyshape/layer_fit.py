"""One frame of video capture (Bregler et al. 3.3, eq. 15-16): the layer's affine and eigen
weights fitted to the frame.

Each frame is started from the one before moved on at the same rate (the affines' constant
velocity), from the one before, and from the affine that matches the layer's area moments; each
start as it is and after a translation search on the pyramid's coarsest level, judged at full
resolution. The best is refined there: affine plus eigen weights by Levenberg-Marquardt on eq. 15
(forward additive, the frame's gradients by Gaussian derivatives, sigma 1), residuals weighed by
Huber's function and by how familiar each pixel's colour is (:func:`track_frame`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.image_model import ImageModel, layer_image
from toonmotion.keyshape.image_ops import (
    FloatArray,
    apply_affine,
    fill_polygon,
    gaussian_smooth,
    image_gradients,
    sample_at,
    square_affine,
)

ITERATIONS = 20  # Levenberg-Marquardt steps per solve, at most


SETTLED = 0.05  # px (at the level's scale): a step that moves no window corner further has converged


HUBER = 0.35  # Huber's function's knee, as a share of the layer's typical value in the layer image


SEEN = 0.2  # a start from which the frame shows less of the layer than this share is no start


WEIGHT_BOUND = 1.5  # eigen weights stay within +-this (the examples span +-1)


@dataclass(frozen=True)
class Level:
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
    def of(cls, model: ImageModel, level: int) -> Level:
        masks = [model.mask, model.core, model.inside]
        images = [gaussian_smooth(model.mean), *map(gaussian_smooth, model.eigen),
                  *(mask.astype(np.float32) for mask in masks)]
        for _ in range(level):
            images = [cv2.pyrDown(image) for image in images]
        mean, *eigen, mask, core, inside = images
        keep = mask > 0.05
        count = np.ones(mean.shape, np.float32)
        if level == 0:  # where the template is flat, one pixel in four stands for its block
            slope = np.zeros(mean.shape, np.float32)
            for image in (mean, *eigen):
                gx, gy = image_gradients(image)
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


def track_frame(rgb, matte, model, fine_level, coarse_level, starts, a):
    """One frame. Each start (``starts``, and the affine that matches the layer's area moments)
    as it is and moved by a translation search on the coarsest level; the one the finest level
    likes best is refined there, affine and weights together."""
    frame = _Frame(rgb, matte, [apply_affine(A, fine_level.corners) for A in starts], coarse_level.level + 1)
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
        image = gaussian_smooth(layer_image(crop, matte, self.matte))
        channels = [image, self.matte, gaussian_smooth(matte.familiar(crop))]
        self.pyramid = [cv2.merge(channels)]
        for _ in range(levels - 1):
            self.pyramid.append(cv2.pyrDown(self.pyramid[-1]))
        self.finest = cv2.merge([*channels, *image_gradients(image)])  # and d/dx, d/dy

    def at(self, points, A):
        """The five channels (layer image, matte, familiarity, d/dx, d/dy) at the template's
        ``points`` (n, 2) moved by ``A``: (5, n)."""
        X = points @ A[:, :2].T.astype(np.float32) + (A[:, 2] - self.offset).astype(np.float32)
        return sample_at(self.finest, X, border=(0, 0, 1, 0)).T  # off the frame: no layer, no occluder

    def warped(self, level, A):
        """The frame pulled back by ``A`` into the template's window, then brought down to
        ``level`` (so blurred in the template's coordinates, like the template, however ``A``
        stretches): layer image, matte and familiarity (h, w, 3)."""
        # From the frame's level two below (a quarter of the template's blur there: too little
        # to matter, and sixteen times fewer pixels to pull back at the coarsest levels).
        start = min(max(level.level - 2, 0), len(self.pyramid) - 1)
        step = 2.0**start
        M = square_affine(A) @ np.array([[step, 0, level.origin[0]], [0, step, level.origin[1]], [0, 0, 1]])
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

    level: Level
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
    placed = fill_polygon(apply_affine(near, shape) - frame.offset, (h, w))
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
        gu, gv = image_gradients(np.ascontiguousarray(image[..., 0]))
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
