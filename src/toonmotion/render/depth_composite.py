"""Depth compositing of a drawing with rendered 3D elements (Jain et al. 2012, eq. 23-26).

Per frame, with the drawing ``Y_h`` (``(H, W, 3)`` bytes) and the elements' render
(:class:`toonmotion.render.zbuffer.Layer`: colour ``Y_r``, depth ``D_r``, coverage ``eta_r``):

- **The drawing's depth** ``D_h`` (eq. 23): every pixel of the figure takes the depth of the
  nearest point on its limb's segment between the two markers' pixels, the markers' depths
  interpolated linearly along it. The limb is the nearest segment in the picture, or the one a
  label map gives (a rigged character knows which bone each pixel follows).
- **Its occlusion map** ``eta_h`` (eq. 24): 1 inside the figure and on its lines. From the
  drawing's alpha when it has one (a mask, a transparent PNG, a toonmotion render), else from its
  ink: the pixels darker than :data:`INK` with the holes they enclose filled.
- **Its alpha** ``alpha``: the drawing's own alpha, or, for line art on white, the inverted grey
  value ``(255 - grey) / 255`` (the paper's).
- **The depth test** (eq. 25) and **the composite** (eq. 26): where an element is seen, the
  result is ``a * Y_h + (1 - a) * Y_r`` with ``a = 0`` on figure pixels the element is in front
  of, and elsewhere on the figure ``a = max(alpha, eta_h)``; off the figure ``a = alpha``. Where no
  element is seen, the drawing is copied as it is. On an element's edge, where it covers a
  fraction ``c < 1`` of the pixel (the layer's ``alpha``), ``1 - a`` is scaled by ``c``.

One departure from the paper, for users: eq. 25 keeps ``alpha`` (the inverted grey) where the
figure is in front, so a figure filled with white would let an element behind it show through
its body; here the figure is opaque where its occlusion map says it is. Everything is in pixels,
x right, y down; depths are metres along the camera's axis (``PerspectiveCamera.depth``).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

from toonmotion.errors import SceneError
from toonmotion.render.zbuffer import Layer

INK = 250  # grey values below this are the artist's lines


def drawing_alpha(frame: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The drawing's alpha ``(H, W)`` in [0, 1] and its occlusion map ``eta_h`` ``(H, W)`` bool.

    ``frame`` is ``(H, W, 3)`` or ``(H, W, 4)`` bytes. An alpha channel that is not opaque
    everywhere gives both (the figure is where alpha > 0); otherwise the drawing is taken as line
    art on white: alpha is the inverted grey, the figure its ink with enclosed holes filled.

    >>> art = np.full((5, 5, 3), 255, np.uint8); art[1:4, 1:4] = 0; art[2, 2] = 255   # a ring
    >>> alpha, figure = drawing_alpha(art)
    >>> alpha[2, 2], bool(figure[2, 2]), bool(figure[0, 0])
    (np.float64(0.0), True, False)
    """
    F = np.asarray(frame)
    if F.ndim != 3 or F.shape[2] not in (3, 4) or F.dtype != np.uint8:
        raise SceneError(f"a drawn frame must be (height, width, 3 or 4) bytes, got {F.shape} {F.dtype}")
    if F.shape[2] == 4 and (F[..., 3] < 255).any():
        alpha = F[..., 3] / 255.0
        return alpha, F[..., 3] > 0
    grey = F[..., :3].astype(np.float64) @ [0.299, 0.587, 0.114]
    alpha = (255.0 - grey) / 255.0
    return np.clip(alpha, 0.0, 1.0), ndimage.binary_fill_holes(grey < INK)


def drawn_depth(figure: ArrayLike, pixels: ArrayLike, depths: ArrayLike, limbs: ArrayLike,
                labels: ArrayLike | None = None) -> NDArray[np.float64]:
    """The drawing's depth map ``D_h`` (eq. 23): ``(H, W)`` metres, ``inf`` off the figure.

    Parameters
    ----------
    figure : (H, W) bool
        The figure's pixels (``eta_h``).
    pixels : (N, 2) float
        The markers in the frame, pixels.
    depths : (N,) float
        Their depths, metres.
    limbs : (K, 2) int
        Marker pairs ``(parent, child)``.
    labels : (H, W) int, optional
        Each pixel's limb (index into ``limbs``), -1 where unknown (then the nearest limb).

    Examples
    --------
    One limb from pixel (0, 0) at 2 m to pixel (4, 0) at 4 m:

    >>> D = drawn_depth(np.ones((1, 5), bool), [[0.0, 0.0], [4.0, 0.0]], [2.0, 4.0], [[0, 1]])
    >>> D.tolist()
    [[2.0, 2.5, 3.0, 3.5, 4.0]]
    """
    mask = np.asarray(figure, dtype=bool)
    x = np.asarray(pixels, dtype=np.float64)
    z = np.asarray(depths, dtype=np.float64)
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    out = np.full(mask.shape, np.inf)
    rows, cols = np.nonzero(mask)
    if len(rows) == 0 or len(L) == 0:
        return out
    given = np.full(len(rows), -1, np.int64)
    if labels is not None:
        given = np.asarray(labels, dtype=np.int64)[rows, cols]
    out[rows, cols] = _along_limbs(rows.astype(np.int64), cols.astype(np.int64), x[L[:, 0]], x[L[:, 1]],
                                   z[L[:, 0]], z[L[:, 1]], given)
    return out


@njit(cache=True)
def _along_limbs(rows, cols, a, b, za, zb, given):  # pragma: no cover - compiled
    """Each pixel's depth on its limb: the given one (``given`` in range) or the nearest segment
    ``a`` to ``b`` (the first of equals), interpolated between the ends' depths ``za``, ``zb``."""
    K = len(a)
    out = np.empty(len(rows))
    s = np.empty(K)
    for n in range(len(rows)):
        px, py = float(cols[n]), float(rows[n])  # pixel centres are whole numbers
        best, k = np.inf, 0
        for m in range(K):
            abx, aby = b[m, 0] - a[m, 0], b[m, 1] - a[m, 1]
            span = max(abx * abx + aby * aby, 1e-300)
            s[m] = min(max(((px - a[m, 0]) * abx + (py - a[m, 1]) * aby) / span, 0.0), 1.0)
            gx, gy = a[m, 0] + s[m] * abx - px, a[m, 1] + s[m] * aby - py
            gap = gx * gx + gy * gy
            if gap < best:
                best, k = gap, m
        if 0 <= given[n] < K:
            k = given[n]
        out[n] = (1 - s[k]) * za[k] + s[k] * zb[k]
    return out


def composite(drawing: ArrayLike, layer: Layer, drawn: ArrayLike, *, alpha: ArrayLike | None = None,
              figure: ArrayLike | None = None) -> NDArray[np.uint8]:
    """The drawing and the elements in depth order (eq. 25-26), ``(H, W, 3)`` bytes.

    Parameters
    ----------
    drawing : (H, W, 3 or 4) uint8
    layer : Layer
        The elements rendered from the frame's camera.
    drawn : (H, W) float
        The drawing's depth (:func:`drawn_depth`).
    alpha, figure : optional
        The drawing's alpha and occlusion map; default :func:`drawing_alpha` of ``drawing``.

    With no element seen anywhere the result is the drawing's colour, bit for bit.
    """
    F = np.asarray(drawing)
    if alpha is None or figure is None:
        alpha, figure = drawing_alpha(F)
    colour = F[..., :3]
    H, W = colour.shape[:2]
    if layer.depth.shape != (H, W):
        h, w = layer.depth.shape
        raise SceneError(f"the render is {w}x{h} pixels but the drawing is {W}x{H}")
    out = colour.copy()  # C-ordered
    _mix(out, layer.colour, layer.depth, layer.coverage, layer.alpha, np.asarray(alpha, dtype=np.float64),
         np.asarray(figure, dtype=np.float64), np.asarray(drawn, dtype=np.float64))
    return out


@njit(cache=True)
def _mix(out, colour, depth, seen, cover, alpha, occlusion, drawn):  # pragma: no cover - compiled
    """Eq. 25-26 in place on ``out`` (the drawing's colour) where an element is ``seen``: the
    drawing's alpha where it is in front of the element (at least its occlusion map), none where
    it is behind, its own off the figure; then the drawing over the element, rounded half to even.
    Where the element covers a fraction ``cover`` < 1 of the pixel (its edge), only that fraction
    of what it would show is shown."""
    H, W = seen.shape
    for i in range(H):
        for j in range(W):
            if not seen[i, j]:
                continue
            a = alpha[i, j]
            o = occlusion[i, j]
            if o > 0:
                a = max(a, o) if drawn[i, j] < depth[i, j] else 0.0
            if cover[i, j] < 1.0:
                a = 1.0 - (1.0 - a) * cover[i, j]
            for c in range(3):
                mixed = a * out[i, j, c] + (1.0 - a) * colour[i, j, c]
                out[i, j, c] = min(max(np.rint(mixed), 0), 255)
