"""Image sequences with known joint positions: a limb figure, textured over a textured background
or flat-coloured and outlined over a plain one (a cel cartoon).

Motion capture is measured on these (``benchmarks/track.py`` and the tests): real motion-capture
clips, projected to 2D, drive a figure whose every bone is a textured band and every joint a
textured disc, drawn far to near so limbs cross and hide each other. The true 2D joint positions
are the input, so a tracker's error can be measured exactly. Textures are seeded noise, turned
with their bone, so a joint's patch rotates as a drawn limb's would. The noise is smooth, with
features a few pixels across like crayon or cloth: pixel-sized noise would decorrelate under
any sub-pixel resampling, which no drawing or footage does (a tracker lost the turning hand of
a test arm on its first frame with it, and kept it to 0.1 px without).

The *flat* style is the footage the thesis was written for (4.6): every bone a rounded band of
one flat colour with a dark outline, over a plain paper-coloured background, drawn far to near
so a nearer limb's outline crosses a farther one. Colours come from a small cartoon palette and
repeat (a left and a right arm alike, as in most cartoons), so a joint's rectangle holds one or
two flat colours and the outlines' shapes: nothing tells one place along a straight limb from
another, and a look-alike of every joint is never far away.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import TrackingError
from toonmotion.rig.kinematics import rotation

STYLES = ("textured", "flat")

# The flat style's background, outline and fill colours (RGB): a few cartoon colours, so that
# parts repeat them.
_PAPER = (246, 240, 226)
_INK = (30, 24, 28)
_PALETTE = ((238, 196, 160), (200, 60, 50), (60, 90, 170), (250, 200, 60), (90, 150, 80))
_SHIFT = 4


def limb_figure_frames(
    points: ArrayLike,
    parents: ArrayLike,
    *,
    depth: ArrayLike | None = None,
    size: tuple[int, int] = (640, 480),
    width: float | None = None,
    seed: int = 0,
    style: str = "textured",
) -> tuple[NDArray[np.uint8], float]:
    """Render a limb figure at ``points`` for every frame.

    Parameters
    ----------
    points : (T, J, 2) float
        Joint positions, pixels, y down.
    parents : (J,) int
        Parent of each joint, -1 for a root; a bone joins each joint to its parent.
    depth : (T, J) float, optional
        Distance of each joint from the viewer (larger is farther); bones and discs are drawn
        far to near. Default: all at one depth, in joint order.
    size : (width, height)
    width : float, optional
        Limb width in pixels; default 6% of the figure's height in frame 0, at least 6.
    seed : int
    style : {"textured", "flat"}
        Textured bands and joint discs over a textured background, or flat-coloured outlined
        bands with round ends over a plain background (module docstring).

    Returns
    -------
    frames : (T, h, w, 3) uint8
    radius : float
        Radius of the joint discs (a tracker's rectangle of side ``2 * radius`` covers one); in
        the flat style, where no disc is drawn, the same size: 0.75 of the limb width.
    """
    if style not in STYLES:
        raise TrackingError(f"the figure's style must be one of {', '.join(STYLES)}, got {style!r}")
    points = np.asarray(points, dtype=float)
    parents = np.asarray(parents)
    if points.ndim != 3 or points.shape[2] != 2 or points.shape[1] != len(parents):
        raise TrackingError(f"points must be (frames, {len(parents)}, 2), got {points.shape}")
    T, J = points.shape[:2]
    depth = np.zeros((T, J)) if depth is None else np.asarray(depth, dtype=float)
    if width is None:
        width = max(6.0, 0.06 * float(np.ptp(points[0, :, 1])))
    radius = 0.75 * width
    rng = np.random.default_rng(seed)
    w, h = size
    if style == "flat":
        return _flat_frames(points, parents, depth, (w, h), width, rng), radius
    background = _noise((h, w), rng, grain=0.1, blur=15, contrast=25)
    bones = [(int(p), j) for j, p in enumerate(parents) if p >= 0]
    longest = max(1.0, float(np.max([np.hypot(*(points[:, j] - points[:, p]).T).max() for p, j in bones])))
    limb_textures = [_noise((int(np.ceil(width)) + 2, int(np.ceil(longest)) + 2), rng) for _ in bones]
    side = (int(np.ceil(2 * radius)) + 3) | 1  # odd: the centre is a pixel
    disc_textures = [_noise((side, side), rng, grain=0.15, blur=2, contrast=70) for _ in range(J)]
    frames = np.empty((T, h, w, 3), dtype=np.uint8)
    for t in range(T):
        frame = background.copy()
        items = [(0.5 * (depth[t, p] + depth[t, j]), 0, k) for k, (p, j) in enumerate(bones)]
        # A joint's disc lies on its own bones: just nearer than the nearest of them. Only other
        # parts of the figure, nearer the viewer, hide it.
        near = depth[t].copy()
        for d, _, k in items:
            p, j = bones[k]
            near[p], near[j] = min(near[p], d), min(near[j], d)
        items += [(near[j] - 1e-6, 1, j) for j in range(J)]
        for _, kind, k in sorted(items, key=lambda item: -item[0]):
            if kind == 0:
                p, j = bones[k]
                _paste_limb(frame, limb_textures[k], points[t, p], points[t, j], width)
            else:
                _paste_disc(frame, disc_textures[k], points[t, k], _disc_angle(points[t], parents, k), radius)
        frames[t] = frame
    return frames, radius


def _flat_frames(points, parents, depth, size, width, rng):
    """The flat style: each bone a round-ended band of a palette colour with a dark outline."""
    T, J = points.shape[:2]
    w, h = size
    bones = [(int(p), j) for j, p in enumerate(parents) if p >= 0]
    colours = [_PALETTE[i] for i in rng.integers(0, len(_PALETTE), len(bones))]
    outline = max(1.5, 0.12 * width)
    # cv2 draws with fixed-point coordinates: SHIFT fractional bits keep sub-pixel positions.
    scale = 1 << _SHIFT
    frames = np.empty((T, h, w, 3), dtype=np.uint8)
    for t in range(T):
        frame = np.empty((h, w, 3), dtype=np.uint8)
        frame[:] = _PAPER
        order = sorted(range(len(bones)), key=lambda k: -(depth[t, bones[k][0]] + depth[t, bones[k][1]]))
        for k in order:
            p, j = bones[k]
            a = tuple(int(v) for v in np.rint(points[t, p] * scale))
            b = tuple(int(v) for v in np.rint(points[t, j] * scale))
            cv2.line(frame, a, b, _INK, int(round(width + 2 * outline)), cv2.LINE_AA, _SHIFT)
            cv2.line(frame, a, b, colours[k], int(round(width)), cv2.LINE_AA, _SHIFT)
        frames[t] = frame
    return frames


def _noise(shape, rng, *, grain=0.25, blur=3, contrast=50):
    """A smooth noise texture round a random colour, with some fine grain, ``shape + (3,)`` uint8."""
    base = rng.uniform(0, 255, size=(*shape, 3)).astype(np.float32)
    k = 2 * blur + 1
    smooth = cv2.GaussianBlur(base, (k, k), blur) if blur else base
    smooth = (smooth - smooth.mean()) / max(float(smooth.std()), 1e-6) * contrast + rng.uniform(60, 195, 3)
    out = (1 - grain) * smooth + grain * (smooth + (base - 127.5) * contrast / 75)
    return np.clip(out, 0, 255).astype(np.uint8)


def _disc_angle(frame_points, parents, j):
    p = parents[j]
    if p < 0:
        return 0.0
    d = frame_points[j] - frame_points[p]
    return float(np.arctan2(d[1], d[0]))


def _paste(frame, texture, M, mask):
    """Warp ``texture`` by the 2x3 texture-to-image map ``M`` and paste it where ``mask`` covers."""
    h, w = frame.shape[:2]
    th, tw = texture.shape[:2]
    corners = np.array([[0, 0, 1], [tw, 0, 1], [0, th, 1], [tw, th, 1]], dtype=float) @ M.T
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - 1, 0)
    x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + 1, (w, h))
    if x1 <= x0 or y1 <= y0:
        return
    shifted = M - np.array([[0, 0, x0], [0, 0, y0]], dtype=float)
    size = (int(x1 - x0), int(y1 - y0))
    colour = cv2.warpAffine(texture, shifted, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    cover = cv2.warpAffine(mask, shifted, size, flags=cv2.INTER_LINEAR, borderValue=0)[..., None] / 255.0
    region = frame[y0:y1, x0:x1]
    region[:] = np.rint(region * (1 - cover) + colour * cover).astype(np.uint8)


def _paste_limb(frame, texture, a, b, width):
    d = b - a
    length = float(np.hypot(*d))
    if length < 1e-6:
        return
    u = d / length
    n = np.array([-u[1], u[0]])
    th, tw = texture.shape[:2]
    # Texture x runs along the bone from a, texture y across it, centred.
    M = np.column_stack([u, n * width / th, a - n * width / 2])
    mask = np.zeros((th, tw), dtype=np.uint8)
    mask[:, : int(np.ceil(length)) + 1] = 255
    _paste(frame, texture, M, mask)


def _paste_disc(frame, texture, centre, angle, radius):
    side = texture.shape[0]
    R = rotation(angle)
    middle = side // 2
    M = np.column_stack([R, centre - R @ np.array([middle, middle], dtype=float)])
    mask = np.zeros((side, side), dtype=np.uint8)
    cv2.circle(mask, (middle, middle), int(round(radius)), 255, -1, lineType=cv2.LINE_AA)
    _paste(frame, texture, M, mask)
