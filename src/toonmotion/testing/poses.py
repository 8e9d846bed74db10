"""Pose sets built from a skeleton's structure, never from joint names: what the deformation
tests and ``benchmarks/deform.py`` share.

A *bend joint* has a parent and exactly one child, both bones with length; a *chain* starts at a
joint whose parent branches (or is the root) and runs to a leaf. *Above the root* is above it in
the image: drawings stand upright. So a six-armed figure (``right_elbow1`` ... ``right_elbow3``)
or a pig gets the same treatment as a humanoid with Animated Drawings' names.

* :func:`key_poses`: rest, every bend joint at 60 degrees (alternate ways), every chain above the
  root raised 60 degrees above horizontal, rest (an animation's keys);
* :func:`extreme_poses`: each bend joint bent 150 degrees above the root and 120 below (an elbow,
  a knee), both ways, one at a time; every chain raised: above the root to 80 degrees (arms
  overhead), below it sideways; the upper body turned 40 degrees both ways against the lower;
* :func:`stretch_poses`: every bone with length stretched 1.5x, one at a time;
* :func:`filter_jump`: the single-frame filter's jump (pushed up by 15% of the figure's height,
  every leaf below the root held down).
"""

from __future__ import annotations

import numpy as np

from toonmotion.animate.pose_filter import exaggerate_pose
from toonmotion.rig.character import Character
from toonmotion.rig.pose import Pose, descendants, rotate_about
from toonmotion.rig.skeleton import Skeleton

# Joints closer than this (px) are at one place.
_SAME = 1e-6


def _children(skeleton):
    kids = [[] for _ in range(len(skeleton))]
    for j, p in enumerate(skeleton.parents):
        if p >= 0:
            kids[p].append(j)
    return kids


def bend_joints(skeleton: Skeleton) -> list[int]:
    """Joints with a parent and exactly one child, whose bones both have length."""
    kids = _children(skeleton)
    P = skeleton.positions
    return [j for j in range(len(skeleton)) if skeleton.parents[j] >= 0 and len(kids[j]) == 1
            and np.linalg.norm(P[j] - P[skeleton.parents[j]]) > _SAME
            and np.linalg.norm(P[kids[j][0]] - P[j]) > _SAME]


def chain_starts(skeleton: Skeleton) -> list[int]:
    """Joints that start a chain: their parent branches (or is the root), and they have length."""
    kids = _children(skeleton)
    P = skeleton.positions
    return [j for j in range(len(skeleton)) if skeleton.parents[j] >= 0
            and (len(kids[skeleton.parents[j]]) >= 2 or skeleton.parents[skeleton.parents[j]] < 0)
            and np.linalg.norm(P[j] - P[skeleton.parents[j]]) > _SAME and kids[j]]


def _root(skeleton):
    """The first root joint."""
    return int(np.flatnonzero(skeleton.parents < 0)[0])


def _above(P, j, root):
    """Joint ``j`` is above ``root`` in the image (y down)."""
    return bool(P[j, 1] < P[root, 1])


def _turn_to(skeleton, P, joint, direction):
    """Turn the bone from ``joint`` to its first child, and all below, to point along ``direction``."""
    child = _children(skeleton)[joint][0]
    d = P[child] - P[joint]
    turn = (np.arctan2(direction[1], direction[0]) - np.arctan2(d[1], d[0]) + np.pi) % (2 * np.pi) - np.pi
    return rotate_about(skeleton, P, skeleton.names[joint], turn)


def _raise(skeleton, P, degrees, below_sideways=True):
    """Every chain raised: above the root to ``degrees`` above horizontal, outwards; below it
    sideways to horizontal when ``below_sideways``."""
    root = _root(skeleton)
    for j in chain_starts(skeleton):
        outwards = np.sign(P[j, 0] - P[skeleton.parents[j], 0]) or np.sign(P[j, 0] - P[root, 0]) or 1.0
        if _above(P, j, root):
            a = np.radians(degrees)
            P = _turn_to(skeleton, P, j, (outwards * np.cos(a), -np.sin(a)))
        elif below_sideways:
            P = _turn_to(skeleton, P, j, (outwards, 0.0))
    return P


def key_poses(skeleton: Skeleton) -> list[Pose]:
    """Rest, every bend joint at 60 degrees (alternating ways), chains raised 60 degrees, rest."""
    rest = skeleton.positions
    bent = rest
    for i, j in enumerate(bend_joints(skeleton)):
        bent = rotate_about(skeleton, bent, skeleton.names[j], (np.pi / 3) * (-1) ** i)
    raised = _raise(skeleton, rest, 60.0, below_sideways=False)
    return [Pose(np.array(p)) for p in (rest, bent, raised, rest)]


def extreme_poses(skeleton: Skeleton) -> list[tuple[str, Pose]]:
    """The extreme pose set (module docstring), ``[(label, Pose)]``."""
    rest = skeleton.positions
    root = _root(skeleton)
    poses = []
    for j in bend_joints(skeleton):
        angle = np.radians(150.0 if _above(rest, j, root) else 120.0)
        for sign in (1, -1):
            poses.append((f"{skeleton.names[j]} {sign * np.degrees(angle):+.0f}",
                          rotate_about(skeleton, rest, skeleton.names[j], sign * angle)))
    poses.append(("chains raised", _raise(skeleton, rest, 80.0)))
    kids = _children(skeleton)
    while len(kids[root]) == 1:
        root = kids[root][0]  # the joint the body branches at
    upper = [j for j in kids[root] if rest[np.r_[j, descendants(skeleton, j)], 1].mean() < rest[root, 1]]
    for j in upper[:1]:
        for sign in (1, -1):
            turned = _turn_upper(skeleton, rest, root, j, sign * np.radians(40))
            poses.append((f"upper body {sign * 40:+d}", turned))
    return [(label, Pose(np.array(P))) for label, P in poses]


def _turn_upper(skeleton, P, root, top, angle):
    """Turn ``top`` and everything below it about the root by ``angle``."""
    moved = np.concatenate([[top], descendants(skeleton, top)])
    c, s = np.cos(angle), np.sin(angle)
    out = np.array(P, dtype=float)
    out[moved] = (out[moved] - out[root]) @ np.array([[c, s], [-s, c]]) + out[root]
    return out


def stretch_poses(skeleton: Skeleton) -> list[tuple[str, Pose]]:
    """Every bone with length stretched 1.5x, one at a time, carrying everything below it."""
    P = skeleton.positions
    out = []
    for child, parent in enumerate(skeleton.parents):
        if parent < 0 or np.linalg.norm(P[child] - P[parent]) <= _SAME:
            continue
        moved = np.concatenate([[child], descendants(skeleton, child)])
        Q = np.array(P, dtype=float)
        Q[moved] += 0.5 * (P[child] - P[parent])
        out.append((f"{skeleton.names[child]} x1.5", Pose(Q)))
    return out


def filter_jump(character: Character) -> Pose:
    """The single-frame filter's jump: pushed up by 15% of the figure's height, every leaf below
    the root held down."""
    skeleton = character.skeleton
    root = _root(skeleton)
    kids = _children(skeleton)
    P = skeleton.positions
    feet = [skeleton.names[j] for j in range(len(skeleton)) if not kids[j] and P[j, 1] > P[root, 1]]
    rows = np.flatnonzero(character.mask.any(axis=1))
    push = np.array([0.0, -0.15 * (rows[-1] - rows[0] + 1)])
    return exaggerate_pose(skeleton, Pose(P), push, feet, root=skeleton.names[root])
