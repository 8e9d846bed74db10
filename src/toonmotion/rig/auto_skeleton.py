"""An animation skeleton built from a curve skeleton, for drawings that come without one.

Each connected piece of the curve skeleton becomes one tree. Its root is the junction with the
largest inscribed circle (the body's core) or, with no junction, the middle of its longest
branch. Walking outwards from the root, every branch becomes a chain of bones: joints at its
far end and evenly along it, so no bone is longer than ``max_bone`` (that puts elbows and knees
on limbs). A branch that closes a loop (around a hole) is left out, which keeps it a tree.

Joints are named ``root`` (``root2``, ... for further pieces) and ``joint1``, ``joint2``, ...
in the order they are made; rename them in the project or give a skeleton file to use your own.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from toonmotion.errors import SkeletonError
from toonmotion.geometry.segments import arc_lengths
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import CurveSkeleton, default_bone_length, split_points


def skeleton_from_curve_skeleton(curve_skeleton: CurveSkeleton, *, max_bone: float | None = None) -> Skeleton:
    """Build an animation skeleton along a curve skeleton.

    Parameters
    ----------
    curve_skeleton : CurveSkeleton
    max_bone : float, optional
        Longest bone in pixels; default a fifth of the curve skeleton's bounding-box diagonal.

    Returns
    -------
    Skeleton
    """
    cs = curve_skeleton
    if len(cs.nodes) == 0:
        raise SkeletonError("the curve skeleton is empty, so no skeleton can be built from it")
    max_bone = float(max_bone) if max_bone else default_bone_length(cs)
    joints = []  # (name, parent, (x, y))
    counter = iter(range(1, 1 << 30))

    def add(parent, point):
        name = f"joint{next(counter)}"
        joints.append((name, parent, (float(point[0]), float(point[1]))))
        return name

    def chain(parent, path):
        """Joints along ``path`` (which starts at ``parent``'s position) and at its end."""
        for point in split_points(path, max_bone):
            parent = add(parent, point)
        return add(parent, path[-1])

    adjacency = _adjacency(cs)
    visited = np.zeros(len(cs.nodes), dtype=bool)
    for piece, nodes in enumerate(_pieces(cs, adjacency)):
        root_name = "root" if piece == 0 else f"root{piece + 1}"
        junctions = [i for i in nodes if cs.kinds[i] == "junction"]
        if junctions:
            root = max(junctions, key=lambda i: cs.radius[i])
            joints.append((root_name, None, tuple(map(float, cs.nodes[root]))))
            starts = [(root, root_name)]
        else:
            starts = _root_on_longest_branch(cs, nodes, adjacency, root_name, joints, chain)
            root = starts[0][0] if starts else nodes[0]
        visited[root] = True
        for node, _name in starts:
            visited[node] = True
        queue = deque(starts)
        while queue:
            node, name = queue.popleft()
            for _, other, path in adjacency[node]:
                if visited[other] or other == node:
                    continue
                visited[other] = True
                queue.append((other, chain(name, path)))
    if len(joints) == 1:  # a blob that thinned to one point: give it one upright bone
        x, y = joints[0][2]
        radius = max(float(cs.radius.max()), 1.0)
        joints.append(("joint1", joints[0][0], (x, y - radius)))
    return Skeleton.from_joints(joints)


def _adjacency(cs):
    """For each node: (branch, other node, path oriented away from the node)."""
    adjacency = [[] for _ in cs.nodes]
    for b, ((i, j), path) in enumerate(zip(cs.branches, cs.paths, strict=True)):
        adjacency[i].append((b, j, path))
        if i != j:
            adjacency[j].append((b, i, path[::-1]))
    return adjacency


def _pieces(cs, adjacency):
    """Node sets of the connected pieces, largest (by total branch length) first.

    Each is a sorted list; pieces of equal size keep the order of their lowest node.
    """
    n = len(cs.nodes)
    ends = np.asarray(cs.branches, dtype=np.int64).reshape(-1, 2)
    graph = coo_array((np.ones(len(ends)), (ends[:, 0], ends[:, 1])), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    pieces = sorted((np.flatnonzero(label == piece).tolist() for piece in np.unique(label)), key=min)
    lengths = cs.lengths

    def size(nodes):
        branches = {b for n in nodes for b, _, _ in adjacency[n]}
        return sum(lengths[b] for b in branches)

    return sorted(pieces, key=size, reverse=True)


def _root_on_longest_branch(cs, nodes, adjacency, root_name, joints, chain):
    """Root a junction-free piece at the middle of its longest branch; chain both halves."""
    branches = {b for n in nodes for b, _, _ in adjacency[n]}
    if not branches:  # a lone point
        joints.append((root_name, None, tuple(map(float, cs.nodes[nodes[0]]))))
        return [(nodes[0], root_name)]
    b = max(branches, key=lambda k: cs.lengths[k])
    path = cs.paths[b]
    arc = arc_lengths(path)
    middle = int(np.searchsorted(arc, arc[-1] / 2))
    middle = min(max(middle, 1), len(path) - 2) if len(path) > 2 else 0
    joints.append((root_name, None, tuple(map(float, path[middle]))))
    i, j = cs.branches[b]
    starts = []
    for node, half in ((j, path[middle:]), (i, path[: middle + 1][::-1])):
        if len(half) >= 2 and not (node == i == j and starts):
            starts.append((node, chain(root_name, half)))
    return starts
