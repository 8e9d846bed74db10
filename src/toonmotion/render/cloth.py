"""Cloth triangles seen through a :class:`PerspectiveCamera`, z-buffered into a :class:`Layer`.

Simulated scarves and skirts (:mod:`toonmotion.scene.simulate`) are triangle meshes. They are
rasterised here in NumPy, to be drawn in the same layer as the ray-cast spheres and capsules of
:func:`toonmotion.render.zbuffer.render_primitives` and depth-composited with the drawing alike.

Each triangle lists the pixels of its screen box; a pixel is the triangle's when its centre is
inside it (edge functions, either winding: cloth is two-sided). Depth is interpolated
perspective-correctly (``1 / z`` is affine on the screen) and is ``z_c``, the distance along the
camera's axis, as the ray caster's. Normals are the vertices' (the mean of their triangles'),
interpolated and turned to face the camera, lit as the ray caster lights (flat, smooth or toon
bands). A triangle with a vertex at depth ``MIN_DEPTH`` or less is not drawn.

Conventions as :mod:`toonmotion.render.zbuffer`: +Y up, metres; pixel ``(i, j)`` is sampled at
``(j, i)`` in the camera's pixel coordinates.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from toonmotion.errors import SceneError
from toonmotion.proxy3d.camera import MIN_DEPTH, PerspectiveCamera
from toonmotion.render.zbuffer import AMBIENT, LIGHT, SHADINGS, TOON_BANDS, Layer, _frame, _light, _to_camera


def render_cloth(camera: PerspectiveCamera, frame: int, V: ArrayLike, F: ArrayLike, colours: ArrayLike, *,
                 shading: str = "toon", light: ArrayLike = LIGHT, under: Layer | None = None,
                 first_id: int = 0) -> Layer:
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
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}; got {shading!r}")
    t = _frame(camera, frame)
    W, H, f = camera.width, camera.height, camera.focal
    if under is None:
        depth = np.full(H * W, np.inf)
        ids = np.full(H * W, -1, np.int32)
        colour = np.zeros((H * W, 3), np.uint8)
    else:
        depth = under.depth.ravel().copy()
        ids = under.ids.ravel().copy()
        colour = under.colour.reshape(-1, 3).copy()
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    rgb = np.asarray(colours, dtype=np.uint8).reshape(-1, 3)
    if len(F) and len(V):
        if not np.isfinite(V).all():
            raise SceneError("the cloth's vertices must be finite")
        R, centre = camera.rotations[t], camera.centres[t]
        _rasterise(_to_camera(V, R, centre), F, rgb, R @ _light(light), shading, f, W, H, depth, ids, colour,
                   first_id)
    layer = Layer(colour=colour.reshape(H, W, 3), depth=depth.reshape(H, W), coverage=ids.reshape(H, W) >= 0,
                  ids=ids.reshape(H, W))
    for array in (layer.colour, layer.depth, layer.coverage, layer.ids):
        array.setflags(write=False)
    return layer


def _rasterise(C, F, rgb, light, shading, f, W, H, depth, ids, colour, first_id):
    """Draw triangles ``F`` of camera-frame vertices ``C`` into the flat buffers, nearest kept."""
    z = C[:, 2]
    seen = (z[F] > MIN_DEPTH).all(axis=1)
    u = np.where(z > MIN_DEPTH, f * C[:, 0] / np.maximum(z, MIN_DEPTH) + W / 2, 0.0)
    v = np.where(z > MIN_DEPTH, f * C[:, 1] / np.maximum(z, MIN_DEPTH) + H / 2, 0.0)
    normals = _vertex_normals(C, F)
    k = np.flatnonzero(seen)
    if not len(k):
        return
    U, Vv = u[F[k]], v[F[k]]  # (m, 3)
    j0 = np.clip(np.ceil(U.min(axis=1)), 0, W).astype(np.intp)
    j1 = np.clip(np.floor(U.max(axis=1)) + 1, 0, W).astype(np.intp)
    i0 = np.clip(np.ceil(Vv.min(axis=1)), 0, H).astype(np.intp)
    i1 = np.clip(np.floor(Vv.max(axis=1)) + 1, 0, H).astype(np.intp)
    w, h = np.maximum(j1 - j0, 0), np.maximum(i1 - i0, 0)
    n = w * h
    total = int(n.sum())
    if total == 0:
        return
    tri = np.repeat(np.arange(len(k)), n)
    within = np.arange(total) - np.repeat(np.cumsum(n) - n, n)
    jj = j0[tri] + within % np.maximum(w[tri], 1)
    ii = i0[tri] + within // np.maximum(w[tri], 1)
    x, y = jj.astype(np.float64), ii.astype(np.float64)
    ua, ub, uc = U[tri, 0], U[tri, 1], U[tri, 2]
    va, vb, vc = Vv[tri, 0], Vv[tri, 1], Vv[tri, 2]
    area = (ub - ua) * (vc - va) - (uc - ua) * (vb - va)
    with np.errstate(divide="ignore", invalid="ignore"):
        b0 = ((ub - x) * (vc - y) - (uc - x) * (vb - y)) / area
        b1 = ((uc - x) * (va - y) - (ua - x) * (vc - y)) / area
    b2 = 1.0 - b0 - b1
    eps = -1e-9
    inside = (np.abs(area) > 1e-12) & (b0 >= eps) & (b1 >= eps) & (b2 >= eps)
    tri, b0, b1, b2, x, y = tri[inside], b0[inside], b1[inside], b2[inside], x[inside], y[inside]
    flat = (ii[inside] * W + jj[inside]).astype(np.intp)
    if not len(flat):
        return
    Fk = F[k[tri]]
    iz = b0 / z[Fk[:, 0]] + b1 / z[Fk[:, 1]] + b2 / z[Fk[:, 2]]  # 1 / depth, affine on the screen
    d = 1.0 / iz
    np.fmin.at(depth, flat, d)
    win = d == depth[flat]
    flat, tri, Fk, d = flat[win], tri[win], Fk[win], d[win]
    b0, b1, b2, x, y = b0[win], b1[win], b2[win], x[win], y[win]
    ids[flat] = first_id + k[tri]
    base = rgb[k[tri]].astype(np.float64)
    if shading == "flat":
        colour[flat] = base.astype(np.uint8)
        return
    # Perspective-correct weights for the normals.
    p0, p1, p2 = b0 / z[Fk[:, 0]] * d, b1 / z[Fk[:, 1]] * d, b2 / z[Fk[:, 2]] * d
    nrm = p0[:, None] * normals[Fk[:, 0]] + p1[:, None] * normals[Fk[:, 1]] + p2[:, None] * normals[Fk[:, 2]]
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    ray = np.stack([(x - W / 2) / f, (y - H / 2) / f, np.ones(len(x))], axis=1)
    nrm *= np.where((nrm * ray).sum(axis=1) > 0, -1.0, 1.0)[:, None]  # face the camera
    lit = np.maximum(nrm @ light, 0.0)
    if shading == "toon":
        band = np.minimum(np.floor(lit * TOON_BANDS), TOON_BANDS - 1) / (TOON_BANDS - 1)
        value = AMBIENT + (1 - AMBIENT) * band
    else:
        value = AMBIENT + (1 - AMBIENT) * lit
    colour[flat] = np.clip(np.rint(base * value[:, None]), 0, 255).astype(np.uint8)


def _vertex_normals(C, F):
    """Unit normals at the vertices: the sum of their triangles' area-weighted normals."""
    n = np.cross(C[F[:, 1]] - C[F[:, 0]], C[F[:, 2]] - C[F[:, 0]])
    out = np.zeros_like(C)
    for corner in range(3):
        np.add.at(out, F[:, corner], n)
    return out / np.maximum(np.linalg.norm(out, axis=1, keepdims=True), 1e-12)

