"""Rasterising a drawing through a deformed triangle mesh.

Every output pixel whose centre lies in a deformed triangle takes the drawing sampled
(bilinearly) at the matching rest position, found with the inverse of that triangle's affine
map. Overlapping triangles are resolved by draw order, so depth layers are respected.

Coordinates: drawing and output points are (x, y) pixels, x right, y down, and integer
coordinates are pixel centres. A ``view`` rectangle ``(x0, y0, x1, y1)`` in drawing pixels is
fitted into the output (uniform scale, centred, letterboxed); its edges are pixel edges, so the
default view of a ``w`` x ``h`` drawing is ``(-0.5, -0.5, w - 0.5, h - 0.5)``.

Coverage follows a top-left rule: a pixel centre counts as inside a triangle when it lies in
the closed-open span ``[left, right)`` of its row, and rows are taken closed-open in y as well.
Shared edges are evaluated with the same arithmetic from both sides, so every pixel centre in
the mesh is covered exactly once: no cracks, no double coverage.

Sampling uses premultiplied alpha, so colours of transparent texels never bleed into the
figure's edge. Fully transparent texels come out as (0, 0, 0, 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from numbers import Integral, Real
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from toonmotion import limits
from toonmotion.errors import SettingsError
from toonmotion.render.composite import over

# A deformed triangle whose doubled area is below this fraction of its longest edge squared
# is degenerate (zero area up to rounding) and is skipped.
_DEGENERATE = 1e-12
# Deformed triangles with a vertex this far outside the output (pixels) are skipped, which keeps
# the integer arithmetic of the spans from overflowing.
_FAR = 2.0**24
# Map value for uncovered pixels: far enough outside any texture to sample only the border.
_OUTSIDE = -16.0


def view_transform(view: Sequence[float], size: Sequence[int]) -> tuple[float, NDArray[np.float64]]:
    """Scale and offset mapping drawing points to output pixels.

    The view rectangle is fitted inside the output with a uniform scale, centred, and the
    spare rows or columns are left empty (letterboxing).

    Parameters
    ----------
    view : (x0, y0, x1, y1) float
        Rectangle in drawing pixels to show; its edges are pixel edges.
    size : (W, H) int
        Output size in pixels.

    Returns
    -------
    scale : float
    offset : (2,) float
        Output point ``o = p * scale + offset`` for a drawing point ``p``.

    Examples
    --------
    >>> view_transform((-0.5, -0.5, 9.5, 19.5), (10, 20))
    (1.0, array([0., 0.]))
    >>> view_transform((-0.5, -0.5, 9.5, 9.5), (40, 20))
    (2.0, array([10.5,  0.5]))
    """
    x0, y0, x1, y1 = _check_view(view)
    W, H = check_size(size)
    scale = min(W / (x1 - x0), H / (y1 - y0))
    offset = np.array([(W - 1) / 2 - (x0 + x1) / 2 * scale, (H - 1) / 2 - (y0 + y1) / 2 * scale])
    return float(scale), offset


def render_mesh(texture: NDArray[np.uint8], V: NDArray[np.float64], U: NDArray[np.float64],
                F: NDArray[np.int_], *, size: Sequence[int], view: Sequence[float] | None = None,
                order: NDArray[np.int_] | None = None, background: Sequence[int] | None = None,
                mask: np.ndarray | None = None) -> NDArray[np.uint8]:
    """Render a drawing mapped through a deformed triangle mesh.

    Parameters
    ----------
    texture : (h, w, 4) uint8
        The drawing, RGBA with straight alpha.
    V : (n, 2) float
        Rest vertex positions, (x, y) texture pixels, y down.
    U : (n, 2) float
        Deformed vertex positions, (x, y) drawing pixels, y down.
    F : (m, 3) int
        Triangles, either winding. Inverted deformed triangles are drawn too; degenerate
        (zero-area) ones, and any with a vertex over 2**24 output pixels away, are skipped.
    size : (W, H) int
        Output size in pixels.
    view : (x0, y0, x1, y1) float, optional
        Rectangle in drawing pixels shown in the output (see :func:`view_transform`).
        Default: the texture's canvas, ``(-0.5, -0.5, w - 0.5, h - 0.5)``.
    order : (m,) int, optional
        Permutation of triangle indices giving the draw order; later triangles are drawn on
        top. Default: ``0, 1, ..., m - 1``.
    background : (r, g, b) or (r, g, b, a) int 0-255, optional
        Colour composited under the figure. Default: transparent.
    mask : (h, w) bool or float in [0, 1], optional
        Multiplied into the texture's alpha before sampling, so the figure's edges come out
        soft.

    Returns
    -------
    (H, W, 4) uint8
        RGBA, straight alpha. With ``U == V``, the default view and ``size == (w, h)`` every
        pixel whose centre is in the mesh equals the texture exactly.

    Examples
    --------
    >>> texture = np.zeros((4, 4, 4), np.uint8); texture[..., 0] = 200; texture[..., 3] = 255
    >>> V = np.array([[-0.5, -0.5], [3.5, -0.5], [3.5, 3.5], [-0.5, 3.5]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> out = render_mesh(texture, V, V + [1.0, 0.0], F, size=(4, 4))
    >>> out[0, :, 0].tolist(), out[0, :, 3].tolist()
    ([0, 200, 200, 200], [0, 255, 255, 255])
    """
    texture, V, U, F = _check_mesh(texture, V, U, F)
    W, H = check_size(size)
    h, w = texture.shape[:2]
    if view is None:
        view = (-0.5, -0.5, w - 0.5, h - 0.5)
    scale, offset = view_transform(view, (W, H))
    order = _check_order(order, len(F))
    if mask is not None:
        mask = _check_mask_shape(mask, (h, w))
    out = np.zeros((H, W, 4), np.uint8)
    bg = None if background is None else check_colour(background, "background")
    if bg is not None:
        out.view(np.uint32).fill(np.array(bg, np.uint8).view(np.uint32)[0])
    if len(F) == 0:
        return out
    Uo = U * scale + offset
    lin, map_x, map_y = _rasterise(Uo, V, F, order, W, H)
    n = len(lin)
    if n == 0:
        return out
    sampled = cv2.remap(
        _premultiplied(texture, mask), map_x, map_y, interpolation=cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0, 0),
    ).reshape(-1, 4)[:n]
    pixels = over(sampled, bg)
    # One uint32 per RGBA pixel: scattering words is much faster than scattering rows.
    out.view(np.uint32).reshape(-1)[lin] = pixels.view(np.uint32).reshape(-1)
    return out


def render_labels(labels: NDArray[np.integer], V: NDArray[np.float64], U: NDArray[np.float64],
                  F: NDArray[np.int_], *, size: Sequence[int], view: Sequence[float] | None = None,
                  order: NDArray[np.int_] | None = None) -> NDArray[np.int32]:
    """Carry a label image through a deformed mesh as :func:`render_mesh` carries the drawing.

    Each covered output pixel takes the label of the rest pixel it comes from (nearest, never
    blended, so labels stay whole); uncovered pixels are -1.

    Parameters
    ----------
    labels : (h, w) int
        A label per rest (texture) pixel, -1 for none.
    V, U, F, size, view, order
        As :func:`render_mesh`.

    Returns
    -------
    (H, W) int32

    Examples
    --------
    >>> labels = np.array([[0, 0, 1, 1]] * 4)
    >>> V = np.array([[-0.5, -0.5], [3.5, -0.5], [3.5, 3.5], [-0.5, 3.5]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> render_labels(labels, V, V + [1.0, 0.0], F, size=(4, 4))[0].tolist()
    [-1, 0, 0, 1]
    """
    L = np.asarray(labels)
    h, w = L.shape
    texture = np.zeros((h, w, 4), np.uint8)
    _, V, U, F = _check_mesh(texture, V, U, F)
    W, H = check_size(size)
    if view is None:
        view = (-0.5, -0.5, w - 0.5, h - 0.5)
    scale, offset = view_transform(view, (W, H))
    out = np.full(H * W, -1, np.int32)
    if len(F) == 0:
        return out.reshape(H, W)
    lin, map_x, map_y = _rasterise(U * scale + offset, V, F, _check_order(order, len(F)), W, H)
    n = len(lin)
    if n:
        col = np.clip(np.rint(map_x.reshape(-1)[:n]), 0, w - 1).astype(np.intp)
        row = np.clip(np.rint(map_y.reshape(-1)[:n]), 0, h - 1).astype(np.intp)
        out[lin] = L[row, col]
    return out.reshape(H, W)


def _rasterise(Uo, V, F, order, W, H):
    """Cover output pixel centres with deformed triangles, later ones in ``order`` winning.

    Parameters
    ----------
    Uo : (n, 2) float
        Deformed vertices in output pixels.
    V : (n, 2) float
        Rest vertices in texture pixels.

    Returns
    -------
    lin : (k,) int
        Covered pixels, as linear indices ``row * W + column`` into the output.
    map_x, map_y : (rows, cols) float32
        Rest position (texture pixels) of each covered pixel's centre, in the order of ``lin``,
        as one compact image for :func:`cv2.remap` (whose sides must stay below 32767),
        padded with far-outside positions.
    """
    empty = np.zeros(0, np.int64), None, None
    # Only the bounding box of the deformed mesh within the output is touched.
    lo = np.maximum(np.ceil(Uo.min(axis=0)), 0)
    hi = np.minimum(np.floor(Uo.max(axis=0)), [W - 1, H - 1])
    if np.any(hi < lo):
        return empty
    x0, y0 = int(lo[0]), int(lo[1])
    x1, y1 = int(hi[0]), int(hi[1])

    P = Uo[F[order]]  # (m, 3, 2), in draw order
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    area2 = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    longest = np.max(np.sum((P - P[:, [1, 2, 0]]) ** 2, axis=2), axis=1)
    keep = (np.abs(area2) > _DEGENERATE * longest) & np.all(np.abs(P) < _FAR, axis=(1, 2))
    tri, P, e1, e2, area2 = order[keep], P[keep], e1[keep], e2[keep], area2[keep]
    if len(tri) == 0:
        return empty

    # Inverse affine maps, output -> rest: rest = R0 + [R1-R0, R2-R0] @ inv([e1, e2]) @ (o - O0),
    # written as rest_x = a ox + b oy + e and rest_y = c ox + d oy + f.
    R = V[F[tri]]
    r1, r2 = R[:, 1] - R[:, 0], R[:, 2] - R[:, 0]
    i00, i01, i10, i11 = e2[:, 1] / area2, -e2[:, 0] / area2, -e1[:, 1] / area2, e1[:, 0] / area2
    a = r1[:, 0] * i00 + r2[:, 0] * i10
    b = r1[:, 0] * i01 + r2[:, 0] * i11
    c = r1[:, 1] * i00 + r2[:, 1] * i10
    d = r1[:, 1] * i01 + r2[:, 1] * i11
    e = R[:, 0, 0] - a * P[:, 0, 0] - b * P[:, 0, 1]
    f = R[:, 0, 1] - c * P[:, 0, 0] - d * P[:, 0, 1]

    # Rows: vertices sorted by y (top A, middle B, bottom C); rows y in [yA, yC).
    s = np.argsort(P[:, :, 1], axis=1, kind="stable")
    Q = np.take_along_axis(P, s[:, :, None], axis=1)
    xa, xb, xc = Q[:, 0, 0], Q[:, 1, 0], Q[:, 2, 0]
    ya, yb, yc = Q[:, 0, 1], Q[:, 1, 1], Q[:, 2, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        # A slope is only used on rows strictly inside its edge's y range.
        k_ac = (xc - xa) / (yc - ya)
        k_ab = np.where(yb > ya, (xb - xa) / (yb - ya), 0.0)
        k_bc = np.where(yc > yb, (xc - xb) / (yc - yb), 0.0)
    first_row = np.maximum(np.ceil(ya), y0).astype(np.int64)
    n_rows = np.maximum(np.minimum(np.ceil(yc) - 1, y1).astype(np.int64) - first_row + 1, 0)
    t = np.repeat(np.arange(len(tri)), n_rows)  # triangle of each (triangle, row) span
    y = np.arange(len(t)) - np.repeat(np.cumsum(n_rows) - n_rows - first_row, n_rows)

    # Each edge is evaluated as p.x + (y - p.y) * slope from its upper end p: the same
    # arithmetic in both triangles sharing it, so their spans meet without gap or overlap.
    yf = y.astype(np.float64)
    x_long = xa[t] + (yf - ya[t]) * k_ac[t]
    x_short = np.where(yf < yb[t], xa[t] + (yf - ya[t]) * k_ab[t], xb[t] + (yf - yb[t]) * k_bc[t])
    c0 = np.maximum(np.ceil(np.minimum(x_long, x_short)), x0).astype(np.int64)
    c1 = np.minimum(np.ceil(np.maximum(x_long, x_short)) - 1, x1).astype(np.int64)
    n_pix = c1 - c0 + 1
    full = n_pix > 0
    t, y, yf, c0, n_pix = t[full], y[full], yf[full], c0[full], n_pix[full]
    total = int(n_pix.sum())

    # The pixels of all spans, in draw order, numbered j = 0, 1, ... along each span.
    j = np.arange(total, dtype=np.int32)
    j -= np.repeat((np.cumsum(n_pix) - n_pix).astype(np.int32), n_pix)
    lin = np.repeat(y * W + c0, n_pix)
    lin += j

    # Along a span the rest position is linear in j: start + slope * j. An extra span of
    # far-outside positions pads the maps to a compact rows x cols image for cv2.remap.
    rows, cols = _compact_shape(total)
    lengths = np.append(n_pix, rows * cols - total)
    jf = np.zeros(rows * cols, np.float32)
    jf[:total] = j
    del j
    maps = []
    for slope, coef_y, const in ((a, b, e), (c, d, f)):
        start = (slope[t] * c0 + coef_y[t] * yf + const[t]).astype(np.float32)
        m = np.repeat(np.append(start, np.float32(_OUTSIDE)), lengths)
        step = np.repeat(np.append(slope[t].astype(np.float32), np.float32(0)), lengths)
        step *= jf
        m += step
        maps.append(m)
    del jf, step

    # Overlaps: keep, for each pixel, the entry of the latest triangle (its highest rank).
    key = np.zeros(H * W, np.int16 if len(tri) < 32767 else np.int32)
    rank = np.repeat((t + 1).astype(key.dtype), n_pix)
    np.maximum.at(key, lin, rank)
    if np.count_nonzero(key[y0 * W:(y1 + 1) * W]) < total:
        win = key[lin] == rank
        lin = lin[win]
        rows, cols = _compact_shape(len(lin))
        for i, m in enumerate(maps):
            maps[i] = np.full(rows * cols, _OUTSIDE, np.float32)
            maps[i][:len(lin)] = m[:total][win]
    return lin, maps[0].reshape(rows, cols), maps[1].reshape(rows, cols)


def _compact_shape(n):
    """Rows and columns of an image holding ``n`` pixels, both sides below 32767."""
    cols = max(1024, math.isqrt(n) + 1)
    return max(1, -(-n // cols)), cols


def _premultiplied(texture, mask):
    """The texture times ``mask``, premultiplied: float32 in the units of ``composite.premultiply``."""
    alpha = np.ascontiguousarray(texture[..., 3])
    if mask is None or mask.dtype == bool:
        opaque = np.full_like(alpha, 255)
        if mask is not None:
            opaque[~mask] = 0
            alpha &= opaque
        return cv2.multiply(texture, cv2.merge([alpha, alpha, alpha, opaque]), dtype=cv2.CV_32F)
    alpha = alpha * mask
    scale = cv2.merge([alpha, alpha, alpha, mask * np.float32(255)])
    return cv2.multiply(texture.astype(np.float32), scale)


def _check_mesh(texture, V, U, F):
    texture = np.asarray(texture)
    if texture.ndim != 3 or texture.shape[2] != 4 or texture.dtype != np.uint8:
        raise SettingsError(
            f"texture must be an (h, w, 4) uint8 RGBA array, got shape {texture.shape} "
            f"dtype {texture.dtype}; convert it with load_image"
        )
    if max(texture.shape[:2]) >= 32767:
        raise SettingsError(
            f"texture is {texture.shape[1]}x{texture.shape[0]} pixels; sides must be under 32767, "
            "scale it down"
        )
    V = np.asarray(V, dtype=np.float64)
    U = np.asarray(U, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 2:
        raise SettingsError(f"rest vertices V must have shape (n, 2), got {V.shape}")
    if U.shape != V.shape:
        raise SettingsError(
            f"deformed vertices U have shape {U.shape} but V has {V.shape}; give one position per vertex"
        )
    if not (np.all(np.isfinite(U)) and np.all(np.isfinite(V))):
        raise SettingsError("vertex positions contain NaN or infinity; check the deformation that made them")
    if F.size == 0:
        F = F.reshape(0, 3)
    if F.ndim != 2 or F.shape[1] != 3 or not np.issubdtype(F.dtype, np.integer):
        raise SettingsError(
            f"triangles F must be an (m, 3) integer array, got shape {F.shape} dtype {F.dtype}"
        )
    if len(F) and (F.min() < 0 or F.max() >= len(V)):
        raise SettingsError(
            f"triangles F index vertices {F.min()}..{F.max()} but there are {len(V)}; "
            "pass the F that belongs to V"
        )
    return texture, V, U, F.astype(np.int64)


def _check_mask_shape(mask, shape):
    mask = np.asarray(mask)
    if mask.shape != shape:
        raise SettingsError(
            f"mask has shape {mask.shape} but the texture is {shape}; give a mask of the same size"
        )
    if mask.dtype != bool:
        mask = mask.astype(np.float32)
        if not np.all(np.isfinite(mask)) or mask.min() < 0 or mask.max() > 1:
            raise SettingsError("mask values must lie in [0, 1]; scale an 8-bit mask by 1/255")
    return mask


def _check_order(order, m):
    if order is None:
        return np.arange(m)
    order = np.asarray(order)
    if (
        order.shape != (m,)
        or (m and not np.issubdtype(order.dtype, np.integer))
        or not np.array_equal(np.sort(order), np.arange(m))
    ):
        raise SettingsError(f"order must be a permutation of the {m} triangle indices 0..{m - 1}")
    return order.astype(np.int64)


def check_size(size: Any) -> tuple[int, int]:
    """``size`` as ``(width, height)``, two positive ints; SettingsError otherwise."""
    try:
        W, H = size
    except (TypeError, ValueError):
        raise SettingsError(f"size must be (width, height) in pixels, got {size!r}") from None
    if not all(isinstance(v, Integral) and not isinstance(v, bool) and int(v) > 0 for v in (W, H)):
        raise SettingsError(f"size must be two positive integers (width, height), got {size!r}")
    check_canvas(W, H)
    return int(W), int(H)


def check_canvas(width: float, height: float, *, why: str = "") -> None:
    """Refuse a picture over the ``canvas_side`` or ``canvas_pixels`` limit (:class:`LimitError`).

    ``why`` says what made the picture that big, as a hint for staying under the limit.
    """
    what = f"the picture to draw, {width:.0f}x{height:.0f} pixels,"
    limits.check("canvas_side", max(width, height), what + " has a side that", hint=why)
    limits.check("canvas_pixels", width * height, what, hint=why)


def _check_view(view):
    try:
        x0, y0, x1, y1 = (float(v) for v in view)
    except (TypeError, ValueError):
        raise SettingsError(f"view must be (x0, y0, x1, y1) in drawing pixels, got {view!r}") from None
    if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or x1 <= x0 or y1 <= y0:
        raise SettingsError(
            f"view must be a finite rectangle (x0, y0, x1, y1) with x1 > x0 and y1 > y0, got {view!r}"
        )
    return x0, y0, x1, y1


def check_colour(colour: Any, name: str) -> tuple[int, int, int, int]:
    """``colour`` as an RGBA tuple of ints 0-255 (alpha 255 when three are given); SettingsError otherwise."""
    try:
        values = tuple(colour)
    except TypeError:
        values = ()
    if len(values) not in (3, 4) or not all(
        isinstance(v, Real) and not isinstance(v, bool) and float(v).is_integer() and 0 <= float(v) <= 255
        for v in values
    ):
        raise SettingsError(
            f"{name} must be an (r, g, b) or (r, g, b, a) tuple of ints 0-255, got {colour!r}"
        )
    r, g, b, a = [int(v) for v in values] + ([255] if len(values) == 3 else [])
    return r, g, b, a
