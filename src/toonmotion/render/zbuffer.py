"""Spheres and capsules seen through a :class:`PerspectiveCamera`: colour, depth and coverage.

Simulated 3D elements (balloons, balls, strings) are rendered per frame from the estimated
camera, to be depth-composited with the drawing. Each primitive is ray-cast exactly, and the
nearest hit per pixel is kept (a z-buffer: the order of the primitives does not matter). For
speed the primitives of a kind are cast together in NumPy, and only at the pixels they may
cover: within the screen box of their bounding spheres, on each row the pixels between the two
roots of a quadratic in the ray's x (a sphere, or the infinite cylinder round a capsule's axis),
with a pixel of margin. Spheres and capsules that reach behind the camera are cast over the
whole image, and only hits in front count.

Conventions: 3D is right-handed, +Y up, metres; pictures are RGB, y down. Pixel ``(i, j)`` (row,
column) is sampled at its centre, ``(j, i)`` in the camera's pixel coordinates (toonmotion's
convention: a pixel's centre is at whole numbers, as the drawn markers are), so its ray is
``camera.rays`` of that point. The depth of a hit is ``z_c``, its distance along the
camera's axis (what :meth:`PerspectiveCamera.depth` gives), not along the ray: rays are scaled to
unit depth, so a hit's ray parameter is its depth. Hits at depth ``MIN_DEPTH`` or less are not
seen; a camera inside a primitive sees its inside. A capsule is the set of points within its
radius of the segment ``ab``: a cylinder with hemispherical caps.

Anti-aliasing: with ``antialias=k`` each pixel casts ``k x k`` rays on a grid centred on it (a
:class:`SampleBuffer`'s samples), resolved into a pixel's coverage (``alpha``), mean colour and
nearest depth by :mod:`toonmotion.render.samples`. Only a window of the picture is cast: the box
the primitives (and cloth drawn in later) may cover, :func:`window_of`.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from typing import NamedTuple

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import SceneError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.proxy3d.camera import MIN_DEPTH, PerspectiveCamera
from toonmotion.render.ray_hits import draw_capsules, draw_spheres
from toonmotion.render.samples import resolve_samples

SHADINGS = ("flat", "smooth", "toon")
GREY = (180, 180, 180)
LIGHT = (-0.4, 0.8, 0.45)
# Smooth and toon shading: AMBIENT + (1 - AMBIENT) * max(0, n . l), toon in TOON_BANDS levels.
AMBIENT = 0.35
TOON_BANDS = 3
# Rays per pixel side at most: 4 x 4 = 16 rays a pixel, 16 times the memory and on the demo 7 times the time.
MAX_ANTIALIAS = 4


@dataclass(frozen=True, eq=False)
class Layer:
    """What a camera sees of some primitives on one frame; every array is read-only.

    Attributes
    ----------
    colour : (H, W, 3) uint8
        Shaded RGB where a primitive is seen, black elsewhere.
    depth : (H, W) float64
        Depth (metres along the camera's axis) of the nearest surface, ``inf`` where nothing.
    coverage : (H, W) bool
        The occlusion map: True where any primitive is seen.
    ids : (H, W) int32
        Index of the primitive seen, spheres first and then capsules, -1 where nothing.
    alpha : (H, W) float64
        The fraction of the pixel the elements cover, 0 to 1: of its ``k x k`` rays when rendered
        with ``antialias=k``, else 1 where ``coverage`` and 0 elsewhere.

    With ``antialias=k > 1`` a pixel's colour is the mean of its rays that hit (its edge pixels
    blend what they see), its depth and id the nearest of them.
    """

    colour: NDArray[np.uint8]
    depth: NDArray[np.float64]
    coverage: NDArray[np.bool_]
    ids: NDArray[np.int32]
    alpha: NDArray[np.float64]


def render_primitives(camera: PerspectiveCamera, frame: int, *, spheres: ArrayLike | None = None,
                      capsules: ArrayLike | None = None, colours: ArrayLike | None = None,
                      shading: str = "toon", light: ArrayLike = LIGHT, antialias: int = 1) -> Layer:
    """Ray-cast spheres and capsules through ``camera`` on ``frame``, nearest hit per pixel.

    Parameters
    ----------
    camera : PerspectiveCamera
        The whole image, ``camera.width`` x ``camera.height``, is rendered.
    frame : int
        The camera's frame, ``0 <= frame < camera.frame_count``.
    spheres : (S, 4) float, optional
        Centre x, y, z and radius, metres.
    capsules : (C, 7) float, optional
        End ``a`` (3), end ``b`` (3) and radius, metres; ``a == b`` is a sphere.
    colours : (S + C, 3) uint8, optional
        RGB per primitive, spheres then capsules; default a neutral grey.
    shading : {"flat", "smooth", "toon"}
        ``"flat"``: the colour as is; ``"smooth"``: Lambert with ambient light,
        ``AMBIENT + (1 - AMBIENT) * max(0, n . l)``; ``"toon"``: that in three bands (a cel look).
    light : (3,) float
        Direction towards the light in the world; normalised here.
    antialias : int
        Rays per pixel side, 1 to :data:`MAX_ANTIALIAS`: ``k`` casts ``k x k`` rays a pixel on a
        regular grid centred on it, and the layer's ``alpha`` is the fraction that hit.

    Returns
    -------
    Layer

    Raises
    ------
    SceneError
        A frame the camera does not have, an unknown shading, arrays of the wrong shape,
        non-finite values, negative radii, colours that are not 0-255, a zero light direction,
        an ``antialias`` out of range.

    Examples
    --------
    A unit sphere 5 m ahead of a camera 40 x 30 pixels, whose pixel (15, 20)'s ray is the
    camera's axis:

    >>> cam = PerspectiveCamera(100.0, 40, 30, [[0, 0, 0, 0, 0, 5]])
    >>> layer = render_primitives(cam, 0, spheres=[[0, 0, 0, 1]], shading="flat")
    >>> float(layer.depth[15, 20]), int(layer.ids[15, 20]), layer.colour[15, 20].tolist()
    (4.0, 0, [180, 180, 180])
    >>> bool(layer.coverage[0, 0]), float(layer.depth[0, 0]), int(layer.ids[0, 0])
    (False, inf, -1)
    """
    return cast_primitives(camera, frame, spheres=spheres, capsules=capsules, colours=colours,
                           shading=shading, light=light, antialias=antialias).layer()


def cast_primitives(camera: PerspectiveCamera, frame: int, *, spheres: ArrayLike | None = None,
                    capsules: ArrayLike | None = None, colours: ArrayLike | None = None,
                    shading: str = "toon", light: ArrayLike = LIGHT, antialias: int = 1,
                    window: tuple[int, int, int, int] | None = None) -> SampleBuffer:
    """:func:`render_primitives`'s rays, not yet resolved into pixels: more (cloth) can be drawn in.

    Only the pixels in ``window`` (rows ``i0:i1``, columns ``j0:j1``; default, those the primitives
    may cover, :func:`window_of`) are cast: the rest of the picture is nothing.
    """
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}; got {shading!r}")
    t = checked_frame(camera, frame)
    S = _primitives(spheres, 4, "spheres", "(S, 4): centre x, y, z and radius")
    C = _primitives(capsules, 7, "capsules", "(C, 7): end a x, y, z, end b x, y, z and radius")
    rgb = _colours(colours, len(S) + len(C))
    R, centre = camera.rotations[t], camera.centres[t]
    if window is None:
        window = window_of(camera, t, spheres=S, capsules=C)
    z = SampleBuffer(camera, checked_antialias(antialias), R @ checked_light(light), rgb, shading, window)
    a, b = to_camera(C[:, 0:3], R, centre), to_camera(C[:, 3:6], R, centre)
    point = np.all(C[:, 0:3] == C[:, 3:6], axis=1)  # a capsule whose ends coincide is a sphere
    ids = np.arange(len(S) + len(C), dtype=np.int32)
    # Rays that miss give NaN roots (square roots of negative numbers): they fail every test.
    with np.errstate(invalid="ignore", divide="ignore"):
        draw_spheres(z, np.concatenate([ids[:len(S)], ids[len(S):][point]]),
                 np.concatenate([to_camera(S[:, :3], R, centre), a[point]]),
                 np.concatenate([S[:, 3], C[point, 6]]))
        draw_capsules(z, ids[len(S):][~point], a[~point], b[~point], C[~point, 6])
    return z


class _Rows(NamedTuple):
    """One entry per primitive and image row of its box."""

    prim: NDArray[np.intp]  # the primitive, an index into its batch
    y: NDArray[np.float64]  # the row's rays' y (x_c / z_c)
    start: NDArray[np.intp]  # flat index of the row's first pixel
    j0: NDArray[np.intp]  # the box's columns, j0:j1
    j1: NDArray[np.intp]


class SampleBuffer:
    """The image's rays, ``k x k`` a pixel, with their buffers (flat) and each ray's direction.

    The rays lie on a grid of ``k W`` columns and ``k H`` rows, "samples": sample ``J`` is at
    ``u = (J - (k - 1) / 2) / k`` in the camera's pixel coordinates, so pixel ``j``'s ``k`` samples
    are centred on ``j`` (``k = 1``: the pixel's centre). Only a ``window`` of pixels may have rays
    (rows ``i0:i1``, columns ``j0:j1``; default the whole picture): the grid starts at its corner,
    and on it the camera has focal length ``k f`` and its principal point at ``(cx, cy)``, in
    samples. :meth:`layer` resolves the samples into pixels.

    Primitives are drawn in batches: :meth:`rows` and :meth:`pixels` list the samples each may
    cover, the caller finds its depth there, :meth:`keep` keeps the nearest hits.
    """

    def __init__(self, camera, antialias, light=(0.0, 0.0, 1.0), rgb=None, shading="flat", window=None):
        rgb = np.zeros((0, 3)) if rgb is None else rgb
        k = antialias
        self.antialias, self.pixels_wide, self.pixels_high = k, camera.width, camera.height
        self.window = (0, camera.height, 0, camera.width) if window is None else window
        i0, i1, j0, j1 = self.window
        W, H = k * (j1 - j0), k * (i1 - i0)
        self.focal, self.width, self.height, self.shading = k * camera.focal, W, H, shading
        self.cx = k * camera.width / 2 + (k - 1) / 2 - k * j0
        self.cy = k * camera.height / 2 + (k - 1) / 2 - k * i0
        self.light = tuple(np.asarray(light, dtype=np.float64).tolist())
        # A sample's ray in the camera's frame is (x[j], y[i], 1): unit depth, as camera.rays gives.
        self.x = (np.arange(W) - self.cx) / self.focal
        self.y = (np.arange(H) - self.cy) / self.focal
        self.depth = np.full(H * W, np.inf)
        self.ids = np.full(H * W, -1, np.int32)
        # RGBA bytes packed in one uint32 per pixel: one scatter per hit.
        self.colour = np.zeros(H * W, np.uint32)
        self.rgb = rgb.astype(np.float64)
        # Where R, G and B sit in a packed pixel: its bytes in memory are R, G, B, A.
        self.shifts = (0, 8, 16) if sys.byteorder == "little" else (24, 16, 8)
        # Flat: one level; toon: a level per band, the top one twice (n.l = 1 gives band index 3).
        band = np.minimum(np.arange(TOON_BANDS + 1), TOON_BANDS - 1) / (TOON_BANDS - 1)
        levels = np.ones(1) if shading == "flat" else AMBIENT + (1 - AMBIENT) * band
        palette = np.zeros((len(rgb), len(levels), 4), np.uint8)
        palette[..., :3] = np.rint(self.rgb[:, None, :] * levels[:, None])
        self.levels = len(levels)
        self.palette = palette.view(np.uint32).ravel()  # primitive k, level l at k * levels + l

    def box(self, extent):
        """Rows ``i0:i1`` and columns ``j0:j1`` whose centres may fall in ``extent`` (pixels), or None.

        No extent: the whole image.
        """
        if extent is None:
            return 0, self.height, 0, self.width
        x0, x1, y0, y1 = extent
        # Pixel j's centre is j; a pixel of margin for rounding. Clamp before int().
        j0 = max(0, math.floor(min(max(x0, -2.0), self.width + 2.0)) - 1)
        j1 = min(self.width, math.ceil(min(max(x1, -2.0), self.width + 2.0)) + 2)
        i0 = max(0, math.floor(min(max(y0, -2.0), self.height + 2.0)) - 1)
        i1 = min(self.height, math.ceil(min(max(y1, -2.0), self.height + 2.0)) + 2)
        return (i0, i1, j0, j1) if i0 < i1 and j0 < j1 else None

    def rows(self, boxes):
        """The rows of each primitive's box (None: nothing to draw), as :class:`_Rows`; None if none."""
        live = [k for k, box in enumerate(boxes) if box is not None]
        if not live:
            return None
        i0, i1, j0, j1 = np.array([boxes[k] for k in live]).T
        n = i1 - i0
        i = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n - i0, n)
        return _Rows(np.repeat(live, n), self.y[i], i * self.width, np.repeat(j0, n), np.repeat(j1, n))

    def pixels(self, rows, alpha, beta, gamma, bounded):
        """The pixels whose rays ``(x, y, 1)`` may have ``alpha x^2 + beta x + gamma >= 0`` on each row.

        The coefficients hold one value per row. Where the row is ``bounded`` (``alpha`` clearly
        negative) its pixels are those between the roots, with a pixel of margin; elsewhere the
        whole row of the box. A superset, to be tested exactly: returns each pixel's entry in
        ``rows``, its ray's x and its flat index, or None.
        """
        disc = beta * beta - 4 * alpha * gamma
        root = np.sqrt(np.maximum(disc, 0.0))
        # Column j's ray has x = (j - half) / f: the roots as columns, clamped before int().
        half, scale = self.cx, self.focal / (2 * alpha)
        j0, j1 = rows.j0, rows.j1
        lo = np.minimum(np.maximum((root - beta) * scale + half, j0 - 1.0), j1 + 1.0)
        hi = np.minimum(np.maximum((root + beta) * -scale + half, j0 - 1.0), j1 + 1.0)
        first = np.where(bounded, np.maximum(np.ceil(lo) - 1, j0), j0).astype(np.intp)
        last = np.where(bounded, np.minimum(np.floor(hi) + 1, j1 - 1), j1 - 1).astype(np.intp)
        counts = np.maximum(last - first + 1, 0) * ((disc >= 0) | ~bounded)
        total = int(counts.sum())
        if total == 0:
            return None
        # Each row's run of columns, one after another.
        row = np.repeat(np.arange(len(counts)), counts)
        j = np.arange(total) + (first - (np.cumsum(counts) - counts))[row]
        return row, self.x[j], rows.start[row] + j

    def keep(self, flat, depth, lit, ids):
        """Keep the hits at pixels ``flat`` nearer than what is there (NaN depth: no hit).

        ``lit`` is ``n . l`` with the unit normal that faces the camera (None for flat shading);
        ``ids`` are the hits' primitives. Several hits may share a pixel: the nearest is kept.
        """
        np.fmin.at(self.depth, flat, depth)
        win = np.flatnonzero(depth == self.depth[flat])
        flat, ids = flat[win], ids[win]
        self.ids[flat] = ids
        if self.shading == "flat":
            self.colour[flat] = self.palette[ids]
            return
        lit = np.maximum(lit[win], 0.0)
        if self.shading == "toon":
            self.colour[flat] = self.palette[ids * self.levels + (lit * TOON_BANDS).astype(np.intp)]
        else:
            value = AMBIENT + (1 - AMBIENT) * lit
            packed = np.zeros(len(flat), np.uint32)
            for channel, shift in enumerate(self.shifts):
                packed |= np.rint(self.rgb[:, channel][ids] * value).astype(np.uint32) << shift
            self.colour[flat] = packed

    def rgba(self):
        """The samples' colours, ``(k H * k W, 4)`` bytes R, G, B, A: a view to draw into."""
        return self.colour.view(np.uint8).reshape(-1, 4)

    def layer(self):
        """The samples resolved into pixels: a :class:`Layer` of read-only ``(H, W)`` arrays."""
        k, (i0, i1, j0, j1) = self.antialias, self.window
        ids, depth = self.ids.reshape(self.height, self.width), self.depth.reshape(self.height, self.width)
        rgba = self.colour.view(np.uint8).reshape(self.height, self.width, 4)
        if k == 1:
            rgb = np.zeros(ids.shape + (3,), np.uint8)
            if ids.size:  # OpenCV drops the alpha bytes faster than NumPy's strided copy
                rgb = np.asarray(cv2.cvtColor(rgba, cv2.COLOR_RGBA2RGB), np.uint8)
            alpha = (ids >= 0).astype(np.float64)
        else:
            rgb, depth, ids, alpha = resolve_samples(rgba, depth, ids, k)
        H, W = self.pixels_high, self.pixels_wide
        if (i1 - i0, j1 - j0) != (H, W):  # the window in the whole picture
            whole = (np.zeros((H, W, 3), np.uint8), np.full((H, W), np.inf), np.full((H, W), -1, np.int32),
                     np.zeros((H, W)))
            for array, part in zip(whole, (rgb, depth, ids, alpha), strict=True):
                array[i0:i1, j0:j1] = part
            rgb, depth, ids, alpha = whole
        layer = Layer(colour=rgb, depth=depth, coverage=ids >= 0, ids=ids, alpha=alpha)
        for array in (layer.colour, layer.depth, layer.coverage, layer.ids, layer.alpha):
            array.setflags(write=False)
        return layer


def window_of(camera: PerspectiveCamera, frame: int, *, spheres: NDArray[np.float64] | None = None,
              capsules: NDArray[np.float64] | None = None, points: NDArray[np.float64] | None = None
              ) -> tuple[int, int, int, int]:
    """The pixels ``(i0, i1, j0, j1)`` (rows ``i0:i1``, columns ``j0:j1``) where spheres ``(S, 4)``,
    capsules ``(C, 7)`` and points ``(n, 3)`` may be seen on ``frame``, with two pixels of margin.

    Points at depth ``MIN_DEPTH`` or less are left out (a triangle with such a corner is not
    drawn); a sphere or capsule that reaches there may be seen anywhere: the whole picture.
    """
    R, centre = camera.rotations[frame], camera.centres[frame]
    balls = [np.zeros((0, 4))]
    if spheres is not None:
        balls.append(spheres)
    if capsules is not None:
        balls += [capsules[:, [0, 1, 2, 6]], capsules[:, [3, 4, 5, 6]]]
    if points is not None:
        balls.append(np.concatenate([points, np.zeros((len(points), 1))], axis=1))
    ball = np.concatenate(balls)
    ball = ball[np.isfinite(ball).all(axis=1)]  # refused by what draws them
    m, r = to_camera(ball[:, :3], R, centre), ball[:, 3]
    behind = m[:, 2] - r <= MIN_DEPTH
    if np.any(behind & (r > 0)):
        return 0, camera.height, 0, camera.width
    m, r = m[~behind], r[~behind]
    if not len(m):
        return 0, 0, 0, 0
    # The tangent planes through the camera bound each sphere's picture (see ray_hits._sphere_extent).
    den = m[:, 2] ** 2 - r ** 2
    f, W, H = camera.focal, camera.width, camera.height
    bounds = []
    for axis, half in ((1, H / 2), (0, W / 2)):
        rho = np.sqrt(m[:, axis] ** 2 + den)
        low, high = (m[:, axis] * m[:, 2] - r * rho) / den, (m[:, axis] * m[:, 2] + r * rho) / den
        lo, hi = f * low.min() + half, f * high.max() + half
        size = H if axis == 1 else W
        bounds += [int(min(max(math.floor(lo) - 2, 0), size)), int(min(max(math.ceil(hi) + 3, 0), size))]
    i0, i1, j0, j1 = bounds
    return (i0, i1, j0, j1) if i0 < i1 and j0 < j1 else (0, 0, 0, 0)


def to_camera(points, R, centre):
    """World points ``(n, 3)`` in the camera's frame, each row computed alike whatever ``n``."""
    d = points - centre
    return d[:, 0:1] * R[:, 0] + d[:, 1:2] * R[:, 1] + d[:, 2:3] * R[:, 2]


def checked_frame(camera, frame):
    """``frame`` checked against the camera's frames: one of them, a whole number."""
    T = camera.frame_count
    if isinstance(frame, bool) or not isinstance(frame, int | np.integer) or not 0 <= frame < T:
        raise SceneError(f"the frame must be a whole number from 0 to {T - 1} (the camera has {T} "
                         f"frames), got {frame!r}")
    return int(frame)


def _primitives(value, columns, name, layout):
    if value is None:
        return np.zeros((0, columns))
    array = frozen_array(value, dtype=np.float64, name=f"the {name}", error=SceneError, finite=True)
    if array.size == 0:
        return np.zeros((0, columns))
    if array.ndim != 2 or array.shape[1] != columns:
        raise SceneError(f"the {name} must be an array of shape {layout}; got shape {array.shape}")
    if np.any(array[:, -1] < 0):
        i = int(np.flatnonzero(array[:, -1] < 0)[0])
        raise SceneError(f"the {name} must have radii >= 0; number {i} has radius {array[i, -1]:g}")
    return array


def _colours(value, n):
    if value is None:
        return np.tile(np.array(GREY, np.uint8), (n, 1))
    rgb = frozen_array(value, dtype=np.uint8, name="the colours", error=SceneError)
    if rgb.shape != (n, 3):
        raise SceneError(f"the colours must be an (S + C, 3) = ({n}, 3) array of RGB 0-255, one per "
                         f"primitive; got shape {rgb.shape}")
    return rgb


def checked_antialias(value):
    """``antialias`` checked: a whole number of rays per pixel side, 1 to :data:`MAX_ANTIALIAS`."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 1 <= value <= MAX_ANTIALIAS:
        raise SceneError(f"antialias must be a whole number of rays per pixel side from 1 (off) to "
                         f"{MAX_ANTIALIAS}, got {value!r}")
    return int(value)


def checked_light(value):
    """The light's direction, checked: three finite numbers, not all zero."""
    light = frozen_array(value, dtype=np.float64, name="the light", error=SceneError, finite=True)
    if light.shape != (3,):
        raise SceneError(f"the light must be a direction (x, y, z); got shape {light.shape}")
    norm = float(np.linalg.norm(light))
    if norm == 0:
        raise SceneError("the light must be a non-zero direction (x, y, z); got (0, 0, 0)")
    return light / norm


def layer_passes(layer: Layer, *, depth_unit: float = 0.001
                 ) -> tuple[NDArray[np.uint8], NDArray[np.uint16], NDArray[np.uint8]]:
    """A layer as the three passes a compositing program reads: beauty, depth and occlusion.

    Returns
    -------
    beauty : (H, W, 4) uint8
        The colour, its alpha the layer's (the fraction of the pixel covered, 0-255: opaque
        inside an element, partly transparent on its edges, transparent elsewhere).
    depth : (H, W) uint16
        Depth in ``depth_unit`` metres (millimetres by default), rounded and capped at 65,535;
        0 where nothing is seen.
    occlusion : (H, W) uint8
        The same coverage as a matte: 255 inside an element, 0 where none is seen.

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import MIN_DEPTH, PerspectiveCamera
    >>> cam = PerspectiveCamera(100.0, 40, 30, [[0, 0, 0, 0, 0, 5]])
    >>> beauty, depth, seen = layer_passes(render_primitives(cam, 0, spheres=[[0, 0, 0, 1]]))
    >>> int(depth[15, 20]), int(beauty[15, 20, 3]), int(seen[0, 0])
    (4000, 255, 0)
    """
    if not (np.isfinite(depth_unit) and depth_unit > 0):
        raise SceneError(f"the depth unit must be a positive number of metres, got {depth_unit!r}")
    covered = layer.coverage
    matte = np.rint(layer.alpha * 255).astype(np.uint8)
    beauty = np.concatenate([layer.colour, matte[..., None]], axis=2)
    depth = np.zeros(covered.shape, np.uint16)
    depth[covered] = np.clip(np.rint(layer.depth[covered] / depth_unit), 1, 65535).astype(np.uint16)
    return beauty, depth, matte
