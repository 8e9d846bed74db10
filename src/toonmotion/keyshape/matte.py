"""A layer's colour matte (Bregler et al. 3.3, eq. 16): the probability that a pixel belongs to a
cartoon layer, from its colour; and picking a layer by its colour.

Two Gaussian mixtures (OpenCV's EM) are fitted on one frame: one on the layer's pixels, one on
the rest; a third, uniform "anything else" model takes colours neither has seen (an occluder
that enters later). The posterior of the layer is tabulated on a 32³ colour grid once, so a
frame's matte is a table look-up.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.model import resample_contour

BINS = 32  # per colour channel
SAMPLES = 4000  # pixels each mixture is fitted on, at most
# The "anything else" density: a colour this many times less likely under the layer's mixture
# than a colour spread evenly over the colour cube would be.
UNSEEN = 1.0


@dataclass(frozen=True, eq=False)
class ColourMatte:
    """The posteriors, tabulated on colours ``[r // 8, g // 8, b // 8]``: ``table`` of the layer,
    ``known`` of the layer or its surroundings (low for a colour neither model has seen: an
    occluder)."""

    table: NDArray[np.float32]
    known: NDArray[np.float32]

    def __call__(self, rgb: NDArray[np.uint8]) -> NDArray[np.float32]:
        """The matte (h, w) float32 of an (h, w, 3) uint8 image."""
        q = rgb >> 3  # 256 / BINS
        return self.table[q[..., 0], q[..., 1], q[..., 2]]

    def familiar(self, rgb: NDArray[np.uint8]) -> NDArray[np.float32]:
        """How likely each pixel is the layer or its surroundings rather than something else."""
        q = rgb >> 3
        return self.known[q[..., 0], q[..., 1], q[..., 2]]


def fit_matte(rgb: ArrayLike, layer: ArrayLike, *, components: int = 3, surround: float | None = 0.5,
              seed: int = 0) -> ColourMatte:
    """The colour matte of the layer ``layer`` (h, w) bool marks in ``rgb`` (h, w, 3) uint8.

    A band of two pixels round the layer's edge is left out of both fits (anti-aliased and
    outline colours belong to neither). The other model is fitted on the layer's surroundings,
    within ``surround`` times its size (None: the whole frame); colours seen neither there nor
    on the layer are "unseen" (:meth:`ColourMatte.familiar` is low): occluders, as a rule.

    Examples
    --------
    >>> image = np.zeros((40, 40, 3), np.uint8); image[...] = (240, 240, 230)
    >>> image[10:30, 10:30] = (200, 40, 40)
    >>> matte = fit_matte(image, np.pad(np.ones((20, 20), bool), 10))(image)
    >>> float(matte[20, 20]) > 0.99, float(matte[2, 2]) < 0.01
    (True, True)
    """
    image = np.asarray(rgb)
    mask = np.asarray(layer, dtype=bool)
    if image.ndim != 3 or image.shape[2] != 3 or mask.shape != image.shape[:2]:
        raise KeyShapeError("the layer's mask must be the frame's size")
    inside = ndimage.binary_erosion(mask, iterations=2)
    outside = ~ndimage.binary_dilation(mask, iterations=2)
    if surround is not None:  # the surroundings only: what else is in the frame is "unseen"
        ys, xs = np.nonzero(mask)
        reach = max(4, int(round(surround * max(int(np.ptp(xs)), int(np.ptp(ys)), 1))))
        outside &= ndimage.binary_dilation(mask, iterations=reach)
    if inside.sum() < 8:
        raise KeyShapeError("the layer's region holds too few pixels to learn its colours (fewer than 8 "
                            "away from its edge)")
    rng = np.random.default_rng(seed)
    grid = (np.stack(np.meshgrid(*[np.arange(BINS)] * 3, indexing="ij"), axis=-1).reshape(-1, 3) + 0.5) * 8
    layer_density = _mixture(image[inside], components, rng)(grid)
    unseen = UNSEEN / 256.0**3
    if outside.sum() >= 8:
        rest_density = _mixture(image[outside], components + 2, rng)(grid)
    else:  # the layer fills the frame
        rest_density = np.zeros_like(layer_density)
    total = layer_density + rest_density + unseen
    cube = (BINS, BINS, BINS)
    return ColourMatte(table=(layer_density / total).reshape(cube).astype(np.float32),
                       known=((layer_density + rest_density) / total).reshape(cube).astype(np.float32))


def _mixture(pixels, components, rng):
    """A Gaussian mixture fitted to ``pixels`` (n, 3); returns its density function."""
    colours = np.asarray(pixels, dtype=np.float64)
    if len(colours) > SAMPLES:
        colours = colours[rng.choice(len(colours), SAMPLES, replace=False)]
    colours = colours + rng.normal(0, 1.0, colours.shape)  # flat colours: keep covariances invertible
    k = int(min(components, max(1, len(np.unique(np.rint(colours / 8), axis=0)))))
    em = cv2.ml.EM_create()
    em.setClustersNumber(k)
    em.setCovarianceMatrixType(cv2.ml.EM_COV_MAT_GENERIC)
    em.setTermCriteria((cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-4))
    cv2.setRNGSeed(int(rng.integers(1 << 30)))
    em.trainEM(colours)
    means, weights = em.getMeans(), em.getWeights().ravel()
    covariances = [c + np.eye(3) * 4.0 for c in em.getCovs()]  # at least 2 grey levels of spread

    def density(x):
        total = np.zeros(len(x))
        for mean, cov, weight in zip(means, covariances, weights, strict=True):
            d = x - mean
            inverse = np.linalg.inv(cov)
            exponent = -0.5 * np.einsum("ni,ij,nj->n", d, inverse, d)
            total += weight * np.exp(exponent) / np.sqrt((2 * np.pi) ** 3 * np.linalg.det(cov))
        return total

    return density


# How far a picked layer's colours may stray from the one picked, in steps of the tolerance.
SEED_REACH = 3


def pick_layer(rgb: ArrayLike, point: ArrayLike, *, tolerance: int = 24, points: int = 100
               ) -> NDArray[np.float64]:
    """The outline (``points``, 2) of the layer under ``point`` (x, y): the connected region of
    colours within ``tolerance`` of their neighbours (a flood fill), holes filled, resampled by
    arc length from its topmost point. A layer cut in two by another colour gives only the part
    picked: draw its outline instead.

    Examples
    --------
    >>> image = np.zeros((40, 40, 3), np.uint8); image[10:30, 5:25] = (200, 40, 40)
    >>> outline = pick_layer(image, (15, 15), points=8)
    >>> outline.shape, bool(outline[:, 0].min() >= 4.5 and outline[:, 0].max() <= 24.5)
    ((8, 2), True)
    """
    image = np.ascontiguousarray(np.asarray(rgb, dtype=np.uint8)[..., :3])
    x, y = (int(round(float(v))) for v in np.asarray(point, dtype=float))
    h, w = image.shape[:2]
    if not (0 <= x < w and 0 <= y < h):
        raise KeyShapeError(f"the picked point ({x}, {y}) is outside the {w}x{h} frame")
    mask = np.zeros((h + 2, w + 2), np.uint8)
    flags = 8 | cv2.FLOODFILL_MASK_ONLY | (1 << 8)
    cv2.floodFill(image.copy(), mask, (x, y), (0, 0, 0), (tolerance,) * 3, (tolerance,) * 3, flags)
    # Step by step, a fill can creep through an outline's soft edge into the next colour and round
    # the whole figure (an outlined cartoon's jeans picked the whole character): it keeps only the
    # colours within SEED_REACH steps of the one picked, joined to the point.
    near = np.abs(image.astype(np.int16) - image[y, x].astype(np.int16)).max(axis=2) <= SEED_REACH * tolerance
    labels, _ = ndimage.label(mask[1:-1, 1:-1].astype(bool) & near, structure=np.ones((3, 3)))
    region = ndimage.binary_fill_holes(labels == labels[y, x])
    if region.sum() < 16:
        raise KeyShapeError(f"the region picked at ({x}, {y}) is under 16 px: pick inside the layer")
    if region.all():
        raise KeyShapeError(f"the colour picked at ({x}, {y}) fills the frame: pick the layer, not the "
                            "background")
    outlines, _ = cv2.findContours(region.astype(np.uint8), cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    centres = max(outlines, key=cv2.contourArea)[:, 0, :].astype(float)
    # The traced outline runs through the edge pixels' centres: half a pixel out is the edge.
    edge = shapely.Polygon(centres).buffer(0.5, join_style="mitre")
    outline = np.asarray(max(getattr(edge, "geoms", [edge]), key=lambda g: g.area).exterior.coords)[:-1]
    top = outline[np.argmin(outline[:, 1])]
    return resample_contour(outline, points, start=top)
