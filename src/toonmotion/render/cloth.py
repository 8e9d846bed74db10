"""Cloth triangles seen through a :class:`PerspectiveCamera`, z-buffered into a :class:`Layer`.

Simulated scarves and skirts (:mod:`toonmotion.scene.simulate`) are triangle meshes. They are
rasterised here, to be drawn in the same layer as the ray-cast spheres and capsules of
:func:`toonmotion.render.zbuffer.render_primitives` and depth-composited with the drawing alike.

Each triangle visits the pixels of its screen box; a pixel is the triangle's when its centre is
inside it (edge functions, either winding: cloth is two-sided); the loop is compiled with Numba
(the demo's scarf and skirt in 2-5 ms a frame, against 27 ms in NumPy). Depth is interpolated
perspective-correctly (``1 / z`` is affine on the screen) and is ``z_c``, the distance along the
camera's axis, as the ray caster's. Normals are the vertices' (the mean of their triangles'),
interpolated and turned to face the camera, lit as the ray caster lights (flat, smooth or toon
bands). A triangle with a vertex at depth ``MIN_DEPTH`` or less is not drawn.

Conventions as :mod:`toonmotion.render.zbuffer`: +Y up, metres; pixel ``(i, j)`` is sampled at
``(j, i)`` in the camera's pixel coordinates.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from toonmotion.errors import SceneError
from toonmotion.proxy3d.camera import MIN_DEPTH, PerspectiveCamera
from toonmotion.render.zbuffer import (
    AMBIENT,
    LIGHT,
    SHADINGS,
    TOON_BANDS,
    Layer,
    SampleBuffer,
    checked_antialias,
    checked_frame,
    checked_light,
    to_camera,
    window_of,
)


def render_cloth(camera: PerspectiveCamera, frame: int, V: ArrayLike, F: ArrayLike, colours: ArrayLike, *,
                 shading: str = "toon", light: ArrayLike = LIGHT, under: Layer | None = None,
                 first_id: int = 0, antialias: int = 1) -> Layer:
    """Rasterise triangles ``F`` of vertices ``V`` through ``camera`` on ``frame``, over ``under``.

    Parameters
    ----------
    camera : PerspectiveCamera
    frame : int
    V : (n, 3) float
        Vertices, metres.
    F : (m, 3) int
        Triangles, indices into ``V``; either winding.
    colours : (m, 3) uint8
        Each triangle's colour.
    shading : {"flat", "smooth", "toon"}
        As :func:`toonmotion.render.zbuffer.render_primitives`.
    light : (3,) float
    under : Layer, optional
        What is already drawn (spheres and capsules): a pixel keeps the nearer of the two.
    first_id : int
        The id of triangle 0 in the layer's ``ids`` (after the primitives'); ``-1`` stays nothing.
    antialias : int
        Rays per pixel side, as :func:`toonmotion.render.zbuffer.render_primitives`; 1 with
        ``under`` (to antialias cloth with primitives, :func:`draw_cloth` into their buffer).

    Returns
    -------
    Layer

    Examples
    --------
    A square of two triangles 5 m ahead, facing the camera, half a metre (10 pixels) on a side:
    the 11 x 11 pixel centres on it or on its edges are the cloth's.

    >>> cam = PerspectiveCamera(100.0, 40, 30, [[0, 0, 0, 0, 0, 5]])
    >>> V = [[-0.25, -0.25, 0], [0.25, -0.25, 0], [0.25, 0.25, 0], [-0.25, 0.25, 0]]
    >>> layer = render_cloth(cam, 0, V, [[0, 1, 2], [0, 2, 3]], [[200, 0, 0]] * 2, shading="flat")
    >>> float(layer.depth[15, 20]), layer.colour[15, 20].tolist(), int(layer.coverage.sum())
    (5.0, [200, 0, 0], 121)
    """
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    window = None if under is not None or not np.isfinite(V).all() else window_of(
        camera, checked_frame(camera, frame), points=V)
    buffer = SampleBuffer(camera, checked_antialias(antialias), window=window)
    if under is not None:
        if antialias != 1 or not np.isin(under.alpha, (0.0, 1.0)).all():
            raise SceneError("cloth over a layer is drawn one ray a pixel, over a layer of one ray a pixel: "
                             "to antialias both, draw the cloth into the primitives' rays (draw_cloth)")
        if under.depth.shape != (camera.height, camera.width):
            h, w = under.depth.shape
            raise SceneError(f"the layer under the cloth is {w}x{h} pixels but the camera's picture is "
                             f"{camera.width}x{camera.height}")
        buffer.depth[:] = under.depth.ravel()
        buffer.ids[:] = under.ids.ravel()
        buffer.rgba()[:, :3] = under.colour.reshape(-1, 3)
    draw_cloth(buffer, camera, frame, V, F, colours, shading=shading, light=light, first_id=first_id)
    return buffer.layer()


def draw_cloth(buffer: SampleBuffer, camera: PerspectiveCamera, frame: int, V: ArrayLike, F: ArrayLike,
               colours: ArrayLike, *, shading: str = "toon", light: ArrayLike = LIGHT,
               first_id: int = 0) -> None:
    """:func:`render_cloth` into ``buffer``'s rays (made for ``camera``), nearer hits kept.

    The buffer's window must hold the cloth (:func:`toonmotion.render.zbuffer.window_of` of its
    vertices, with the primitives'): cloth outside it would be cut off, so it is refused.
    """
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}; got {shading!r}")
    t = checked_frame(camera, frame)
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    rgb = np.asarray(colours, dtype=np.uint8).reshape(-1, 3)
    if len(F) and len(V):
        if not np.isfinite(V).all():
            raise SceneError("the cloth's vertices must be finite")
        i0, i1, j0, j1 = window_of(camera, t, points=V)
        w0, w1, v0, v1 = buffer.window
        if i0 < i1 and not (w0 <= i0 and i1 <= w1 and v0 <= j0 and j1 <= v1):
            raise SceneError(f"the cloth is seen at rows {i0}:{i1}, columns {j0}:{j1}, outside the rays' "
                             f"window (rows {w0}:{w1}, columns {v0}:{v1}): cast them with a window that "
                             "holds it (window_of with the cloth's points)")
        R, centre = camera.rotations[t], camera.centres[t]
        _rasterise(to_camera(V, R, centre), F, rgb, R @ checked_light(light), shading, buffer, first_id)


def _rasterise(C, F, rgb, light, shading, buffer, first_id):
    """Draw triangles ``F`` of camera-frame vertices ``C`` into the buffer's rays, nearest kept."""
    z = C[:, 2]
    seen = (z[F] > MIN_DEPTH).all(axis=1)
    k = np.flatnonzero(seen)
    if not len(k):
        return
    # Vertices on the buffer's grid of rays (samples; pixels when one ray a pixel): on the whole
    # picture's grid, then shifted to the window's corner, exactly (whole numbers of samples).
    f, cx, cy = buffer.focal, buffer.cx, buffer.cy
    top, left = buffer.antialias * buffer.window[0], buffer.antialias * buffer.window[2]
    u = np.where(z > MIN_DEPTH, (f * C[:, 0] / np.maximum(z, MIN_DEPTH) + (cx + left)) - left, 0.0)
    v = np.where(z > MIN_DEPTH, (f * C[:, 1] / np.maximum(z, MIN_DEPTH) + (cy + top)) - top, 0.0)
    _triangles(u, v, z, _vertex_normals(C, F), F[k], k.astype(np.int64), rgb, light.astype(np.float64),
               SHADINGS.index(shading), float(f), float(cx), float(cy), buffer.antialias, buffer.width,
               buffer.height, buffer.depth, buffer.ids, buffer.rgba(), first_id, AMBIENT, TOON_BANDS)


@njit(cache=True)
def _triangles(u, v, z, normals, F, k, rgb, light, shading, f, cx, cy, n, W, H, depth, ids, colour, first_id,
               ambient, bands):  # pragma: no cover - compiled
    """The rasteriser's loop, compiled: every triangle's rays (samples) on each row of its screen box
    between where its edges cross the row (a sample of margin; the exact test is per sample), in
    order, a later triangle winning a tie. ``shading`` indexes :data:`SHADINGS`; ``(cx, cy)`` is the
    principal point, ``f`` the focal length and ``W x H`` the grid, all in samples, ``n x n`` a
    pixel. A triangle is shaded once a pixel, at the first of the pixel's samples it wins (as
    multisampling does), and that colour is given to each sample of the pixel it wins."""
    shaded_by = np.full((H // n) * (W // n), -1, np.int64)  # the last triangle to shade each pixel
    shade = np.zeros((len(shaded_by), 3), np.uint8)
    for m in range(len(F)):
        a, b, c = F[m, 0], F[m, 1], F[m, 2]
        ua, ub, uc, va, vb, vc = u[a], u[b], u[c], v[a], v[b], v[c]
        area = (ub - ua) * (vc - va) - (uc - ua) * (vb - va)
        if abs(area) <= 1e-12:
            continue
        j0 = max(0, min(W, int(math.ceil(min(ua, ub, uc)))))
        j1 = max(0, min(W, int(math.floor(max(ua, ub, uc))) + 1))
        i0 = max(0, min(H, int(math.ceil(min(va, vb, vc)))))
        i1 = max(0, min(H, int(math.floor(max(va, vb, vc))) + 1))
        # Barycentric coordinates are affine on the screen. Measured from corner a they are the same
        # numbers wherever the grid starts (a window's shift is exact), so a window changes nothing.
        Ub, Vb, Uc, Vc = ub - ua, vb - va, uc - ua, vc - va
        P1, Q1, P2, Q2 = Vc / area, -Uc / area, -Vb / area, Ub / area  # b1 = P1 X + Q1 Y, b2 = P2 X + Q2 Y
        za, zb, zc = 1.0 / z[a], 1.0 / z[b], 1.0 / z[c]
        for i in range(i0, i1):
            y = float(i)
            Y = y - va
            r1, r2 = Q1 * Y, Q2 * Y
            lo, hi = float(j0), float(j1 - 1)
            for P, R in ((P1, r1), (P2, r2), (-P1 - P2, 1.0 - r1 - r2)):  # each b >= -1e-9 where X ...
                if P > 1e-12:
                    lo = max(lo, ua + (-1e-9 - R) / P - 1.0)
                elif P < -1e-12:
                    hi = min(hi, ua + (-1e-9 - R) / P + 1.0)
            for j in range(int(math.ceil(lo)), int(math.floor(hi)) + 1):
                x = float(j)
                X = x - ua
                b1, b2 = P1 * X + r1, P2 * X + r2
                b0 = 1.0 - b1 - b2
                if b0 < -1e-9 or b1 < -1e-9 or b2 < -1e-9:
                    continue
                d = 1.0 / (b0 * za + b1 * zb + b2 * zc)  # 1 / depth is affine on the screen
                p = i * W + j
                if d > depth[p]:
                    continue
                depth[p] = d
                ids[p] = first_id + k[m]
                pixel = (i // n) * (W // n) + j // n
                if shaded_by[pixel] != m:
                    value = 1.0 if shading == 0 else _lit(b0 * za * d, b1 * zb * d, b2 * zc * d,
                                                           normals[a], normals[b], normals[c], (x - cx) / f,
                                                           (y - cy) / f, light, shading, ambient, bands)
                    for ch in range(3):
                        shade[pixel, ch] = min(max(np.rint(rgb[k[m], ch] * value), 0), 255)
                    shaded_by[pixel] = m
                for ch in range(3):
                    colour[p, ch] = shade[pixel, ch]


@njit(cache=True)
def _lit(p0, p1, p2, na, nb, nc, rx, ry, light, shading, ambient, bands):  # pragma: no cover - compiled
    """The light on a triangle where its perspective-correct weights are ``p0, p1, p2``: the
    vertices' normals interpolated, turned to face the ray ``(rx, ry, 1)``, lit smooth (1) or in
    toon bands (2)."""
    nx = p0 * na[0] + p1 * nb[0] + p2 * nc[0]
    ny = p0 * na[1] + p1 * nb[1] + p2 * nc[1]
    nz = p0 * na[2] + p1 * nb[2] + p2 * nc[2]
    size = max(math.sqrt(nx * nx + ny * ny + nz * nz), 1e-12)
    nx, ny, nz = nx / size, ny / size, nz / size
    if nx * rx + ny * ry + nz > 0:
        nx, ny, nz = -nx, -ny, -nz
    lit = max(nx * light[0] + ny * light[1] + nz * light[2], 0.0)
    if shading == 2:
        lit = min(math.floor(lit * bands), bands - 1) / (bands - 1)
    return ambient + (1 - ambient) * lit


def _vertex_normals(C, F):
    """Unit normals at the vertices: the sum of their triangles' area-weighted normals."""
    n = np.cross(C[F[:, 1]] - C[F[:, 0]], C[F[:, 2]] - C[F[:, 0]])
    out = np.zeros_like(C)
    for corner in range(3):
        np.add.at(out, F[:, corner], n)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)

