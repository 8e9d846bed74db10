"""A sketched skeleton's strokes as a graph (thesis 3.3.3): strokes checked, cut at their corners
and where they meet, the pieces joined where they end near one another (:func:`sketch_graph`), and
the graph's connected pieces; :func:`toonmotion.rig.sketch.match_sketch` embeds the skeleton in it."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from toonmotion.errors import SketchError
from toonmotion.geometry.arrays import MAX_COORDINATE

# Simplifying a stroke: tolerance as a fraction of its length, and at least this many pixels.
CORNER_TOLERANCE = 0.06

# The most strokes and points a sketch may have.
MAX_STROKES, MAX_POINTS = 200, 20_000


MIN_CORNER_TOLERANCE = 3.0


def sketch_graph(strokes: Sequence[NDArray[np.float64]], *, snap: float
                 ) -> tuple[NDArray[np.float64], list[tuple[int, int]]]:
    """The stick figure of simplified ``strokes``: its joints ``(n, 2)`` and segments (index pairs).

    Examples
    --------
    >>> points, edges = sketch_graph([np.array([(0., 0), (0, 100)]), np.array([(2., 50), (60, 50)])], snap=5)
    >>> points.tolist(), edges
    ([[0.0, 0.0], [0.0, 100.0], [2.0, 50.0], [60.0, 50.0]], [(0, 2), (2, 1), (2, 3)])
    """
    points, edges, _, _ = stroke_graph(strokes, snap=snap)
    return points, edges


def stroke_graph(strokes: Sequence[NDArray[np.float64]], *, snap: float
           ) -> tuple[NDArray[np.float64], list[tuple[int, int]], list[int], list[NDArray[np.float64]]]:
    """:func:`sketch_graph`, the stroke each segment comes from, and the stretch of stroke it
    simplifies (a polyline from its first joint to its second)."""
    points: list[NDArray[np.float64]] = []
    edges: list[tuple[int, int]] = []
    owner: list[int] = []  # the stroke each segment comes from
    trails: list[NDArray[np.float64]] = []
    group: list[int] = []  # union-find over joints: a join never closes a loop

    def root(i: int) -> int:
        while group[i] != i:
            group[i] = group[group[i]]
            i = group[i]
        return i

    def add(xy: NDArray[np.float64], like: int | None = None) -> int:
        points.append(xy)
        group.append(len(group) if like is None else root(like))
        return len(points) - 1

    def join(xy: NDArray[np.float64], barred: int | None) -> int:
        """The joint at ``xy``: the nearest joint within snap, or a split segment, or a new one;
        never one in the piece ``barred`` (the stroke's own, once its first end has joined)."""
        options: list[tuple[float, int, int]] = []  # (distance, joint or -1, segment or -1)
        for i, p in enumerate(points):
            d = float(np.hypot(*(p - xy)))
            if d <= snap and root(i) != barred:
                options.append((d / 2, i, -1))  # a joint is preferred to the inside of a segment
        for e, (a, b) in enumerate(edges):
            d = _onto_segment(xy, points[a], points[b])[1]
            if _splits(xy, points[a], points[b], snap) and root(a) != barred:
                options.append((d, -1, e))
        if not options:
            return add(xy)
        _, joint, e = min(options)
        if joint >= 0:
            return joint
        split = add(xy, like=edges[e][0])
        divide(e, split)
        return split

    def divide(e: int, joint: int) -> None:
        """Split segment ``e`` at ``joint``, and its stretch of stroke at the nearest point."""
        (a, b), trail = edges[e], trails[e]
        gaps = [_onto_segment(points[joint], p, q)[1] for p, q in zip(trail, trail[1:], strict=False)]
        k = int(np.argmin(gaps))
        edges[e:e + 1] = [(a, joint), (joint, b)]
        owner[e:e + 1] = [owner[e]] * 2
        trails[e:e + 1] = [np.vstack([trail[:k + 1], points[joint]]),
                           np.vstack([points[joint], trail[k + 1:]])]

    for stroke, line in enumerate(strokes):
        line, corners = _corners(line)
        if len(line) < 2:  # a dot
            continue
        first = join(line[0], None)
        chain = [first] + [add(line[i], like=first) for i in corners[1:-1]]
        last = join(line[-1], root(first))
        chain.append(last)
        pairs = zip(chain, chain[1:], strict=False)
        for (a, b), (i, j) in zip(pairs, zip(corners, corners[1:], strict=False), strict=True):
            if a != b:
                edges.append((a, b))
                owner.append(stroke)
                trails.append(np.vstack([points[a], line[i + 1:j], points[b]]))
                group[root(a)] = root(b)
    # An earlier stroke's free end may lie on a later stroke: join it there too.
    for i in range(len(points)):
        if sum(i in e for e in edges) != 1:
            continue
        for e, (a, b) in enumerate(edges):
            if i not in (a, b) and _splits(points[i], points[a], points[b], snap) and root(a) != root(i):
                divide(e, i)
                group[root(a)] = root(i)
                break
    if not points:
        raise SketchError("the sketch is empty: draw at least one stroke")
    return np.array(points, dtype=float), edges, owner, trails


def checked_strokes(strokes: Sequence[ArrayLike]) -> list[NDArray[np.float64]]:
    if isinstance(strokes, (str, bytes)) or not isinstance(strokes, Sequence) or not strokes:
        raise SketchError("a sketch is a list of strokes, each a list of [x, y] points")
    if len(strokes) > MAX_STROKES:
        raise SketchError(f"a sketch may have {MAX_STROKES} strokes at most, got {len(strokes)}")
    lines, total = [], 0
    for n, stroke in enumerate(strokes, start=1):
        try:
            line = np.asarray(stroke, dtype=float)
        except (TypeError, ValueError):
            raise SketchError(f"stroke {n} must be a list of [x, y] points") from None
        if line.ndim != 2 or line.shape[1] != 2 or len(line) < 2:
            raise SketchError(f"stroke {n} must be at least 2 [x, y] points")
        if not np.isfinite(line).all():
            raise SketchError(f"stroke {n} has a point that is not a finite number")
        if np.abs(line).max() > MAX_COORDINATE:
            raise SketchError(f"stroke {n} has a point beyond {MAX_COORDINATE:,.0f} px from the origin")
        total += len(line)
        if total > MAX_POINTS:
            raise SketchError(f"a sketch may have {MAX_POINTS:,} points at most")
        lines.append(line)
    return lines


def _corners(line: NDArray[np.float64]) -> tuple[NDArray[np.float64], list[int]]:
    """The stroke without repeated points, and the indices of its corners (first and last kept)."""
    steps = np.hypot(*np.diff(line, axis=0).T)
    line = line[np.concatenate([[True], steps > 1e-9])]
    if len(line) < 2:
        return line, [0]
    tolerance = max(MIN_CORNER_TOLERANCE, CORNER_TOLERANCE * float(steps.sum()))
    kept = shapely.get_coordinates(shapely.simplify(shapely.LineString(line), tolerance))
    corners, at = [], 0
    for xy in kept:  # simplify keeps a subset of the points, in order
        while not np.array_equal(line[at], xy):
            at += 1
        corners.append(at)
    return line, corners


def _splits(xy: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64], snap: float) -> bool:
    """Whether ``xy`` lies within ``snap`` of the inside of segment ``a b``, away from its ends."""
    t, d = _onto_segment(xy, a, b)
    return d <= snap and 0 < t < 1 and min(np.hypot(*(xy - a)), np.hypot(*(xy - b))) > snap


def _onto_segment(xy: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
                  ) -> tuple[float, float]:
    """Where ``xy`` falls along segment ``a b`` (0 at a, 1 at b) and its distance from it."""
    ab = b - a
    span = float(ab @ ab)
    t = float((xy - a) @ ab) / span if span > 0 else 0.0
    nearest = a + min(max(t, 0.0), 1.0) * ab
    return t, float(np.hypot(*(xy - nearest)))


def connected_pieces(count: int, edges: list[tuple[int, int]]) -> list[list[tuple[int, int]]]:
    """The segments of each connected piece, largest piece first."""
    if not edges:
        raise SketchError("the sketch has no segment of any length: draw strokes, not dots")
    rows, cols = zip(*edges, strict=True)
    graph = coo_array((np.ones(len(edges)), (rows, cols)), shape=(count, count))
    _, label = connected_components(graph, directed=False)
    groups: dict[int, list[tuple[int, int]]] = {}
    for a, b in edges:
        groups.setdefault(int(label[a]), []).append((a, b))
    return sorted(groups.values(), key=len, reverse=True)
