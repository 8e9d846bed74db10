"""The cartoon filter on a single pose (thesis 5.2.1, eq. 5.5, fig. 5.3 and 5.4).

The animator draws an acceleration ``OA`` at the root ``O`` and picks joints that stay put
(feet on the ground). For each fixed joint ``B`` the chain of joints from ``O`` down to ``B``
is deformed as one piece: ``OB`` becomes ``OB' = OB + OA`` (eq. 5.5). The transform is the
thesis' two stages, a rotation ``R`` that turns ``OB`` onto the direction of ``OB'`` and then a
scale along that direction,

    M = S R,    S = I + (s - 1) u u^T,    s = |OB'| / |OB|,    u = OB' / |OB'|,

applied to every joint of the chain relative to ``O`` (so ``M OB = OB'``). Then the whole
character moves by ``B - B' = -OA``, which puts every fixed joint back where it was, and the
root ends up at ``O - OA``: pushing up before a jump crouches the figure, pushing right before a
run leans it back (anticipation).

Choices where the paper leaves them open:

- ``S`` scales along ``u`` only; sizes across ``OB'`` are kept. That is what makes a squashed
  leg bend more (fig. 5.4): a bent knee's offset from the hip-foot line is across ``u`` and keeps
  its size while the leg's extent along ``u`` shrinks by ``s``, so the thigh and shin turn
  towards each other and the angle at the knee closes. A uniform scale would shrink the leg
  without bending it; a stretch (``s > 1``) straightens it instead.
- A chain whose first bone leaves the root sideways (more than :data:`CONNECTOR_ANGLE` from
  the line ``OB``) pivots at that bone's end instead of at ``O``: the sideways hip bones of
  Animated-Drawings-style skeletons (root -> right_hip, 46-82 degrees off the root-foot line on
  the five test figures) are part of the pelvis, so they move with the body and only the limb
  below them turns and scales. Turning them with the leg folded the pelvis over the thighs:
  three of the five test figures lost 8-10% of their area for a push of 15% of their height.
  A skeleton whose legs start at the root, as in the thesis' fig. 5.3, has no such bone and is
  filtered exactly as eq. 5.5 says.
- A joint on several chains (a spine shared by both legs) takes the mean of its transformed
  positions. Fixed joints are then set exactly to their input positions, bit for bit.
- A joint on no chain (arms, head, the other leg, toes below a fixed foot) moves rigidly with
  its nearest ancestor on a chain; joints with none (ancestors of a ``root`` that is not a
  skeleton root, other trees of a forest) move with the root, by ``-OA``.
- A chain must not collapse: a fixed joint at the root's own place has no direction, and an
  acceleration that shrinks ``|OB'|`` below :data:`MIN_CHAIN_FRACTION` of ``|OB|`` is refused.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from toonmotion.animate.cartoon_filter import joint_indices
from toonmotion.errors import FilterError, PoseError
from toonmotion.rig.kinematics import rotation
from toonmotion.rig.pose import Pose, check_pose
from toonmotion.rig.skeleton import Skeleton

# A chain root -> fixed joint shorter than this (pixels) has no direction.
MIN_CHAIN_LENGTH = 1e-6

# The acceleration may shrink a chain to this fraction of its length, no further.
MIN_CHAIN_FRACTION = 0.05

# A chain's first bone this far (radians) off the root-to-fixed-joint line is a connector (a hip
# bone): it moves with the body and the chain pivots at its end.
CONNECTOR_ANGLE = np.radians(40.0)


def exaggerate_pose(
    skeleton: Skeleton, pose: Pose, accel: ArrayLike, fixed: Sequence[str], *, root: str | None = None
) -> Pose:
    """Squash or stretch a pose along a drawn acceleration, keeping the fixed joints in place.

    Parameters
    ----------
    skeleton : Skeleton
    pose : Pose
    accel : (2,) float
        ``(dx, dy)`` pixels, y down: the acceleration drawn at the root. ``(0, -40)`` pushes
        up, as before a jump.
    fixed : sequence of str
        Names of the joints that stay put (feet on the ground); at least one, each below the root.
    root : str, optional
        The joint the acceleration acts on; by default the skeleton root of the tree that holds
        the fixed joints.

    Returns
    -------
    Pose
        A new pose; the fixed joints keep their positions exactly and the root moves by ``-accel``.

    Examples
    --------
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> leg = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (3, 4)), ("foot", "knee", (0, 8))])
    >>> np.round(exaggerate_pose(leg, Pose(leg.positions), (0, -4), ["foot"]).positions, 3).tolist()
    [[0.0, 4.0], [3.0, 6.0], [0.0, 8.0]]
    """
    P = _checked_positions(skeleton, pose)
    a = _accel(accel)
    held = joint_indices(skeleton, fixed, what="fixed joints")
    if not held:
        raise FilterError("there are no fixed joints; fix at least one joint, such as a foot on the ground")
    o = _root(skeleton, held, root)
    origin = P[o]

    total, count = np.zeros_like(P), np.zeros(len(skeleton))
    for b in held:
        chain = _chain(skeleton, o, b)
        pivot = chain[1] if _is_connector(P, chain) else o
        limb = chain[chain.index(pivot):]
        M = _chain_transform(P[b] - P[pivot], a, skeleton.names[pivot], skeleton.names[b])
        total[chain] += P[chain] - a  # joints above the pivot move with the body
        total[limb] += (P[limb] - P[pivot]) @ M.T - (P[limb] - P[pivot])
        count[chain] += 1
    on_chain = count > 0
    out = P.copy()
    out[on_chain] = total[on_chain] / count[on_chain, None]
    out[o] = origin - a
    out[held] = P[held]  # exactly where they were

    # Joints on no chain move rigidly with their nearest chain ancestor, or with the root.
    move = out - P
    for j, parent in enumerate(skeleton.parents):  # parents come first
        if not on_chain[j]:
            move[j] = move[parent] if parent >= 0 else -a
            out[j] = P[j] + move[j]
    try:
        return check_pose(skeleton, Pose(positions=out), where="the exaggerated pose")
    except PoseError as error:
        raise FilterError(f"{error}; use a smaller acceleration") from None


def _is_connector(P, chain):
    """Whether the chain's first bone leaves the root sideways (see the module notes)."""
    if len(chain) < 3:
        return False
    first, whole = P[chain[1]] - P[chain[0]], P[chain[-1]] - P[chain[0]]
    size = np.hypot(*first) * np.hypot(*whole)
    return size > 0 and abs(first @ whole) < np.cos(CONNECTOR_ANGLE) * size


def _chain_transform(OB, a, root_name, fixed_name):
    """``M = S R`` taking ``OB`` to ``OB + a`` (see the module notes), ``(2, 2)``."""
    length = np.hypot(*OB)
    if length < MIN_CHAIN_LENGTH:
        raise FilterError(
            f"fixed joint {fixed_name!r} is at the position of the root {root_name!r}, so its chain has no "
            "direction; fix a joint away from the root"
        )
    target = OB + a
    s = np.hypot(*target) / length
    if s < MIN_CHAIN_FRACTION:
        raise FilterError(
            f"the acceleration ({a[0]:g}, {a[1]:g}) cancels the chain from {root_name!r} to {fixed_name!r} "
            f"(it would shrink to {s:.1%} of its length); shorten the acceleration"
        )
    angle = np.arctan2(OB[0] * target[1] - OB[1] * target[0], OB @ target)
    u = target / np.hypot(*target)
    S = np.eye(2) + (s - 1) * np.outer(u, u)
    return S @ rotation(angle)


def _chain(skeleton, o, b):
    """Joint indices from ``o`` down to ``b``, both included; FilterError if ``b`` is not below ``o``."""
    chain, j = [b], b
    while j != o and j >= 0:
        j = skeleton.parents[j]
        chain.append(j)
    if j != o or b == o:
        raise FilterError(
            f"joint {skeleton.names[b]!r} is not on a chain from the root {skeleton.names[o]!r}; "
            "fix joints below the root, such as its feet"
        )
    return chain[::-1]


def _root(skeleton, fixed, root):
    """Index of the root joint: ``root`` by name, or the tree root above the fixed joints."""
    if root is not None:
        return joint_indices(skeleton, [root], what="root")[0]
    tops = {}
    for b in fixed:
        j = b
        while skeleton.parents[j] >= 0:
            j = skeleton.parents[j]
        tops.setdefault(int(j), b)
    if len(tops) > 1:
        (r1, b1), (r2, b2) = list(tops.items())[:2]
        names = skeleton.names
        raise FilterError(
            f"fixed joints {names[b1]!r} and {names[b2]!r} are in different trees (roots {names[r1]!r} "
            f"and {names[r2]!r}); give root= or fix joints of one tree"
        )
    return next(iter(tops))


def _accel(accel):
    try:
        a = np.array(accel, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape != (2,) or not np.all(np.isfinite(a)):
        raise FilterError(f"the acceleration must be two finite numbers (dx, dy) in pixels, got {accel!r}")
    return a


def _checked_positions(skeleton, pose):
    if not isinstance(pose, Pose):
        raise FilterError(f"pose must be a Pose, got {type(pose).__name__}")
    try:
        check_pose(skeleton, pose)
    except PoseError as error:
        raise FilterError(str(error)) from None
    return np.array(pose.positions, dtype=float)
