"""What dragging a joint does to a pose, as skeletal animation tools do it (Spine, Moho,
DragonBones): the bones keep their lengths unless the animator asks for a stretch.

Three ways, :data:`DRAG_MODES`:

* ``"turn"`` (forward kinematics, the default): the joint's bone turns about its parent joint
  towards the pointer and carries everything below the joint with it. A root moves the whole
  figure. A bone of no length (two joints at one place) turns about the nearest joint above
  that is elsewhere.
* ``"reach"`` (inverse kinematics): the joint reaches for the pointer by bending the chain of
  bones above it, up to ``bones`` of them (2: a hand moves the forearm and upper arm), stopping
  at a pinned joint, a joint where bones branch, or a root, which stay. The chain is solved by
  FABRIK (Aristidou and Lasenby 2011), which keeps every bone's length and, started from the
  current pose, its bend to the same side; each joint's other bones are carried by its chain
  bone's turn. Out of reach, the chain points straight at the pointer.
* ``"stretch"``: the joint goes to the pointer and everything below it moves along; its own bone
  stretches (or shrinks) and turns.

Every function takes the pose as ``(k, 2)`` positions and returns new ones; none checks the pose
(:func:`~toonmotion.rig.pose.check_pose` does, where a pose is made).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import PoseError
from toonmotion.rig.kinematics import rotate
from toonmotion.rig.pose import descendants
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

DRAG_MODES = ("turn", "reach", "stretch")

# FABRIK stops when the chain's end is this close to where it reaches for (px), or after this
# many passes (each pass moves it closer; 2-3 bones settle in a few).
_REACH_TOLERANCE = 1e-3
_REACH_PASSES = 64


def drag_joint(
    skeleton: Skeleton, positions: ArrayLike, joint: int | str, target: ArrayLike, *, mode: str = "turn",
    pinned: Iterable[int | str] = (), bones: int = 2,
) -> NDArray[np.float64]:
    """The pose ``positions`` with ``joint`` dragged to ``target`` (module docstring).

    Parameters
    ----------
    skeleton : Skeleton
    positions : (k, 2) float
        The pose before the drag (the one at the press, for a drag that goes on: each move is
        then made from it, not from the last, so nothing drifts).
    joint : int or str
        The joint dragged, by index or name.
    target : (2,) float
        Where the pointer is.
    mode : {"turn", "reach", "stretch"}
    pinned : joints, by index or name
        Joints the animator pinned: an IK chain (``"reach"``) stops at them, and a pinned joint
        dragged does not move. A turn or a stretch above one carries it along, as in Spine.
    bones : int
        ``"reach"``: the longest chain, >= 1.

    Examples
    --------
    >>> s = Skeleton.from_joints([("shoulder", None, (0, 0)), ("elbow", "shoulder", (10, 0)),
    ...                           ("hand", "elbow", (20, 0))])
    >>> drag_joint(s, s.positions, "elbow", (0, 5)).round(9).tolist()  # the arm turns down
    [[0.0, 0.0], [0.0, 10.0], [0.0, 20.0]]
    >>> drag_joint(s, s.positions, "hand", (10, 10), mode="stretch").tolist()
    [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]]
    """
    if mode not in DRAG_MODES:
        raise PoseError(f"a drag's mode must be one of {', '.join(DRAG_MODES)}, got {mode!r}")
    if isinstance(bones, bool) or not isinstance(bones, int | np.integer) or bones < 1:
        raise PoseError(f"an IK chain must have at least one bone, got {bones!r}")
    out = np.array(positions, dtype=float)
    if out.shape != (len(skeleton), 2):
        raise PoseError(f"a pose of this skeleton has {len(skeleton)} joints, got positions of shape "
                        f"{out.shape}")
    j = _index(skeleton, joint)
    goal = np.asarray(target, dtype=float)
    if goal.shape != (2,) or not np.isfinite(goal).all():
        raise PoseError(f"a drag's target must be a point (x, y), got {np.asarray(target).tolist()!r}")
    held = {_index(skeleton, p) for p in pinned}
    if j in held:
        return out  # a pinned joint stays
    if mode == "stretch":
        return _carry(skeleton, out, j, goal - out[j])
    if mode == "reach":
        chain = _chain(skeleton, out, j, held, bones)
        if len(chain) > 2:
            return _reach(skeleton, out, chain, goal)
    pivot = _pivot(skeleton, out, j)
    if pivot < 0:  # a root, or a joint at its root's place: the whole figure moves
        root = j
        while skeleton.parents[root] >= 0:
            root = int(skeleton.parents[root])
        return _carry(skeleton, out, root, goal - out[j])
    return _turn_towards(skeleton, out, pivot, j, goal)


def _index(skeleton: Skeleton, joint: int | str) -> int:
    if isinstance(joint, str):
        return skeleton.index(joint)
    count = len(skeleton)
    if isinstance(joint, bool) or not isinstance(joint, int | np.integer) or not 0 <= joint < count:
        raise PoseError(f"no joint {joint!r}: joints are numbered 0 to {count - 1}")
    return int(joint)


def _carry(skeleton, out, joint, shift):
    """``joint`` and everything below it moved by ``shift``."""
    moving = np.append(descendants(skeleton, joint), joint)
    out[moving] += shift
    return out


def _pivot(skeleton, out, joint):
    """The nearest joint above ``joint`` that is not at its place; -1 if none."""
    p = int(skeleton.parents[joint])
    while p >= 0 and np.hypot(*(out[joint] - out[p])) <= MIN_BONE_LENGTH:
        p = int(skeleton.parents[p])
    return p


def _turn_towards(skeleton, out, pivot, joint, goal):
    """Turn the joints below ``pivot`` on the way to ``joint``, and all below them, about
    ``pivot`` so that ``joint`` points at ``goal``."""
    reach, wanted = out[joint] - out[pivot], goal - out[pivot]
    if np.hypot(*wanted) <= MIN_BONE_LENGTH:
        return out  # the pointer is on the pivot: no direction to turn to
    angle = np.arctan2(wanted[1], wanted[0]) - np.arctan2(reach[1], reach[0])
    top = joint
    while int(skeleton.parents[top]) != pivot:
        top = int(skeleton.parents[top])
    moving = np.append(descendants(skeleton, top), top)
    out[moving] = rotate(out[moving], angle, about=out[pivot])
    return out


def _chain(skeleton, out, joint, held, bones):
    """The joints an IK drag of ``joint`` moves, base first (the base stays): up from ``joint``
    over at most ``bones`` bones of length, stopping at a pinned joint, one where bones branch, or a
    root. Bones of no length ride along with the joint below them."""
    children = np.bincount(skeleton.parents[skeleton.parents >= 0], minlength=len(skeleton))
    chain, counted = [joint], 0
    while counted < bones:
        p = int(skeleton.parents[chain[-1]])
        if p < 0:
            break
        chain.append(p)
        if np.hypot(*(out[chain[-2]] - out[p])) > MIN_BONE_LENGTH:
            counted += 1
        if p in held or children[p] > 1 or skeleton.parents[p] < 0:
            break
    return [c for c in chain[::-1]]


def _reach(skeleton, out, chain, goal):
    """FABRIK over ``chain`` (base first), then every joint's other bones carried by the turn of
    the chain bone above them."""
    start = out[chain].copy()
    P = start.copy()
    lengths = np.hypot(*(P[1:] - P[:-1]).T)
    base = P[0].copy()
    if np.hypot(*(goal - base)) >= lengths.sum():  # out of reach: straight at the pointer
        way = (goal - base) / max(np.hypot(*(goal - base)), 1e-300)
        P[1:] = base + np.cumsum(lengths)[:, None] * way
    elif len(P) == 3 and (lengths > MIN_BONE_LENGTH).all():
        P[1], P[2] = _two_bones(P, lengths, goal)
    else:
        for _ in range(_REACH_PASSES):
            P[-1] = goal
            for i in range(len(P) - 2, -1, -1):  # backward: from the end to the base
                P[i] = P[i + 1] + _unit(P[i] - P[i + 1]) * lengths[i]
            P[0] = base
            for i in range(1, len(P)):  # forward: from the base to the end
                P[i] = P[i - 1] + _unit(P[i] - P[i - 1]) * lengths[i - 1]
            if np.hypot(*(P[-1] - goal)) <= _REACH_TOLERANCE:
                break
    # Each chain joint's subtree off the chain turns with the bone into it and moves with it.
    on_chain = set(chain)
    for i in range(1, len(chain)):
        bone_before, bone_after = start[i] - start[i - 1], P[i] - P[i - 1]
        turn = np.arctan2(bone_after[1], bone_after[0]) - np.arctan2(bone_before[1], bone_before[0]) \
            if lengths[i - 1] > MIN_BONE_LENGTH else 0.0
        below = [int(d) for d in descendants(skeleton, chain[i]) if int(d) not in on_chain
                 and not _below_any(skeleton, int(d), chain[i + 1:])]
        if below:
            out[below] = rotate(out[below], turn, about=start[i]) + (P[i] - start[i])
    out[chain] = P
    return out


def _two_bones(P, lengths, goal):
    """The middle and end of a two-bone chain ``P`` (base, middle, end) reaching for ``goal``
    within reach, bent to the side it is bent now (law of cosines)."""
    base, (a, b) = P[0], lengths
    reach = goal - base
    d = float(np.clip(np.hypot(*reach), abs(a - b), a + b))
    side = np.sign(_cross(P[1] - P[0], P[2] - P[1])) or 1.0
    cos_base = np.clip((a * a + d * d - b * b) / (2 * a * d), -1.0, 1.0) if d > 0 else 1.0
    # Turning the base-to-goal direction by -side times the base's angle bends to that side.
    heading = np.arctan2(reach[1], reach[0]) - side * np.arccos(cos_base)
    middle = base + a * np.array([np.cos(heading), np.sin(heading)])
    end = base + d * _unit(reach) if np.hypot(*reach) > 0 else P[2]
    return middle, end


def _cross(u, v):
    return float(u[0] * v[1] - u[1] * v[0])


def _below_any(skeleton, joint, ancestors):
    """Whether ``joint`` hangs below one of ``ancestors`` (which the chain moves in its turn)."""
    p = int(skeleton.parents[joint])
    while p >= 0:
        if p in ancestors:
            return True
        p = int(skeleton.parents[p])
    return False


def _unit(v):
    size = np.hypot(*v)
    return v / size if size > 1e-300 else np.zeros(2)
