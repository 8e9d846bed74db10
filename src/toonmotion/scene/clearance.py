"""Where a scene element may start: the proxy's limbs as capsules ``(a, b, radius)`` and whether
points keep clear of them (an element that starts inside a volume is flung out, section 3.5).

The builders (:mod:`toonmotion.scene.build`, :mod:`toonmotion.scene.cloth`) try places in turn
and take the first that these tests pass.
"""

from __future__ import annotations

import numpy as np

from toonmotion.scene.elements import BALLOON_RADIUS, STRING_LENGTH


def across_way(way, axis):
    """A unit vector across ``way`` facing the camera's ``axis`` as far as it can."""
    c = np.cross(way, axis)
    if np.linalg.norm(c) < 1e-6:
        c = np.cross(way, [0.0, 1.0, 0.0]) if abs(way[1]) < 0.9 else np.cross(way, [1.0, 0.0, 0.0])
    return c / np.linalg.norm(c)


def marker_reach(proxy, marker, radii):
    """The largest radius of any limb end at ``marker`` over the clip (its joint sphere's)."""
    L = np.asarray(proxy.limbs)
    ends = [radii[:, k, e] for k in range(len(L)) for e in (0, 1) if L[k, e] == marker]
    return float(max((np.max(r) for r in ends), default=0.0))


def relative_volumes(proxy, marker, radii):
    """Every frame's limb volumes ``(A, B, r)`` seen from ``marker`` (its point at the origin),
    stacked: where a point that moves with the marker must not be."""
    P = proxy.points - proxy.points[:, marker:marker + 1]
    L = np.asarray(proxy.limbs)
    R = np.asarray(radii).max(axis=2)
    return [(P[:, L[:, 0]].reshape(-1, 3), P[:, L[:, 1]].reshape(-1, 3), R.reshape(-1))]


def stack_volumes(volumes):
    if not volumes:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    a, b, r = zip(*volumes, strict=True)
    return np.array(a), np.array(b), np.array(r)


def gap_ok(points, radius, volumes, gap=1e-3):
    """Whether balls of ``radius`` at ``points`` ``(..., 3)`` touch none of the capsules in
    ``volumes`` (a list of stacked ``(A, B, r)``), vectorised."""
    q = np.asarray(points, dtype=float).reshape(-1, 3)
    for A, B, r in volumes:
        if len(A) == 0:
            continue
        AB = B - A
        den = np.maximum((AB * AB).sum(-1), 1e-300)
        s = np.clip(((q[:, None] - A) * AB).sum(-1) / den, 0.0, 1.0)
        d = np.linalg.norm(q[:, None] - (A + s[..., None] * AB), axis=-1)
        if (d < r + radius + gap).any():
            return False
    return True


def directions(P, marker):
    """Ways a chain may hang from a marker, best first: down, then out sideways away from the
    figure's middle, then the other horizontal ways and up."""
    away = P[marker] - P.mean(axis=0)
    away[1] = 0.0
    n = np.linalg.norm(away)
    away = away / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])
    side = np.array([-away[2], 0.0, away[0]])
    return [np.array([0.0, -1.0, 0.0]), away, side, -side, -away, np.array([0.0, 1.0, 0.0])]


def clear(points, radius, volumes, gap=1e-3):
    """Whether balls of ``radius`` at ``points`` touch none of ``volumes`` ``(a, b, r)``."""
    for q in points:
        for a, b, r in volumes:
            if np.linalg.norm(q - closest_on_segment(q, a, b)) < r + radius + gap:
                return False
    return True


def first_frame_volumes(proxy, radii):
    """Frame 0's capsules ``(a, b, radius)``, one per limb at its larger radius."""
    P = proxy.points[0]
    return [(P[p], P[c], float(radii[0, k].max())) for k, (p, c) in enumerate(proxy.limbs)]


def overlap(c, r, capsules, balls, gap=1e-3):
    """A horizontal move that takes the ball at ``c`` out of the first thing it overlaps, or None."""
    for a, b, radius in capsules:
        q = closest_on_segment(c, a, b)
        d = c - q
        depth = radius + r + gap - np.linalg.norm(d)
        if depth > 0:
            return horizontal(d) * depth
    for o, ro in balls:
        d = c - o
        depth = ro + r + gap - np.linalg.norm(d)
        if depth > 0:
            return horizontal(d) * depth
    return None


def horizontal(d):
    h = np.array([d[0], 0.0, d[2]])
    n = np.linalg.norm(h)
    return h / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])


def closest_on_segment(p, a, b):
    ab = b - a
    denominator = float(ab @ ab)
    s = 0.0 if denominator == 0 else float(np.clip((p - a) @ ab / denominator, 0, 1))
    return a + s * ab


def balloon_way(proxy, marker, balloon, volumes, height):
    """Which way a balloon's string starts from its marker: straight up, unless that starts the
    balloon inside a limb's volume on the first frame (a balloon held at the chest, under the
    head), which flings it out and can blow the simulation up; then the first that starts it
    clear of leaning out away from the figure's middle, to either side or back, at 45 degrees,
    then lower, then level (its lift then carries it up on its own). Up when none does."""
    radius = balloon.radius or BALLOON_RADIUS * height
    length = balloon.string_length or STRING_LENGTH * height
    up = np.array([0.0, 1.0, 0.0])
    outs = directions(proxy.points[0], marker)[1:5]
    for way in [up] + [rise * up + w for rise in (1.0, 0.5, 0.0) for w in outs]:
        way = way / np.linalg.norm(way)
        if clear([proxy.points[0][marker] + way * (length + radius)], radius, volumes):
            return way
    return up
