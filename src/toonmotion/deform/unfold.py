"""Mend triangles stage two leaves inverted: widen the joint area round them, then untangle.

Stage two's rigid edge term keeps a joint triangle from flipping on its own, but fixed vertices
on both sides of a sharply bent joint can leave it no room: the thesis's joint band is too
narrow there (its future work, 7.2 item 4, asks for more freedom at joints). Two remedies, used
in turn by :meth:`~toonmotion.deform.deformer.Deformer.deform`:

* :func:`rings_round`: the vertices within a few rings of triangles round the folded ones, to
  add to the joint area and solve again;
* :func:`untangle`: where a triangle is still inverted after that (an outline sliver pinched in
  the crease of a bend, which the outline's curvature term holds folded), each of its movable
  corners is tried at a few places (the mean of its neighbours, its mirror image in the opposite
  edge, half-way from that edge to the mirror image) and moved to the one that leaves the
  smallest of its triangles largest, when that is larger than now; passes repeat while they
  mend something. A triangle still inverted (inside a crowded bend, where every single move
  folds a neighbour) has a patch of a few rings round it laid out again by Tutte's method.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from toonmotion.geometry.polygon import triangle_areas

# untangle's defaults (DeformSettings.untangle_passes and untangle_rings): at most this many
# passes, and rings round a triangle in its last resort.
PASSES = 10
PATCH_RINGS = 4


def rings_round(F: NDArray[np.int_], folded: NDArray[np.bool_], n: int, rings: int = 2
                ) -> NDArray[np.bool_]:
    """Vertices of the ``folded`` triangles and of ``rings`` rings of triangles round them, ``(n,)``."""
    near = np.zeros(n, dtype=bool)
    near[F[folded].ravel()] = True
    for _ in range(rings):
        near[F[near[F].any(axis=1)].ravel()] = True
    return near


def topology(F: NDArray[np.int_], n: int) -> tuple[list[NDArray[np.intp]], list[NDArray[np.int_]]]:
    """``(incident, neighbours)``: each vertex's triangles and its neighbours along mesh edges,
    as lists of index arrays, for :func:`untangle` (build once per mesh)."""
    F = np.asarray(F)
    return _incident(F, n), _neighbours(F, n)


def untangle(U: NDArray[np.float64], F: NDArray[np.int_], movable: NDArray[np.bool_],
             mesh_topology: tuple[list[NDArray[np.intp]], list[NDArray[np.int_]]] | None = None, *,
             passes: int = PASSES, patch_rings: int = PATCH_RINGS) -> NDArray[np.float64]:
    """``U`` with movable corners of inverted triangles moved so fewer (usually none) are inverted.

    Parameters
    ----------
    U : (n, 2) float
        Vertices.
    F : (m, 3) int
        Triangles, counter-clockwise on screen at rest (positive :func:`triangle_areas`).
    movable : (n,) bool
        Vertices that may move (stage two's free vertices).
    mesh_topology : tuple, optional
        :func:`topology` of ``F``, when already built.
    passes : int
        Passes over the inverted triangles at most (0: none; the last resort still runs).
    patch_rings : int
        The largest patch the last resort lays out again, in rings round a triangle (0: none).

    Returns
    -------
    (n, 2) float
        A new array; vertices that are not corners of inverted triangles are unchanged.

    Examples
    --------
    A square of two triangles with one corner pushed across the diagonal:

    >>> U = np.array([[0.0, 0.0], [0.0, 2.0], [2.0, 2.0], [0.5, 1.5]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> mended = untangle(U, F, np.array([False, False, False, True]))
    >>> bool((triangle_areas(U, F) <= 0).any()), bool((triangle_areas(mended, F) > 0).all())
    (True, True)
    """
    U = np.array(U, dtype=float)
    F = np.asarray(F)
    incident, neighbours = mesh_topology if mesh_topology is not None else topology(F, len(U))
    reachable = np.flatnonzero(np.asarray(movable)[F].any(axis=1))  # a pass can move no others
    for _ in range(passes):
        folded = reachable[triangle_areas(U, F[reachable]) <= 0]
        if len(folded) == 0:
            break
        mended = False
        for t in folded:
            if _area(U, F[t]) > 0:
                continue  # mended by a move earlier in this pass
            for k in range(3):
                v = F[t, k]
                if not movable[v]:
                    continue
                a, b = U[F[t, (k + 1) % 3]], U[F[t, (k + 2) % 3]]
                mirror = _mirror(U[v], a, b)
                middle = 0.5 * (a + b)
                halfway = middle + 0.5 * (mirror - middle)
                candidates = np.array([U[neighbours[v]].mean(axis=0), mirror, halfway])
                scores = _smallest_areas(U, F[incident[v]], v, candidates)
                best = _first_best(scores)
                if best > 0:
                    U[v] = candidates[best - 1]
                    mended = True
                    if scores[best] > 0:
                        break
        if not mended:
            break
    for t in np.flatnonzero(triangle_areas(U, F) <= 0):
        if triangle_areas(U, F[t:t + 1])[0] <= 0:
            U = _tutte_patch(U, F, t, movable, incident, neighbours, patch_rings)
    return U


def _tutte_patch(U, F, t, movable, incident, neighbours, patch_rings):
    """``U`` with a patch round triangle ``t`` laid out again by Tutte's method (each inner vertex
    at the mean of its neighbours, the patch's edge held), for the smallest patch of up to
     ``patch_rings`` rings that leaves no triangle of it inverted; ``U`` itself if none does.
    With a convex edge Tutte's layout is never folded, and a small patch's edge nearly is."""
    folded = np.zeros(len(F), dtype=bool)
    folded[t] = True
    for rings in range(1, patch_rings + 1):
        patch = rings_round(F, folded, len(U), rings)
        # Inner vertices: no triangle outside the patch touches them; the rest of it is its edge.
        edge = np.zeros(len(U), dtype=bool)
        edge[F[~patch[F].all(axis=1)].ravel()] = True
        inner = np.flatnonzero(patch & movable & ~edge)
        if len(inner) == 0:
            continue
        where = np.full(len(U), -1)
        where[inner] = np.arange(len(inner))
        counts = np.array([len(neighbours[v]) for v in inner])
        row = np.repeat(np.arange(len(inner)), counts)
        other = np.concatenate([neighbours[v] for v in inner])
        inside = where[other] >= 0
        L = np.zeros((len(inner), len(inner)))
        L[np.arange(len(inner)), np.arange(len(inner))] = counts
        np.add.at(L, (row[inside], where[other[inside]]), -1)
        b = np.zeros((len(inner), 2))
        np.add.at(b, row[~inside], U[other[~inside]])  # in order, as a loop would add them
        trial = U.copy()
        trial[inner] = np.linalg.solve(L, b)
        around = F[np.unique(np.concatenate([incident[v] for v in inner]))]
        if (triangle_areas(trial, around) > 0).all():
            return trial
    return U


def _area(U, corners):
    """One triangle's signed area, as :func:`triangle_areas` computes it."""
    a, b, c = U[corners[0]], U[corners[1]], U[corners[2]]
    return -0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))


def _smallest_areas(U, around, v, candidates):
    """The smallest signed area of the triangles ``around`` (``(k, 3)``, all with corner ``v``)
    with ``v`` where it is and at each of ``candidates`` (``(c, 2)``): ``(1 + c,)``, computed as
    :func:`triangle_areas` does."""
    P = np.broadcast_to(U[around], (len(candidates) + 1, *around.shape, 2)).copy()  # (1 + c, k, 3, 2)
    at = around == v
    P[1:, at] = candidates[:, None, :]
    ab, ac = P[:, :, 1] - P[:, :, 0], P[:, :, 2] - P[:, :, 0]
    return (-0.5 * (ab[..., 0] * ac[..., 1] - ab[..., 1] * ac[..., 0])).min(axis=1)


def _first_best(scores):
    """Which of ``scores[1:]`` to take (1-based), 0 for none: the first to beat every score before
    it, ``scores[0]`` included, the way a scan keeping the best so far would take it."""
    best, best_score = 0, scores[0]
    for i in range(1, len(scores)):
        if scores[i] > best_score:
            best, best_score = i, scores[i]
    return best


def _mirror(p, a, b):
    """``p`` reflected in the line through ``a`` and ``b``."""
    d = b - a
    foot = a + d * (np.dot(p - a, d) / max(np.dot(d, d), 1e-300))
    return 2 * foot - p


def _incident(F, n):
    """Triangles round each vertex, as a list of index arrays."""
    order = np.argsort(F.ravel(), kind="stable")
    counts = np.bincount(F.ravel(), minlength=n)
    return np.split(order // 3, np.cumsum(counts)[:-1])


def _neighbours(F, n):
    """Each vertex's neighbours along mesh edges, as a list of index arrays."""
    edges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    edges = np.unique(np.concatenate([edges, edges[:, ::-1]]), axis=0)
    counts = np.bincount(edges[:, 0], minlength=n)
    return np.split(edges[:, 1], np.cumsum(counts)[:-1])
