"""Where each pixel's ray meets a sphere or a capsule, written into a z-buffer
(:mod:`toonmotion.render.zbuffer`): the nearest hit per pixel, row by row, exact to the float
(the quadratic's roots, a capsule as its cylinder and its two end spheres)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from toonmotion.proxy3d.camera import MIN_DEPTH


def _sphere_extent(z, m, r):
    """Sample bounds ``(x0, x1, y0, y1)`` of a sphere wholly in front of the camera; None otherwise."""
    mx, my, mz = m
    if mz <= r:
        return None
    # Tangent planes through the camera: x_c / z_c on the sphere spans (mx mz -+ r rho) / (mz^2 - r^2).
    den = mz * mz - r * r
    rho_x, rho_y = math.sqrt(mx * mx + den), math.sqrt(my * my + den)
    f, w, h = z.focal, z.cx, z.cy
    return (f * (mx * mz - r * rho_x) / den + w, f * (mx * mz + r * rho_x) / den + w,
            f * (my * mz - r * rho_y) / den + h, f * (my * mz + r * rho_y) / den + h)


def _sphere_roots(xs, dd, mx, row_term, c, far=True):
    """The depths where rays ``(xs, y, 1)`` enter and (if ``far``) leave a sphere ``m``; NaN: miss.

    ``|t d - m|^2 = r^2`` gives ``t = (d.m -+ sqrt((d.m)^2 - c d.d)) / d.d`` with ``c = |m|^2 - r^2``;
    ``dd`` is ``d.d`` and ``d.m = mx xs + row_term``, ``row_term = my y + mz``.
    """
    b = mx * xs + row_term
    s = np.sqrt(b * b - dd * c)
    return (b - s) / dd, ((b + s) / dd if far else None)


def draw_spheres(z, ids, m, r):
    """Ray-cast spheres ``ids`` (centres ``m`` (n, 3) in the camera's frame, radii ``r``)."""
    boxes = [z.box(_sphere_extent(z, c, s)) if s > 0 and c[2] + s > MIN_DEPTH else None
             for c, s in zip(m.tolist(), r.tolist(), strict=True)]  # radius 0, or wholly behind: unseen
    rows = z.rows(boxes)
    if rows is None:
        return
    # Per row: the ray (x, y, 1) meets the sphere where |m x d|^2 <= r^2 |d|^2, a quadratic in x.
    y, (mx, my, mz), radius = rows.y, m[rows.prim].T, r[rows.prim]
    r2, mm = radius * radius, mx * mx + my * my + mz * mz
    alpha = r2 - my * my - mz * mz
    # (alpha clearly negative: the roots' rounding errors are far below a pixel)
    pixels = z.pixels(rows, alpha, 2 * mx * (mz + my * y), (r2 - mx * mx) * (1 + y * y) - (my - mz * y) ** 2,
                      alpha < -1e-3 * (mm + r2))
    if pixels is None:
        return
    row, xs, flat = pixels
    behind = bool(np.any(mz - radius <= MIN_DEPTH))  # one reaches behind the camera: see its far side
    depth, far = _sphere_roots(xs, xs * xs + (1 + y * y)[row], mx[row], (my * y + mz)[row], (mm - r2)[row],
                               far=behind)
    if behind:  # where the near side is behind the camera (inside the sphere, or it is cut by its plane)
        inside = ~(depth > MIN_DEPTH)
        depth = np.where(inside, np.where(far > MIN_DEPTH, far, np.nan), depth)
    lit = None
    if z.shading != "flat":
        # n . l with n = (t d - m) / r, turned round where the inside is seen.
        lx, ly, lz = z.light
        lit = (depth * (lx * xs + (ly * y + lz)[row]) - (lx * mx + ly * my + lz * mz)[row]) / radius[row]
        if behind:
            lit = np.where(inside, -lit, lit)
    z.keep(flat, depth, lit, ids[rows.prim][row])


def draw_capsules(z, ids, a, b, r):
    """Ray-cast capsules ``ids`` (ends ``a != b`` (n, 3) in the camera's frame, radii ``r``)."""
    seen = (r > 0) & (np.maximum(a[:, 2], b[:, 2]) + r > MIN_DEPTH)
    front = np.minimum(a[:, 2], b[:, 2]) - r > MIN_DEPTH  # wholly in front: the camera is outside
    for group, in_front in ((seen & front, True), (seen & ~front, False)):
        if group.any():
            _capsule_batch(z, ids[group], a[group], b[group], r[group], in_front)


def _capsule_batch(z, ids, a, b, r, in_front):
    """Ray-cast capsules all wholly ``in_front`` of the camera, or all not."""
    boxes = []
    for p, q, s in zip(a.tolist(), b.tolist(), r.tolist(), strict=True):
        ep, eq = _sphere_extent(z, p, s), _sphere_extent(z, q, s)
        # The capsule is the hull of its end spheres; in front of the camera, so is its picture.
        boxes.append(z.box(None if ep is None or eq is None else (
            min(ep[0], eq[0]), max(ep[1], eq[1]), min(ep[2], eq[2]), max(ep[3], eq[3]))))
    rows = z.rows(boxes)
    if rows is None:
        return
    length = np.linalg.norm(b - a, axis=1)
    u = (b - a) / length[:, None]
    g = np.cross(a, u)  # the axis's moment
    c = _Capsules(a[rows.prim], b[rows.prim], u[rows.prim], g[rows.prim], length[rows.prim], r[rows.prim],
                  rows.y)
    # Per row: the ray (x, y, 1) comes within r of the axis where (d.g)^2 <= r^2 |d x u|^2, a quadratic
    # in x. Every ray that meets the capsule does.
    (ux, uy, uz), (gx, gy, gz), y, r2 = c.u.T, c.g.T, c.y, c.r ** 2
    moment = gy * y + gz
    alpha = r2 * (uy * uy + uz * uz) - gx * gx
    pixels = z.pixels(rows, alpha, -2 * r2 * ux * (uz + uy * y) - 2 * gx * moment,
                      r2 * ((y * uz - uy) ** 2 + ux * ux * (1 + y * y)) - moment * moment,
                      alpha < -1e-3 * (r2 + gx * gx + gy * gy + gz * gz))
    if pixels is None:
        return
    row, xs, flat = pixels
    dd = xs * xs + (1 + y * y)[row]
    du = ux[row] * xs + (uy * y + uz)[row]
    depth = (_capsule_in_front if in_front else _capsule_anywhere)(c, row, xs, dd, du)
    lit = None
    if z.shading != "flat":
        # n . l with n = (t d - a - w u) / r, from the nearest point of the segment (w along it) to the hit.
        (ax, ay, az), (lx, ly, lz) = c.a.T, z.light
        w = np.minimum(np.maximum(depth * du - (ax * ux + ay * uy + az * uz)[row], 0.0), c.length[row])
        lit = (depth * (lx * xs + (ly * y + lz)[row]) - (lx * ax + ly * ay + lz * az)[row]
               - w * (lx * ux + ly * uy + lz * uz)[row]) / c.r[row]
        if not in_front:  # where n . d > 0 the inside is seen: turn n round
            away = depth * dd - (ax[row] * xs + (ay * y + az)[row]) - w * du > 0
            lit = np.where(away, -lit, lit)
    z.keep(flat, depth, lit, ids[rows.prim][row])


class _Capsules(NamedTuple):
    """Capsules' ends, axis, moment ``a x u``, length and radius, one per row of :class:`_Rows`."""

    a: NDArray[np.float64]
    b: NDArray[np.float64]
    u: NDArray[np.float64]
    g: NDArray[np.float64]
    length: NDArray[np.float64]
    r: NDArray[np.float64]
    y: NDArray[np.float64]

    def cylinder(self, row, xs, dd, du):
        """The depths where the rays enter and leave the infinite cylinder about the axis; NaN: miss.

        With ``d_p`` and ``a_p`` the ray and ``a`` across the axis, ``|t d_p - a_p|^2 = r^2``:
        ``t = (d.a_p -+ sqrt(|d x u|^2 r^2 - (d.g)^2)) / |d x u|^2``.
        """
        (gx, gy, gz), y = self.g.T, self.y
        a_p = self.a - np.sum(self.a * self.u, axis=1)[:, None] * self.u
        # |d x u|^2 = |d|^2 - (d.u)^2 loses digits only for rays nearly along the axis, and those
        # meet the side between the ends only on capsules far longer than r over their angle.
        across = dd - du * du
        e = gx[row] * xs + (gy * y + gz)[row]
        s = np.sqrt(across * (self.r ** 2)[row] - e * e)
        d_a = a_p[:, 0][row] * xs + (a_p[:, 1] * y + a_p[:, 2])[row]
        return (d_a - s) / across, (d_a + s) / across

    def cap(self, end, row, xs, dd):
        """The depths where the rays enter and leave the sphere at ``end`` (per row); NaN: miss."""
        mx, my, mz = end.T
        return _sphere_roots(xs, dd, mx[row], (my * self.y + mz)[row],
                             (mx * mx + my * my + mz * mz - self.r ** 2)[row])

    def along(self, row, depth, du):
        """How far along the axis from ``a`` the hits at ``depth`` lie."""
        return depth * du - np.sum(self.a * self.u, axis=1)[row]


def _capsule_in_front(c, row, xs, dd, du):
    """The nearest hits on capsules wholly in front of the camera (so the camera is outside them).

    The ray's entry into the infinite cylinder is the hit where it lies between the ends; before
    a's end the ray can only meet a's cap first, beyond b's end b's (Quilez's capsule intersection).
    """
    depth = c.cylinder(row, xs, dd, du)[0]
    w = c.along(row, depth, du)
    caps = np.flatnonzero(~((w >= 0) & (w <= c.length[row])))
    if caps.size:
        rows, w, du = row[caps], w[caps], du[caps]
        # No entry (NaN: a miss, or a ray along the axis): the end the ray reaches first.
        end = np.where(np.where(np.isfinite(w), w > c.length[rows], du < 0)[:, None], c.b[rows], c.a[rows])
        mx, my, mz = end.T
        y = c.y[rows]
        depth[caps] = _sphere_roots(xs[caps], dd[caps], mx, my * y + mz,
                                    mx * mx + my * my + mz * mz - c.r[rows] ** 2, far=False)[0]
    return depth


def _capsule_anywhere(c, row, xs, dd, du):
    """The nearest hits in front of the camera on capsules that reach behind it, or hold it.

    Every root of the cylinder and the two end spheres, each kept where it lies on the capsule's
    surface (the cylinder between the ends, a sphere beyond its own end); the nearest in front.
    """
    length = c.length[row]
    slack = 1e-9 * (length + c.r[row])  # where the cylinder meets a cap, both may claim a hit
    found = []
    for t in c.cylinder(row, xs, dd, du):
        w = c.along(row, t, du)
        found.append(np.where((w >= -slack) & (w <= length + slack), t, np.nan))
    for end, beyond_a in ((c.a, True), (c.b, False)):
        for t in c.cap(end, row, xs, dd):
            w = c.along(row, t, du)
            found.append(np.where(w <= slack if beyond_a else w >= length - slack, t, np.nan))
    roots = np.stack(found)
    depth = np.min(np.where(roots > MIN_DEPTH, roots, np.inf), axis=0)
    return np.where(np.isinf(depth), np.nan, depth)
