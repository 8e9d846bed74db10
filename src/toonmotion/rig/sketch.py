"""Posing by sketching a skeleton (thesis 3.4, 6.2a): strokes matched to the skeleton's bones.

The animator draws strokes over the drawing, or a stick figure beside it. A stroke is one bone,
a chain of bones, or part of a stick figure; :func:`match_sketch` finds which bones and returns
the pose. The thesis does not say how its sketches are paired with bones; the method here is
ours (docs/editor.md, "Sketching a pose"):

1. Each stroke is simplified to straight segments (Douglas-Peucker, tolerance 6% of the
   stroke's length, at least 3 px); its corners are joints.
2. A stroke end within ``snap`` of an earlier stroke's joint, or of the inside of one of its
   segments, joins it there, so strokes build one stick figure; a join that would close a loop
   (a skeleton has none) is not made.
3. Each connected piece of the figure is embedded in the skeleton: sketch joints onto skeleton
   joints, each segment onto a bone, or onto a chain of up to 3 bones through joints with no
   branch (one straight stroke along an arm covers the elbow). Joints joined by a bone of no
   length (a root on a hip) count as one. The embedding of least cost wins: per segment,
   ``1 - cos`` of its turn from the bones it covers in the pose being edited (shared among
   them by length) and 0.05 per extra bone it covers; per bone, 3 ``log(length / rest length)²``;
   per sketch joint, 0.25 (100 for the piece's topmost joint) times its squared distance from its
   joint in the pose being edited over the pose's size squared.
   A piece's points are where its joints go, except that a piece that starts within ``snap``
   of its joint hangs from it (a stroke begun on the shoulder leaves the shoulder put), and a
   piece drawn beside the figure (its box clear of the joints' box by a tenth of the figure's
   size) is scaled to the rest lengths and hung from its topmost joint.
   Pieces are matched largest first, each on joints the earlier ones left.
4. Sketched joints go where the sketch puts them; joints below them that were not sketched are
   carried along rigidly (turned with the sketched bone above them); the others stay.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from toonmotion.errors import SketchError
from toonmotion.rig.pose import Pose, check_pose
from toonmotion.rig.skeleton import Skeleton
from toonmotion.rig.sketch_graph import checked_strokes, connected_pieces, stroke_graph

# A segment may cover a chain of up to this many bones through unbranched joints.
MAX_BONES_PER_SEGMENT = 3
# Cost weights (module docstring).
POSITION_WEIGHT, TOP_WEIGHT = 0.25, 400.0
EXTRA_BONE_COST = 0.05
LENGTH_WEIGHT = 3.0  # a bone drawn 1.5 times its length costs as much as one turned 90 degrees
# Embeddings tried per piece before the sketch is called ambiguous.
MAX_STEPS = 20_000


@dataclass(frozen=True)
class SketchMatch:
    """The pose a sketch gives, and how it was read.

    Attributes
    ----------
    pose : Pose
        Every joint's position.
    bones : tuple of str
        The bones the sketch covered (named after their child joints), in skeleton order.
    elsewhere : bool
        True when some piece of the sketch was drawn away from the figure and hung from its
        topmost joint rather than taken in place.
    """

    pose: Pose
    bones: tuple[str, ...]
    elsewhere: bool


def match_sketch(
    skeleton: Skeleton, pose: Pose, strokes: Sequence[ArrayLike], *, snap: float | None = None
) -> SketchMatch:
    """The pose ``strokes`` sketch for ``skeleton``, starting from ``pose``.

    Parameters
    ----------
    skeleton : Skeleton
    pose : Pose
        The pose being edited; joints the sketch does not reach keep their place in it.
    strokes : sequence of (n, 2) float
        Polylines in drawing pixels, in the order drawn, each at least 2 points.
    snap : float, optional
        How near (pixels) a stroke's end must come to join another stroke; default 4% of the
        sketch's size (its bounding box's diagonal), at least 6 px.

    Returns
    -------
    SketchMatch

    Raises
    ------
    SketchError
        For malformed strokes, a loop, more segments than the skeleton has bones, or a shape
        no part of the skeleton has.

    Examples
    --------
    >>> s = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 10)),
    ...                           ("foot", "knee", (0, 20))])
    >>> found = match_sketch(s, Pose(s.positions), [[(0, 0), (10, 0), (10, 10)]])
    >>> found.bones, found.pose.positions.round(6).tolist()
    (('knee', 'foot'), [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    """
    current = np.asarray(pose.positions, dtype=float)
    lines = checked_strokes(strokes)
    size = _size(current)
    snap = max(6.0, 0.04 * _size(np.concatenate(lines))) if snap is None else float(snap)
    points, edges, owner, trails = stroke_graph(lines, snap=snap)
    tree = _SkeletonTree(skeleton, current)
    if len(edges) > tree.edge_count:
        raise SketchError(f"the sketch has {len(edges)} segments, more than the skeleton's "
                          f"{tree.edge_count} bones: draw fewer strokes, or straighter ones")
    placed = current.copy()
    mapped = np.zeros(len(skeleton), dtype=bool)
    used: set[int] = set()
    covered: set[int] = set()
    elsewhere = False
    pieces = [(points, {e: trails[edges.index(e)] for e in piece})
              for piece in connected_pieces(len(points), edges)]
    while pieces:
        figure, piece = pieces.pop(0)
        found = _embed(tree, figure, piece, used, size, beside=_beside(figure, piece, current), snap=snap)
        if found is None:
            # Strokes that touch by accident (a hand on a hip) join into a shape the skeleton
            # lacks: match that piece's strokes one by one instead.
            apart = sorted({owner[edges.index(e)] for e in piece}) if figure is points else []
            if len(apart) < 2:
                raise SketchError(f"no free part of the skeleton has the shape of a sketched piece of "
                                  f"{len(piece)} segments: draw it as separate strokes, or check its joints")
            for stroke in apart:
                alone, segments, _, stretches = stroke_graph([lines[stroke]], snap=snap)
                if segments:
                    pieces.append((alone, dict(zip(segments, stretches, strict=True))))
            pieces.sort(key=lambda item: len(item[1]), reverse=True)
            continue
        elsewhere |= found.elsewhere
        used |= found.clusters
        covered |= found.bones
        for cluster, xy in found.where.items():
            for joint in tree.members[cluster]:
                placed[joint] = xy
                mapped[joint] = True
    positions = _carry(skeleton, current, placed, mapped)
    bones = tuple(skeleton.names[c] for c in skeleton.bones[:, 1] if c in covered)
    return SketchMatch(pose=check_pose(skeleton, Pose(positions), where="the sketched pose"),
                       bones=bones, elsewhere=elsewhere)


def stroke_chains(skeleton: Skeleton) -> list[list[int]]:
    """The strokes that draw ``skeleton`` as a stick figure: its chains of bones from one
    branching joint or end to the next, as joint indices (joints joined by a bone of no length
    count as one).

    Examples
    --------
    >>> s = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 10)),
    ...                           ("foot", "knee", (0, 20)), ("neck", "hip", (0, -20)),
    ...                           ("other_knee", "hip", (5, 10))])
    >>> [[s.names[j] for j in chain] for chain in stroke_chains(s)]
    [['hip', 'knee', 'foot'], ['hip', 'neck'], ['hip', 'other_knee']]
    """
    tree = _SkeletonTree(skeleton, skeleton.positions)
    out, seen = [], set()
    for c in range(len(tree.members)):
        if len(tree.neighbours[c]) == 2:
            continue
        for n in tree.neighbours[c]:
            path = [c, n]
            while len(tree.neighbours[path[-1]]) == 2:
                path.append(next(x for x in tree.neighbours[path[-1]] if x != path[-2]))
            key = frozenset(frozenset(p) for p in zip(path, path[1:], strict=False))
            if key not in seen:
                seen.add(key)
                out.append([int(tree.members[p][0]) for p in path])
    return out


# --- the skeleton as a tree of joint clusters ----------------------------------------------------


class _SkeletonTree:
    """The skeleton with joints joined by bones of no length merged into clusters."""

    def __init__(self, skeleton: Skeleton, current: NDArray[np.float64]) -> None:
        rest = skeleton.positions
        tiny = max(1.0, 0.01 * _size(rest))
        bones = skeleton.bones
        lengths = np.linalg.norm(rest[bones[:, 1]] - rest[bones[:, 0]], axis=1)
        merged = bones[lengths < tiny]
        k = len(skeleton)
        graph = coo_array((np.ones(len(merged)), (merged[:, 0], merged[:, 1])), shape=(k, k))
        _, label = connected_components(graph, directed=False)
        self.cluster = label
        self.members = [np.flatnonzero(label == c) for c in range(label.max() + 1)]
        # Depth of each cluster from its root: the topmost sketched joint is the piece's anchor.
        depth = np.zeros(k, dtype=int)
        for j in range(k):
            depth[j] = depth[skeleton.parents[j]] + 1 if skeleton.parents[j] >= 0 else 0
        self.depth = [int(depth[m].min()) for m in self.members]
        self.position = [current[m].mean(axis=0) for m in self.members]
        self.neighbours: list[dict[int, int]] = [{} for _ in self.members]  # cluster -> bone child joint
        self.rest_length: dict[int, float] = {}
        for (parent, child), length in zip(bones, lengths, strict=True):
            a, b = int(label[parent]), int(label[child])
            if a != b:
                self.neighbours[a][b] = int(child)
                self.neighbours[b][a] = int(child)
                self.rest_length[int(child)] = float(length)
        self.edge_count = len(self.rest_length)

    def paths(self, start: int, used: set[int]) -> list[list[int]]:
        """Cluster paths from ``start`` of 1 to MAX_BONES_PER_SEGMENT bones, through unbranched
        clusters, none of them in ``used``."""
        out, frontier = [], [[start]]
        for _ in range(MAX_BONES_PER_SEGMENT):
            grown = []
            for path in frontier:
                for nxt in self.neighbours[path[-1]]:
                    if nxt in used or nxt in path:
                        continue
                    out.append(path + [nxt])
                    if len(self.neighbours[nxt]) == 2:
                        grown.append(path + [nxt])
            frontier = grown
        return out


@dataclass
class _Embedding:
    cost: float
    where: dict[int, NDArray[np.float64]]  # cluster -> position
    clusters: set[int]
    bones: set[int]  # child joints of the bones covered
    elsewhere: bool


def _embed(tree: _SkeletonTree, points: NDArray[np.float64],
           piece: dict[tuple[int, int], NDArray[np.float64]], used: set[int], size: float, *,
           beside: bool, snap: float) -> _Embedding | None:
    """The cheapest embedding of one connected piece (its segments and their stretches of
    stroke) into the clusters not ``used``; ``beside``: the piece was drawn away from the figure."""
    adjacency: dict[int, list[int]] = {}
    for a, b in piece:
        adjacency.setdefault(a, []).append(b)
        adjacency.setdefault(b, []).append(a)
    start = max(adjacency, key=lambda n: len(adjacency[n]))
    order: list[tuple[int, int]] = []  # (from, to) in breadth-first order from start
    seen, queue = {start}, [start]
    while queue:
        node = queue.pop(0)
        for nxt in adjacency[node]:
            if nxt not in seen:
                seen.add(nxt)
                order.append((node, nxt))
                queue.append(nxt)
    trail = {**piece, **{(b, a): line[::-1] for (a, b), line in piece.items()}}
    best: list[_Embedding | None] = [None]
    steps = [0]

    def grow(step: int, chosen: dict[int, int], taken: set[int], chains: list[_Chain], turn: float) -> None:
        steps[0] += 1
        if steps[0] > MAX_STEPS:
            raise SketchError("the sketch is too ambiguous to match: draw fewer strokes at a time, "
                              "or start each stroke on a joint")
        if best[0] is not None and turn >= best[0].cost:
            return
        if step == len(order):
            found = _score(tree, points, chosen, chains, turn, size, beside, snap)
            if best[0] is None or found.cost < best[0].cost:
                best[0] = found
            return
        a, b = order[step]
        for path in tree.paths(chosen[a], taken):
            if len(tree.neighbours[path[-1]]) < len(adjacency[b]):
                continue
            bones = [tree.neighbours[u][v] for u, v in zip(path, path[1:], strict=False)]
            joints = _chain_points(trail[a, b], [tree.rest_length[c] for c in bones])
            cost = EXTRA_BONE_COST * (len(path) - 2)
            total = sum(tree.rest_length[c] for c in bones)
            hops = zip(path, path[1:], strict=False)
            for (u, v), c, p, q in zip(hops, bones, joints, joints[1:], strict=False):
                drawn, bone = q - p, tree.position[v] - tree.position[u]
                norm = float(np.hypot(*bone) * np.hypot(*drawn))
                if norm > 0:  # the segment's turn, shared among the bones it covers
                    share = tree.rest_length[c] / total if total > 0 else 1.0
                    cost += (1 - float(drawn @ bone) / norm) * share
            chosen[b] = path[-1]
            grow(step + 1, chosen, taken | set(path[1:]), chains + [_Chain(path, bones, joints)], turn + cost)
            del chosen[b]

    for cluster in range(len(tree.members)):
        if cluster not in used and len(tree.neighbours[cluster]) >= len(adjacency[start]):
            grow(0, {start: cluster}, {cluster}, [], 0.0)
    return best[0]


@dataclass
class _Chain:
    """One segment embedded: the clusters it passes, the bones (child joints), the joints' places."""

    path: list[int]
    bones: list[int]
    joints: NDArray[np.float64]


def _score(tree: _SkeletonTree, points: NDArray[np.float64], chosen: dict[int, int],
           chains: list[_Chain], turn: float, size: float, elsewhere: bool, snap: float) -> _Embedding:
    """The full cost of one embedding, in place or drawn elsewhere, and where it puts the joints."""
    top = min(chosen, key=lambda n: (tree.depth[chosen[n]], n))
    # A piece that starts on its joint hangs from it: a stroke begun on the shoulder leaves it put.
    elsewhere_or_on = elsewhere or float(np.hypot(*(points[top] - tree.position[chosen[top]]))) <= snap
    drawn = [float(np.hypot(*(q - p))) for chain in chains for p, q in zip(chain.joints, chain.joints[1:],
                                                                            strict=False)]
    rest = [tree.rest_length[c] for chain in chains for c in chain.bones]
    scale = sum(drawn) / sum(rest) if elsewhere and sum(rest) > 0 and sum(drawn) > 0 else 1.0
    anchor = tree.position[chosen[top]] if elsewhere_or_on else points[top]
    cost = turn
    cost += LENGTH_WEIGHT * sum(math.log(d / (scale * r)) ** 2 for d, r in zip(drawn, rest, strict=True)
                                if d > 0 and r > 0)
    where = {}
    for chain in chains:
        for cluster, xy in zip(chain.path, chain.joints, strict=True):
            where[cluster] = anchor + (xy - points[top]) / scale
    for node, cluster in chosen.items():
        weight = POSITION_WEIGHT * (TOP_WEIGHT if node == top else 1.0)
        cost += weight * float(np.sum((where[cluster] - tree.position[cluster]) ** 2)) / size**2
    return _Embedding(cost=cost, where=where, clusters=set(where),
                      bones={c for chain in chains for c in chain.bones}, elsewhere=elsewhere)


def _beside(points: NDArray[np.float64], piece: dict[tuple[int, int], NDArray[np.float64]],
            current: NDArray[np.float64]) -> bool:
    """Whether a piece was drawn beside the figure: its box and the joints' box, each grown by
    a tenth of the figure's size, do not meet."""
    drawn = np.concatenate(list(piece.values()))
    margin = 0.1 * _size(current)
    low, high = current.min(axis=0) - margin, current.max(axis=0) + margin
    return bool((drawn.max(axis=0) < low).any() or (drawn.min(axis=0) > high).any())


def _carry(skeleton: Skeleton, current: NDArray[np.float64], placed: NDArray[np.float64],
           mapped: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Joints not sketched follow their nearest sketched ancestor, turned with the bone above it."""
    out = placed.copy()
    parents = skeleton.parents
    for j in range(len(skeleton)):  # parents first
        if mapped[j]:
            continue
        anchor = parents[j]
        while anchor >= 0 and not mapped[anchor]:
            anchor = parents[anchor]
        if anchor < 0:
            continue
        turn = _turn(skeleton, current, placed, mapped, anchor)
        c, s = math.cos(turn), math.sin(turn)
        offset = current[j] - current[anchor]
        out[j] = placed[anchor] + np.array([c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]])
    return out


def _turn(skeleton: Skeleton, current: NDArray[np.float64], placed: NDArray[np.float64],
          mapped: NDArray[np.bool_], joint: int) -> float:
    """How far the sketch turned the nearest sketched bone of some length ending at ``joint``."""
    child, parent = joint, skeleton.parents[joint]
    while parent >= 0 and mapped[parent]:
        before, after = current[child] - current[parent], placed[child] - placed[parent]
        if np.hypot(*before) > 1e-9 and np.hypot(*after) > 1e-9:
            return math.atan2(after[1], after[0]) - math.atan2(before[1], before[0])
        child, parent = parent, skeleton.parents[parent]
    return 0.0


# --- small geometry ------------------------------------------------------------------------------


def _chain_points(trail: NDArray[np.float64], steps: Sequence[float]) -> NDArray[np.float64]:
    """Joints along ``trail`` (a polyline) at the arc-length shares of bones of lengths ``steps``."""
    run = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(trail, axis=0).T))])
    total = sum(steps)
    shares = np.cumsum([0.0, *steps]) / total if total > 0 else np.linspace(0, 1, len(steps) + 1)
    at = shares * run[-1]
    return np.stack([np.interp(at, run, trail[:, 0]), np.interp(at, run, trail[:, 1])], axis=1)


def _size(positions: NDArray[np.float64]) -> float:
    """The diagonal of the joints' bounding box, at least 1 px."""
    return max(1.0, float(np.hypot(*np.ptp(positions, axis=0))))
