"""Cartoon footage the package makes itself, with the true motion of every frame: test material
for key-shape capture (no public cartoon footage comes with ground truth).

:func:`bouncing_ball`: a flat-coloured ball with a stripe bouncing across the frame with
squash and stretch, as cel animation draws it; its shape at every frame is an affine map of a
circle, so its true affine parameters (and a single key-shape weight of 1) are known exactly.

:func:`morphing_character`: a flat-coloured character with an eye morphing between three
key-shapes (:func:`character_keys`) by as-rigid-as-possible in-betweens while it hops across
the frame, drawn on twos; its outline at every frame is known.

Both take optional pixel noise and an occluding bar that crosses the frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
import shapely.affinity
from numpy.typing import NDArray
from PIL import Image, ImageDraw

from toonmotion.errors import SettingsError

BALL, STRIPE = (220, 60, 50), (240, 200, 40)


def ball_stripe(radius: float) -> NDArray[np.float64]:
    """The ball's stripe (a band across it, a third of its width, off its centre and turned 30
    degrees), a polygon about the ball's centre: it shows the ball's turn, which a plain disc
    (or a band through the centre, the same upside down) would hide."""
    disc = shapely.Point(0, 0).buffer(radius, quad_segs=32)
    band = shapely.box(-radius * 2, radius / 6, radius * 2, radius / 2)
    band = shapely.affinity.rotate(band, 30, origin=(0, 0))
    return np.asarray(disc.intersection(band).exterior.coords, dtype=float)[:-1]


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
        The key weights: ``contours[t] == warp(affine[t], weights[t], keys)`` for the ball; for
        the morphing character, the shape is the as-rigid-as-possible in-between of the two
        keys these weights share out (not their linear blend).
    fps : float
    key_frames : (K,) int
        A frame where each key is drawn as it is (its affine applied).
    """

    frames: NDArray[np.uint8]
    contours: NDArray[np.float64]
    keys: NDArray[np.float64]
    affine: NDArray[np.float64]
    weights: NDArray[np.float64]
    fps: float
    key_frames: tuple[int, ...] = (0,)


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
    x = 1.7 * radius + 8 + t * (width - 3.4 * radius - 16)  # squashed 1 / 0.6 wide: inside the frame
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
    stripe = ball_stripe(radius)
    rng = np.random.default_rng(seed)
    images = np.empty((frames, height, width, 3), dtype=np.uint8)
    for k, contour in enumerate(contours):
        picture = Image.new("RGB", (width, height), PAPER)
        pen = ImageDraw.Draw(picture)
        pen.rectangle([0, ground, width, height], fill=(120, 170, 90))
        pen.polygon([tuple(p) for p in contour], fill=BALL, outline=(40, 20, 20))
        stripe_points = stripe @ affine[k, :, :2].T + affine[k, :, 2]
        pen.polygon([tuple(p) for p in stripe_points], fill=STRIPE)
        images[k] = _finished(picture, k / max(frames - 1, 1), occluder, noise, rng)
    return Cartoon(frames=images, contours=contours, keys=circle[None], affine=affine,
                   weights=np.ones((frames, 1)), fps=fps)


BODY, EYE, PUPIL, INK = (90, 170, 100), (250, 250, 250), (30, 30, 30), (30, 40, 30)
PAPER, BAR = (250, 246, 236), (60, 60, 160)


def character_keys(points: int = 96, size: float = 40.0) -> NDArray[np.float64]:
    """Three key-shapes of a bean-shaped character with one arm, points in correspondence about
    its centre: standing with the arm down, stretched tall with the arm up, squashed wide with
    the arm out. ``size`` is the body's half-height standing.

    Examples
    --------
    >>> character_keys(points=60).shape
    (3, 60, 2)
    """
    if not (isinstance(points, int) and 24 <= points <= 10_000):
        raise SettingsError(f"a character's outline has 24 to 10,000 points, not {points!r}")
    arm_points = points // 3
    poses = [  # body half-width and half-height (x size), arm angle (degrees, 0 right, 90 up), arm length
        (0.62, 1.0, -35.0, 0.9),
        (0.5, 1.25, 55.0, 1.0),
        (0.85, 0.72, 5.0, 0.85),
    ]
    keys = []
    for wide, tall, angle, reach in poses:
        a, b = wide * size, tall * size
        shoulder, half = np.radians(-12.0), np.radians(8.0)  # on the right, a little up (y down)
        theta = np.linspace(shoulder + half, shoulder - half + 2 * np.pi, points - arm_points)
        body = np.column_stack([a * np.cos(theta), b * np.sin(theta)])
        upper, lower = body[-1], body[0]  # the arm leaves the body between these
        base = (upper + lower) / 2
        width = 0.5 * float(np.hypot(*(upper - lower)))
        d = np.array([np.cos(np.radians(angle)), -np.sin(np.radians(angle))])
        n = np.array([-d[1], d[0]])
        if (upper - base) @ n < 0:
            n = -n
        tip = base + reach * size * d
        phi = np.linspace(0, np.pi, 17)
        around = tip + width * (np.cos(phi)[:, None] * n + np.sin(phi)[:, None] * d)
        path = np.vstack([upper, around, lower])
        keys.append(np.vstack([body, _along(path, arm_points)]))
    return np.stack(keys)


def _along(path: NDArray[np.float64], count: int) -> NDArray[np.float64]:
    """``count`` points evenly spaced along ``path``, its two ends left out."""
    run = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    where = np.linspace(0, run[-1], count + 2)[1:-1]
    return np.column_stack([np.interp(where, run, path[:, 0]), np.interp(where, run, path[:, 1])])


def morphing_character(*, frames: int = 24, size: tuple[int, int] = (240, 200), points: int = 96,
                       noise: float = 0.0, occluder: bool = False, seed: int = 0, fps: float = 24.0,
                       hold: int = 2) -> Cartoon:
    """A flat-coloured character (:func:`character_keys`, with an eye) morphing from key to key
    — standing, stretched with the arm up, squashed with the arm out, and back — by
    as-rigid-as-possible in-betweens, while it hops across the frame, turning a little and
    breathing in size. Drawn like cel animation: each drawing held ``hold`` frames (on twos: 12
    drawings a second at 24 fps). Each key is drawn as it is at ``key_frames``.

    Examples
    --------
    >>> hero = morphing_character(frames=12)
    >>> hero.frames.shape, hero.key_frames
    ((12, 200, 240, 3), (0, 4, 8))
    >>> bool((hero.contours[0] == hero.contours[1]).all())  # on twos
    True
    """
    from toonmotion.keyshape.arap import ArapPair  # keyshape imports nothing from here

    if not (isinstance(frames, int) and 6 <= frames <= 10_000):
        raise SettingsError(f"a generated cartoon has 6 to 10,000 frames, not {frames!r}")
    if not (isinstance(hold, int) and 1 <= hold <= 4):
        raise SettingsError(f"each drawing is held 1 to 4 frames, not {hold!r}")
    width, height = size
    body = 0.2 * height
    keys = character_keys(points, size=body)
    pairs = [ArapPair(keys[k], keys[(k + 1) % 3], closed=True) for k in range(3)]
    drawings = -(-frames // hold)
    at_key = [round(k * drawings / 3) for k in range(3)]
    phase = np.interp(np.arange(drawings), [*at_key, drawings], [0, 1, 2, 3])  # key 0 -> 1 -> 2 -> 0
    shapes, affines, weights = [], [], []
    for d, s in enumerate(phase):
        k, t = min(int(s), 2), s - min(int(s), 2)
        shapes.append(pairs[k].at(t) if t > 0 else keys[k].copy())
        w = np.zeros(3)
        w[k], w[(k + 1) % 3] = 1 - t, w[(k + 1) % 3] + t
        weights.append(w)
        u = d / max(drawings - 1, 1)
        turn, grow = np.radians(10 * np.sin(2 * np.pi * u)), 1 + 0.1 * np.sin(4 * np.pi * u)
        x = 0.22 * width + 0.4 * width * u
        y = 0.55 * height - 0.15 * height * abs(np.sin(2 * np.pi * u))
        c, sn = np.cos(turn) * grow, np.sin(turn) * grow
        affines.append(np.array([[c, sn, x], [-sn, c, y]]))
    index = np.arange(frames) // hold
    affine = np.stack(affines)[index]
    contours = np.stack([_apply(A, shape) for A, shape in zip(affines, shapes, strict=True)])[index]
    eye_index = int(np.argmin(np.abs(np.arctan2(keys[0][:, 1], keys[0][:, 0]) + np.radians(115))))
    rng = np.random.default_rng(seed)
    images = np.empty((frames, height, width, 3), dtype=np.uint8)
    for f in range(frames):
        picture = Image.new("RGB", (width, height), PAPER)
        pen = ImageDraw.Draw(picture)
        outline = contours[f]
        pen.polygon([tuple(p) for p in outline], fill=BODY, outline=INK)
        eye = 0.5 * outline[: len(outline) - len(outline) // 3].mean(axis=0) + 0.5 * outline[eye_index]
        r = 0.16 * body * np.sqrt(abs(np.linalg.det(affine[f][:, :2])))
        pen.ellipse([eye[0] - r, eye[1] - r, eye[0] + r, eye[1] + r], fill=EYE, outline=INK)
        pen.ellipse([eye[0] - r / 2, eye[1] - r / 2, eye[0] + r / 2, eye[1] + r / 2], fill=PUPIL)
        images[f] = _finished(picture, f / max(frames - 1, 1), occluder, noise, rng)
    return Cartoon(frames=images, contours=contours, keys=keys, affine=affine,
                   weights=np.stack(weights)[index], fps=fps, key_frames=tuple(k * hold for k in at_key))


def _finished(picture: Image.Image, u: float, occluder: bool, noise: float, rng: np.random.Generator
              ) -> NDArray[np.uint8]:
    """The frame at ``u`` (0 first, 1 last) with the occluding bar crossing in front, right to
    left, and pixel noise of ``noise`` grey levels."""
    if occluder:
        width, height = picture.size
        left = width * (1 - u) - 20
        ImageDraw.Draw(picture).rectangle([left, 0, left + 14, height], fill=BAR)
    array = np.asarray(picture, dtype=float)
    if noise > 0:
        array = array + rng.normal(0, noise, array.shape)
    return np.clip(np.rint(array), 0, 255).astype(np.uint8)


def _apply(A: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.asarray(points @ A[:, :2].T + A[:, 2], dtype=float)
