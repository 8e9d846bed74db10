"""The curve skeleton of a mask as a graph: end points, junctions and the branches between.

The skeleton pixels come from :func:`~toonmotion.shape.thinning.hilditch_thin`. A pixel with
one skeleton neighbour is an end point; 8-connected clusters of pixels with three or more
neighbours are junctions; branches are the pixel paths between them. A closed loop with no
junction on it gets one node of kind ``"loop"``; a shape that thins to one pixel, a node of
kind ``"point"``.

Short spurs (branches ending in an end point that barely leave the junction's inscribed
circle, the usual artefacts of bumps in an outline) are pruned, repeatedly, until none is left.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage as ndi

from toonmotion.errors import SkeletonError
from toonmotion.geometry.arrays import frozen_array, frozen_arrays
from toonmotion.geometry.segments import resample_by_arc_length
from toonmotion.shape.thinning import hilditch_thin

NODE_KINDS = ("end", "junction", "loop", "point")

_SQUARE = np.ones((3, 3), dtype=bool)
_STEPS = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


@dataclass(frozen=True, eq=False)
class CurveSkeleton:
    """A curve skeleton graph.

    Attributes
    ----------
    nodes : (k, 2) float
        Node positions, (x, y) pixels, y down.
    kinds : tuple of str
        Kind of each node, one of :data:`NODE_KINDS`.
    radius : (k,) float
        Distance from each node to the outline (the inscribed circle's radius).
    branches : (b, 2) int
        The two nodes each branch joins (equal for a loop).
    paths : tuple of (p, 2) float
        Each branch's pixel path from its first node to its second, ends included.

    Construction copies the arrays (read-only) and raises :class:`SkeletonError` unless the
    shapes agree, every kind is one of :data:`NODE_KINDS` and every branch names existing nodes.
    """

    nodes: NDArray[np.float64]
    kinds: tuple[str, ...]
    radius: NDArray[np.float64]
    branches: NDArray[np.int64]
    paths: tuple[NDArray[np.float64], ...]

    def __post_init__(self) -> None:
        error = SkeletonError
        nodes = frozen_array(self.nodes, dtype=np.float64, shape=(None, 2), name="a curve skeleton's nodes",
                             error=error, coordinates=True)
        k = len(nodes)
        radius = frozen_array(self.radius, dtype=np.float64, shape=(k,), name="a curve skeleton's radius",
                              error=error, coordinates=True)
        branches = frozen_array(self.branches, dtype=np.int64, shape=(None, 2),
                                name="a curve skeleton's branches", error=error)
        paths = frozen_arrays(self.paths, dtype=np.float64, shape=(None, 2), name="a curve skeleton's paths",
                              error=error, coordinates=True)
        kinds = tuple(self.kinds)
        if len(kinds) != k or not all(kind in NODE_KINDS for kind in kinds):
            raise error(f"a curve skeleton needs one kind per node ({k}), each of {', '.join(NODE_KINDS)}")
        if len(paths) != len(branches):
            raise error(f"a curve skeleton has {len(branches)} branches but {len(paths)} paths")
        if branches.size and (branches.min() < 0 or branches.max() >= k):
            raise error("a curve-skeleton branch names a node that does not exist")
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "radius", radius)
        object.__setattr__(self, "branches", branches)
        object.__setattr__(self, "paths", paths)

    @property
    def lengths(self) -> NDArray[np.float64]:
        """Length of each branch in pixels, ``(b,)``."""
        return np.array([_path_length(p) for p in self.paths])


def curve_skeleton(mask: ArrayLike, *, prune: float = 0.5, min_spur: float = 3.0) -> CurveSkeleton:
    """Thin a mask and describe its skeleton as a graph.

    Parameters
    ----------
    mask : (h, w) bool
    prune : float
        A branch from a junction to an end point is a spur, and removed, when it reaches less
        than ``prune`` times the junction's radius (plus ``min_spur`` pixels) beyond the
        junction's inscribed circle. With 0, only spurs shorter than ``min_spur`` go; with
        both 0, every branch is kept.
    min_spur : float
        Spurs shorter than this many pixels beyond the inscribed circle are always removed.

    Returns
    -------
    CurveSkeleton

    Examples
    --------
    >>> plus = np.zeros((41, 41), bool); plus[18:23, 2:39] = True; plus[2:39, 18:23] = True
    >>> cs = curve_skeleton(plus)
    >>> sorted(cs.kinds), len(cs.paths)
    (['end', 'end', 'end', 'end', 'junction'], 4)
    """
    mask = np.asarray(mask, dtype=bool)
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return _empty()
    # Work on the figure's bounding box (plus a background margin), then shift back.
    r0, c0 = max(rows.min() - 1, 0), max(cols.min() - 1, 0)
    window = mask[r0 : rows.max() + 2, c0 : cols.max() + 2]
    distance = ndi.distance_transform_edt(window)
    pixels = hilditch_thin(window)
    while True:
        graph, pixel_paths, junction_pixels = _trace(pixels, distance)
        spurs = _spurs(graph, prune, min_spur)
        if not spurs:
            return _shifted(graph, c0, r0)
        for b in spurs:
            rc = pixel_paths[b]
            pixels[rc[:, 0], rc[:, 1]] = False
        pixels |= junction_pixels
        pixels = hilditch_thin(pixels)


def _empty():
    return CurveSkeleton(
        nodes=np.zeros((0, 2)),
        kinds=(),
        radius=np.zeros(0),
        branches=np.zeros((0, 2), dtype=np.int64),
        paths=(),
    )


def _shifted(graph, dx, dy):
    offset = np.array([dx, dy], dtype=float)
    return CurveSkeleton(
        nodes=graph.nodes + offset,
        kinds=graph.kinds,
        radius=graph.radius,
        branches=graph.branches,
        paths=tuple(p + offset for p in graph.paths),
    )


def joint_suggestions(
    skeleton: CurveSkeleton, *, max_bone: float | None = None
) -> tuple[NDArray[np.float64], tuple[str, ...]]:
    """Where joints could go: end points, junctions, and evenly along long branches.

    Parameters
    ----------
    skeleton : CurveSkeleton
    max_bone : float, optional
        Branches longer than this get joints along them, splitting them into equal pieces no
        longer than ``max_bone``. Default: a fifth of the skeleton's bounding-box diagonal.

    Returns
    -------
    points : (k, 2) float
    kinds : tuple of str
        ``"end"``, ``"junction"``, ``"loop"``, ``"point"`` or ``"along"``.
    """
    points = [skeleton.nodes]
    kinds = list(skeleton.kinds)
    for path in skeleton.paths:
        for p in _along(path, max_bone if max_bone else _default_bone(skeleton)):
            points.append(p[None])
            kinds.append("along")
    return np.concatenate(points), tuple(kinds)


def split_points(path: NDArray[np.float64], max_bone: float) -> NDArray[np.float64]:
    """Points that split a path into equal pieces no longer than ``max_bone``, ``(k, 2)``."""
    return np.array(_along(path, max_bone)).reshape(-1, 2)


def default_bone_length(skeleton: CurveSkeleton) -> float:
    """A fifth of the diagonal of the skeleton's bounding box: the default longest bone."""
    return _default_bone(skeleton)


def _default_bone(skeleton):
    every = np.concatenate([skeleton.nodes, *skeleton.paths]) if skeleton.paths else skeleton.nodes
    return max(1.0, float(np.linalg.norm(every.max(axis=0) - every.min(axis=0))) / 5.0)


def _along(path, max_bone):
    length = _path_length(path)
    pieces = int(np.ceil(length / max_bone - 1e-9))
    if pieces < 2:
        return []
    return list(resample_by_arc_length(path, np.arange(1, pieces) * length / pieces))


def _path_length(path):
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def _spurs(graph, prune, min_spur):
    if len(graph.paths) < 2 or prune <= 0 and min_spur <= 0:
        return []
    degree = np.bincount(graph.branches.ravel(), minlength=len(graph.nodes))
    lengths = graph.lengths
    spurs = []
    for b, (i, j) in enumerate(graph.branches):
        kinds = (graph.kinds[i], graph.kinds[j])
        if set(kinds) != {"end", "junction"}:
            continue
        junction = i if kinds[0] == "junction" else j
        if degree[junction] < 3:
            continue
        beyond = lengths[b] - graph.radius[junction]
        if beyond < prune * graph.radius[junction] + min_spur:
            spurs.append(b)
    # Never prune every branch of a junction: keep each junction's longest one.
    by_junction = {}
    for b in spurs:
        i, j = graph.branches[b]
        junction = i if graph.kinds[i] == "junction" else j
        by_junction.setdefault(junction, []).append(b)
    keep = set()
    for junction, bs in by_junction.items():
        if len(bs) >= degree[junction] - 1:
            keep.add(max(bs, key=lambda b: lengths[b]))
    return [b for b in spurs if b not in keep]


def _trace(pixels, distance):
    """Turn skeleton pixels into a graph; also return the branches' (row, col) pixel paths
    and the junction pixels."""
    h, w = pixels.shape
    padded = np.pad(pixels, 1)
    width = w + 2
    at = np.flatnonzero(padded)  # skeleton pixels as flat indices into `padded`
    slot = np.full(padded.size, -1, dtype=np.int64)
    slot[at] = np.arange(len(at))
    offsets = np.array([dr * width + dc for dr, dc in _STEPS])
    neighbour = slot[at[:, None] + offsets[None, :]]  # (p, 8) pixel numbers, -1 for none
    degree = np.sum(neighbour >= 0, axis=1)
    rows, cols = at // width - 1, at % width - 1

    is_junction = np.zeros(pixels.shape, dtype=bool)
    is_junction[rows[degree >= 3], cols[degree >= 3]] = True
    junction_labels, _ = ndi.label(is_junction, structure=_SQUARE)

    node_of = np.full(len(at), -1, dtype=np.int64)
    nodes, kinds = [], []
    cluster = junction_labels[rows, cols]
    for label in range(1, cluster.max() + 1 if len(at) else 1):
        members = np.flatnonzero(cluster == label)
        node_of[members] = len(nodes)
        nodes.append((cols[members].mean(), rows[members].mean()))
        kinds.append("junction")
    for kind, where in (("end", degree == 1), ("point", degree == 0)):
        for k in np.flatnonzero(where):
            node_of[k] = len(nodes)
            nodes.append((float(cols[k]), float(rows[k])))
            kinds.append(kind)

    neighbours = [list(row[row >= 0]) for row in neighbour]
    visited = np.zeros(len(at), dtype=bool)
    branches, paths = [], []

    def walk(start, first):
        """Follow degree-2 pixels from ``first``, stepping off node pixel ``start``."""
        path, prev, k = [start], start, first
        while node_of[k] < 0 and not visited[k]:
            visited[k] = True
            path.append(k)
            step = [q for q in neighbours[k] if q != prev and q not in path[-3:]]
            if not step:
                break
            # Prefer a node pixel when one is adjacent, so a branch ends where it should.
            prev, k = k, next((q for q in step if node_of[q] >= 0), step[0])
        if node_of[k] >= 0:
            path.append(k)
            return node_of[k], path
        return None, path

    seen_direct = set()
    for k in np.flatnonzero(node_of >= 0):
        start = node_of[k]
        for q in neighbours[k]:
            end = node_of[q]
            if end == start:
                continue
            if end >= 0:  # two node pixels side by side: a branch of length ~1
                key = (min(start, end), max(start, end))
                if key not in seen_direct:
                    seen_direct.add(key)
                    branches.append(key)
                    paths.append([k, q])
                continue
            if visited[q]:
                continue
            end, path = walk(k, q)
            if end is not None:
                branches.append((start, end))
                paths.append(path)

    # Loops with no node on them: give each one a node of kind "loop".
    for k in range(len(at)):
        if visited[k] or node_of[k] >= 0:
            continue
        node = len(nodes)
        nodes.append((float(cols[k]), float(rows[k])))
        kinds.append("loop")
        node_of[k] = node
        if neighbours[k]:
            _, path = walk(k, neighbours[k][0])
            if path[-1] != k:  # the walk ends on the loop's node when it closes the loop
                path.append(k)
            branches.append((node, node))
            paths.append(path)

    nodes = np.array(nodes, dtype=float).reshape(-1, 2)
    pixel_paths = [np.stack([rows[path], cols[path]], axis=1) for path in paths]
    xy_paths = []
    for (a, b), rc in zip(branches, pixel_paths, strict=True):
        xy = rc[:, ::-1].astype(float)
        xy[0], xy[-1] = nodes[a], nodes[b]  # junction paths end at the cluster's centre
        xy_paths.append(xy)
    r = np.clip(np.rint(nodes[:, 1]).astype(int), 0, h - 1)
    c = np.clip(np.rint(nodes[:, 0]).astype(int), 0, w - 1)
    graph = CurveSkeleton(
        nodes=nodes,
        kinds=tuple(kinds),
        radius=distance[r, c].astype(float),
        branches=np.array(branches, dtype=np.int64).reshape(-1, 2),
        paths=tuple(xy_paths),
    )
    return graph, pixel_paths, is_junction
