"""Cartoon footage the package makes itself, with the true motion of every frame: test material
for key-shape capture (no public cartoon footage comes with ground truth).

:func:`bouncing_ball`: a flat-coloured ball bouncing across the frame with squash and stretch,
as cel animation draws it; its shape at every frame is an affine map of a circle, so its true
affine parameters (and a single key-shape weight of 1) are known exactly. Optional pixel noise
and an occluding bar that crosses the frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from toonmotion.errors import SettingsError


@dataclass(frozen=True)
class Cartoon:
    """Generated footage and its truth.

    Attributes
    ----------
    frames : (T, h, w, 3) uint8
    contours : (T, N, 2) float
        The shape's outline at every frame, points in correspondence.
    keys : (K, N, 2) float
        The key-shapes the motion is made of.
    affine : (T, 2, 3) float
    weights : (T, K) float
        The true motion model: ``contours[t] == warp(affine[t], weights[t], keys)``.
    fps : float
    """

    frames: NDArray[np.uint8]
    contours: NDArray[np.float64]
    keys: NDArray[np.float64]
    affine: NDArray[np.float64]
    weights: NDArray[np.float64]
    fps: float


def bouncing_ball(*, frames: int = 24, size: tuple[int, int] = (200, 200), radius: float = 24.0,
                  points: int = 64, noise: float = 0.0, occluder: bool = False, seed: int = 0,
                  fps: float = 12.0) -> Cartoon:
    """A ball bouncing left to right: stretched along its path while it falls, squashed flat on
    the ground, round at the top of each bounce (two bounces over ``frames``).

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> ball = bouncing_ball(frames=12)
    >>> model = warp(ball.affine[5], ball.weights[5], ball.keys)
    >>> ball.frames.shape, bool(np.allclose(model, ball.contours[5]))
    ((12, 200, 200, 3), True)
    """
    if not (isinstance(frames, int) and 2 <= frames <= 10_000):
        raise SettingsError(f"a generated cartoon has 2 to 10,000 frames, not {frames!r}")
    width, height = size
    angle = np.linspace(0, 2 * np.pi, points, endpoint=False)
    circle = radius * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    ground = height - 12.0
    t = np.linspace(0, 1, frames)
    phase = (2 * t) % 1.0  # two bounces
    fall = 4 * phase * (1 - phase)  # 0 on the ground, 1 at the top
    x = radius + 8 + t * (width - 2 * radius - 16)
    speed = np.abs(np.gradient(fall))  # vertical speed: stretch while moving fast
    stretch = 1 + 0.5 * speed / max(float(speed.max()), 1e-9)  # up to half as long again
    squash = 1 - 0.4 * (1 - fall / 0.2)  # flattened near the ground, 60% tall on it
    sy = np.where(fall < 0.2, squash, stretch)
    sx = 1 / sy  # the area stays the same
    y = ground - sy * radius - fall * (height - 2.5 * radius - 24)
    affine = np.zeros((frames, 2, 3))
    affine[:, 0, 0], affine[:, 1, 1] = sx, sy
    affine[:, 0, 2], affine[:, 1, 2] = x, y
    contours = np.einsum("tij,nj->tni", affine[:, :, :2], circle) + affine[:, None, :, 2]
    rng = np.random.default_rng(seed)
    images = np.empty((frames, height, width, 3), dtype=np.uint8)
    for k, contour in enumerate(contours):
        picture = Image.new("RGB", (width, height), (250, 246, 236))
        pen = ImageDraw.Draw(picture)
        pen.rectangle([0, ground, width, height], fill=(120, 170, 90))
        pen.polygon([tuple(p) for p in contour], fill=(220, 60, 50), outline=(40, 20, 20))
        if occluder:  # a bar crossing in front, right to left
            left = width * (1 - k / max(frames - 1, 1)) - 20
            pen.rectangle([left, 0, left + 14, height], fill=(60, 60, 160))
        array = np.asarray(picture, dtype=float)
        if noise > 0:
            array = array + rng.normal(0, noise, array.shape)
        images[k] = np.clip(np.rint(array), 0, 255).astype(np.uint8)
    return Cartoon(frames=images, contours=contours, keys=circle[None], affine=affine,
                   weights=np.ones((frames, 1)), fps=fps)
