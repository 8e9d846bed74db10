"""Collision volumes (section 3.4.2, eq. 7-10): a tapered cylinder per limb, a sphere per joint.

A limb's cylinder runs between its two markers' 3D points (:mod:`~toonmotion.proxy3d.points`);
its radius at each end comes from how wide the artist drew the limb there.

**Width in the drawing.** The paper approximates the drawn limb by a box ``p1 p2 p3 p4`` found by
"locating the first black pixel in the direction perpendicular to the line joining the virtual
markers". We walk perpendicular to the limb, both ways, from two points on it and stop at the
first *boundary* pixel, which is

- a pixel of ink (grey value at most ``ink``, as a fraction of white), when the walk starts on
  paint or paper -- the outline of a filled or line-art limb;
- the first pixel off the ink, when the walk starts on ink -- a limb drawn as a stroke (a stick
  figure) is as wide as its stroke;
- also the first background pixel (the colour of the frame's border, within ``tolerance``),
  when the walk starts off the background -- a flat-coloured limb without an outline.

Departure: the paper measures at the markers themselves; there the perpendicular often runs
into the neighbouring part (across the torso at a shoulder, along the other leg at the hips), so
we measure at fractions ``AT = (0.25, 0.75)`` of the way along the limb and give each end the
width measured nearer to it. A walk that finds no boundary within the limb's length (an arm
across the torso, the paper's overlap case) is capped at the limb's length and reported; such
frames take per-frame overrides (``widths``), as the paper's annotation interface gives.

**Radius.** The box's corners are back-projected to the depth of the marker at their end (eq.
7-9, solved exactly on the corners' rays, as the points are) and the radius is half the distance
between the two corners at an end. Eq. 10 prints ``r1 = sqrt(|P1 - P4|) / 2``; a square root of
a length is not a length (it would make a 10 cm arm 16 cm thick at 1 m and 5 cm at 1 cm), and
``|P1 - P4|`` is the limb's width, so we take ``r1 = |P1 - P4| / 2``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.markers import Markers

# Where along a limb (fractions from its parent marker) its widths are measured.
AT = (0.25, 0.75)
# Grey values at most this fraction of white are ink.
INK = 0.4
# Colours within this distance (0-255 per channel, Euclidean) of the border's are background.
TOLERANCE = 40.0


def drawn_widths(
    frames: ArrayLike,
    markers: Markers,
    limbs: ArrayLike,
    *,
    widths: Mapping[tuple[int, int], tuple[float, float]] | None = None,
    ink: float = INK,
    tolerance: float = TOLERANCE,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Each limb's drawn width (pixels) near its parent end and its child end, per frame.

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
        The drawn frames, RGB, one per marker frame.
    markers : Markers
        The drawn markers on them.
    limbs : (K, 2) int
        ``(parent, child)`` marker indices.
    widths : dict, optional
        Overrides: ``(frame, limb) -> (width at parent end, width at child end)`` in pixels, for
        frames where limbs overlap.
    ink, tolerance : float
        What counts as ink and as background (module docstring).

    Returns
    -------
    widths : (T, K, 2) float
        Full widths in pixels (both sides of the limb's line together).
    capped : (T, K) bool
        Where a walk found no boundary within the limb's length (and no override was given).

    Examples
    --------
    A grey bar 10 px thick with a black outline, on white:

    >>> frame = np.full((40, 60, 3), 255, np.uint8)
    >>> frame[14:27, 5:55] = 0
    >>> frame[15:26, 6:54] = 128
    >>> m = Markers(("a", "b"), [[[10.0, 20], [50, 20]]], fps=12)
    >>> w, capped = drawn_widths(frame[None], m, [[0, 1]])
    >>> w.tolist(), capped.tolist()
    ([[[11.0, 11.0]]], [[False]])
    """
    F = np.asarray(frames)
    T = markers.frame_count
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    if F.ndim != 4 or F.shape[-1] != 3 or len(F) != T:
        raise ProxyError(f"the drawn frames must be {T} RGB images (one per marker frame), got shape "
                         f"{F.shape}")
    if not (0 < ink < 1) or not (tolerance >= 0):
        raise ProxyError("ink must be a fraction of white in (0, 1) and tolerance a distance >= 0")
    overrides = dict(widths or {})
    for (t, k), pair in overrides.items():
        if not (0 <= t < T and 0 <= k < len(L)):
            raise ProxyError(f"a width override names frame {t}, limb {k}; there are {T} frames and {len(L)} "
                             "limbs")
        if len(pair) != 2 or not all(np.isfinite(v) and v >= 0 for v in pair):
            raise ProxyError(f"the width override for frame {t}, limb {k} must be two widths >= 0 in pixels")
    out = np.zeros((T, len(L), 2))
    capped = np.zeros((T, len(L)), dtype=bool)
    for t in range(T):
        grey = F[t].astype(float).mean(axis=-1) / 255.0
        border = np.concatenate([F[t, 0], F[t, -1], F[t, :, 0], F[t, :, -1]]).astype(float)
        background = np.linalg.norm(F[t].astype(float) - np.median(border, axis=0), axis=-1) <= tolerance
        is_ink = grey <= ink
        for k, (p, c) in enumerate(L):
            if (t, k) in overrides:
                out[t, k] = overrides[t, k]
                continue
            a, b = markers.positions[t, p], markers.positions[t, c]
            for end, f in enumerate(AT):
                width, hit = _width_at(is_ink, background, a + f * (b - a), b - a)
                out[t, k, end] = width
                capped[t, k] |= not hit
    return out, capped


def collision_radii(
    camera: PerspectiveCamera, markers: Markers, points: ArrayLike, limbs: ArrayLike, widths: ArrayLike
) -> NDArray[np.float64]:
    """Each limb's cylinder radius at its two ends, ``(T, K, 2)`` metres (eq. 7-10).

    The drawn box's corners at an end (the marker's pixel plus and minus half the width across
    the limb) are back-projected to that marker's depth; the radius is half their distance.

    Parameters
    ----------
    camera : PerspectiveCamera
    markers : Markers
    points : (T, N, 3) float
        The single-point proxies (their depths are used).
    limbs : (K, 2) int
    widths : (T, K, 2) float
        Drawn widths in pixels (:func:`drawn_widths`).

    Examples
    --------
    Seen head-on from 5 m with a 500 px focal length, 10 px is 10 cm across, a 5 cm radius:

    >>> cam = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5]])
    >>> pts = np.array([[[0.0, 1, 0], [0.5, 1, 0]]])
    >>> m = Markers(("a", "b"), cam.project(pts), fps=12)
    >>> collision_radii(cam, m, pts, [[0, 1]], [[[10.0, 20.0]]]).round(9).tolist()
    [[[0.05, 0.1]]]
    """
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    W = np.asarray(widths, dtype=float)
    X = np.asarray(points, dtype=float)
    x = markers.positions
    along = x[:, L[:, 1]] - x[:, L[:, 0]]
    length = np.linalg.norm(along, axis=-1, keepdims=True)
    normal = np.stack([-along[..., 1], along[..., 0]], axis=-1) / np.where(length > 0, length, 1.0)
    depth = camera.depth(X)
    radii = np.empty(W.shape)
    for end in (0, 1):
        marker = L[:, end]
        half = 0.5 * W[..., end, None] * normal
        corners = [camera.at(x[:, marker] + s * half, depth[:, marker]) for s in (1.0, -1.0)]
        radii[..., end] = 0.5 * np.linalg.norm(corners[0] - corners[1], axis=-1)
    return radii


def _width_at(is_ink, background, point, along):
    """Full width across the limb through ``point`` and whether both walks found a boundary."""
    length = float(np.hypot(*along))
    if length == 0:
        return 0.0, True
    normal = np.array([-along[1], along[0]]) / length
    steps = np.arange(1, int(np.ceil(length)) + 1, dtype=float)
    start, start_background = _pixels(is_ink, point[None], False)[0], _pixels(background, point[None],
                                                                              True)[0]
    total, found = 0.0, True
    for sign in (1.0, -1.0):
        samples = point + sign * steps[:, None] * normal
        ink = _pixels(is_ink, samples, False)
        stop = ~ink if start else ink | (_pixels(background, samples, True) & (not start_background))
        hits = np.flatnonzero(stop)
        if len(hits):
            total += steps[hits[0]] - 0.5  # the boundary lies between the last pixel in and the first out
        else:
            total += length
            found = False
    return total, found


def _pixels(image, xy, outside):
    """``image`` at the pixels nearest ``xy`` ``(n, 2)``; ``outside`` beyond its edges."""
    col, row = np.rint(xy[:, 0]).astype(np.int64), np.rint(xy[:, 1]).astype(np.int64)
    ok = (row >= 0) & (row < image.shape[0]) & (col >= 0) & (col < image.shape[1])
    out = np.full(len(xy), outside)
    out[ok] = image[row[ok], col[ok]]
    return out
