"""Overlays on a rendered frame: the deformed mesh, the skeleton, a reference skeleton.

Each function takes an RGBA frame rendered with some ``view`` (see
:func:`toonmotion.render.raster.view_transform`), maps drawing points into it the same way,
draws anti-aliased lines and discs on a coverage layer and composites one colour through it
over the frame (``render.composite.over``). Widths and radii are in output pixels. The frame
is not modified; a new one is returned.
"""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import SettingsError
from toonmotion.render.composite import over
from toonmotion.render.raster import check_colour, view_transform
from toonmotion.shape.mesh import unique_edges

# Points are passed to OpenCV in fixed point with this many fractional bits.
_SHIFT = 4
# Points are clamped this far outside the frame (pixels) to keep fixed point within int32.
_FAR = 2.0**20


def draw_mesh(frame: NDArray[np.uint8], U: ArrayLike, F: ArrayLike, *, view: Sequence[float],
              colour: Sequence[int] = (40, 40, 40, 160), width: int = 1) -> NDArray[np.uint8]:
    """Draw the edges of a deformed mesh.

    Parameters
    ----------
    frame : (H, W, 4) uint8
        RGBA frame rendered with ``view``.
    U : (n, 2) float
        Deformed vertices, (x, y) drawing pixels, y down.
    F : (m, 3) int
        Triangles.
    view : (x0, y0, x1, y1) float
        The view ``frame`` was rendered with.
    colour : (r, g, b) or (r, g, b, a) int 0-255
    width : int
        Line width in output pixels.

    Returns
    -------
    (H, W, 4) uint8
        A new frame.
    """
    frame, to_frame = _setup(frame, view)
    P = _points(U, "U")
    T = np.asarray(F)
    if T.size == 0:
        T = T.reshape(0, 3)
    if T.ndim != 2 or T.shape[1] != 3 or not np.issubdtype(T.dtype, np.integer):
        raise SettingsError(f"triangles F must be an (m, 3) integer array, got shape {T.shape}")
    _check_indices(T, len(P), "F")
    segments = to_frame(P)[unique_edges(T)] if len(T) else np.zeros((0, 2, 2))
    return _paint(frame, colour, _check_width(width, "width"), segments)


def draw_skeleton(frame: NDArray[np.uint8], positions: ArrayLike, bones: ArrayLike, *, view: Sequence[float],
                  colour: Sequence[int] = (20, 90, 230, 255), width: int = 3,
                  joint_radius: int = 4) -> NDArray[np.uint8]:
    """Draw a posed skeleton: bones as lines, joints as discs.

    Parameters
    ----------
    frame, view, colour : as for :func:`draw_mesh`
    positions : (k, 2) float
        Joint positions, (x, y) drawing pixels, y down.
    bones : (b, 2) int
        Joint index pairs (parent, child).
    width : int
        Bone line width in output pixels.
    joint_radius : int
        Joint disc radius in output pixels; 0 draws no discs.

    Returns
    -------
    (H, W, 4) uint8
        A new frame.

    Examples
    --------
    >>> frame = np.zeros((20, 20, 4), np.uint8)
    >>> out = draw_skeleton(frame, [[2.0, 10.0], [17.0, 10.0]], [[0, 1]], view=(-0.5, -0.5, 19.5, 19.5))
    >>> out[10, 10].tolist(), frame[10, 10].tolist()
    ([20, 90, 230, 255], [0, 0, 0, 0])
    """
    frame, to_frame = _setup(frame, view)
    P = _points(positions, "positions")
    bones = _bones(bones, len(P))
    if not isinstance(joint_radius, Integral) or isinstance(joint_radius, bool) or joint_radius < 0:
        raise SettingsError(f"joint_radius must be a whole number of pixels >= 0, got {joint_radius!r}")
    Po = to_frame(P)
    discs = Po if joint_radius > 0 else np.zeros((0, 2))
    return _paint(frame, colour, _check_width(width, "width"), Po[bones], discs, int(joint_radius))


def draw_reference(frame: NDArray[np.uint8], positions: ArrayLike, bones: ArrayLike, *, view: Sequence[float],
                   colour: Sequence[int] = (220, 30, 30, 255), width: int = 2) -> NDArray[np.uint8]:
    """Draw a reference skeleton's bones as thin lines (red by default, thesis fig. 6.2a).

    Typically the rest skeleton, showing each bone's original direction and length next to
    the posed one.

    Parameters
    ----------
    frame, positions, bones, view, colour, width : as for :func:`draw_skeleton`, which this
        is without the joints' discs, and thinner and red by default.

    Returns
    -------
    (H, W, 4) uint8
        A new frame.
    """
    return draw_skeleton(frame, positions, bones, view=view, colour=colour, width=width, joint_radius=0)


def _paint(frame, colour, width, segments, discs=None, radius=0):
    """Composite ``colour`` through anti-aliased ``segments`` (s, 2, 2) and ``discs`` (k, 2)."""
    colour = check_colour(colour, "colour")
    H, W = frame.shape[:2]
    cover = np.zeros((H, W), np.uint8)
    fixed = np.rint(np.clip(segments, -_FAR, _FAR) * (1 << _SHIFT)).astype(np.int32)
    if len(fixed):
        cv2.polylines(cover, list(fixed), False, 255, width, cv2.LINE_AA, _SHIFT)
    if discs is not None:
        for x, y in np.rint(np.clip(discs, -_FAR, _FAR) * (1 << _SHIFT)).astype(np.int64):
            cv2.circle(cover, (int(x), int(y)), radius << _SHIFT, 255, -1, cv2.LINE_AA, _SHIFT)
    out = frame.copy()
    x, y, w, h = cv2.boundingRect(cover)
    if w == 0 or h == 0:
        return out
    region = out[y:y + h, x:x + w]
    hit = cover[y:y + h, x:x + w] > 0
    # The colour at alpha colour[3] * coverage, premultiplied in composite's units, over the frame.
    alpha = cover[y:y + h, x:x + w][hit].astype(np.float32) * np.float32(colour[3] / 255)
    src = np.empty((len(alpha), 4), np.float32)
    src[:, :3] = alpha[:, None] * np.float32(colour[:3])
    src[:, 3] = alpha * 255
    region[hit] = over(src, region[hit])
    return out


def _setup(frame, view):
    frame = np.asarray(frame)
    if frame.ndim != 3 or frame.shape[2] != 4 or frame.dtype != np.uint8:
        raise SettingsError(
            f"frame must be an (H, W, 4) uint8 RGBA array, got shape {frame.shape} dtype {frame.dtype}"
        )
    scale, offset = view_transform(view, (frame.shape[1], frame.shape[0]))
    return frame, lambda P: P * scale + offset


def _points(P, name):
    P = np.asarray(P, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 2:
        raise SettingsError(f"{name} must have shape (k, 2), got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise SettingsError(f"{name} contain NaN or infinity; check the pose or deformation that made them")
    return P


def _bones(bones, k):
    bones = np.asarray(bones)
    if bones.size == 0:
        return np.zeros((0, 2), np.int64)
    if bones.ndim != 2 or bones.shape[1] != 2 or not np.issubdtype(bones.dtype, np.integer):
        raise SettingsError(
            f"bones must be a (b, 2) integer array of (parent, child) pairs, got shape {bones.shape}"
        )
    _check_indices(bones, k, "bones")
    return bones


def _check_indices(index, k, name):
    if index.size and (index.min() < 0 or index.max() >= k):
        raise SettingsError(f"{name} index points {index.min()}..{index.max()} but there are {k}")


def _check_width(width, name):
    if not isinstance(width, Integral) or isinstance(width, bool) or not 1 <= width <= 255:
        raise SettingsError(f"{name} must be a whole number of pixels from 1 to 255, got {width!r}")
    return int(width)
