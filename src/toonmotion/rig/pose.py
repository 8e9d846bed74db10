"""Poses: a new 2D position for every joint of a skeleton (a sketched skeleton, thesis 3.4).

Bones may rotate, stretch and squash: a pose is free positions, not angles. A bone whose rest
length is non-zero must keep a length of at least :data:`MIN_POSED_FRACTION` of it in a pose,
because the needle model divides by the bone's stretch.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import PoseError
from toonmotion.geometry.arrays import MAX_COORDINATE, finite_point, frozen_array
from toonmotion.rig.kinematics import rotation, transform
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

# A posed bone may squash to 2% of its rest length, no further.
MIN_POSED_FRACTION = 0.02


@dataclass(frozen=True, eq=False)
class Pose:
    """Joint positions for one skeleton, in the skeleton's joint order.

    Attributes
    ----------
    positions : (k, 2) float
        (x, y) pixels, y down, one row per joint of the skeleton.

    Construction copies the positions (read-only; the caller's array stays writeable) and
    raises :class:`PoseError` unless they are ``(k, 2)`` numbers. Whether they fit a skeleton
    and are finite is :func:`check_pose`'s business, which names the joint.
    """

    positions: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "positions", frozen_array(self.positions, dtype=np.float64, shape=(None, 2),
                                                           name="a pose's positions", error=PoseError))


def rest_pose(skeleton: Skeleton) -> Pose:
    """The skeleton's own rest positions as a pose."""
    return Pose(positions=np.array(skeleton.positions, dtype=float))


def pose_from_joints(skeleton: Skeleton, joints: Mapping[str, Any], *, where: str = "pose") -> Pose:
    """A pose from a mapping of joint name to ``(x, y)``.

    Every joint of the skeleton must be given, and no other; positions must be finite.

    Examples
    --------
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> s = Skeleton.from_joints([("arm", None, (0, 0)), ("hand", "arm", (10, 0))])
    >>> pose_from_joints(s, {"arm": (0, 0), "hand": (0, 10)}).positions.tolist()
    [[0.0, 0.0], [0.0, 10.0]]
    """
    if not isinstance(joints, dict):
        raise PoseError(f"{where}: joints must be a mapping of joint name to [x, y]")
    unknown = [name for name in joints if name not in skeleton.names]
    if unknown:
        raise PoseError(
            f"{where}: unknown joint {unknown[0]!r}; the skeleton's joints are: "
            f"{', '.join(skeleton.names)}"
        )
    missing = [name for name in skeleton.names if name not in joints]
    if missing:
        raise PoseError(f"{where}: joint {missing[0]!r} has no position; give every joint [x, y]"
                        + (f" ({len(missing)} are missing)" if len(missing) > 1 else ""))
    positions = np.array([finite_point(joints[name], name=f"{where}: joint {name!r}", error=PoseError)
                          for name in skeleton.names])
    return check_pose(skeleton, Pose(positions=positions), where=where)


def pose_to_joints(skeleton: Skeleton, pose: Pose) -> dict[str, list[float]]:
    """The pose as a name -> ``[x, y]`` dict in joint order (for JSON)."""
    return {
        name: [float(x), float(y)]
        for name, (x, y) in zip(skeleton.names, pose.positions, strict=True)
    }


def check_pose(skeleton: Skeleton, pose: Pose, *, where: str = "pose") -> Pose:
    """Raise :class:`PoseError` unless ``pose`` fits ``skeleton``; returns the pose."""
    positions = pose.positions
    if positions.shape != (len(skeleton), 2):
        raise PoseError(
            f"{where}: has {positions.shape[0] if positions.ndim else 0} joint positions but the "
            f"skeleton has {len(skeleton)} joints"
        )
    if not np.all(np.isfinite(positions)):
        row = int(np.flatnonzero(~np.isfinite(positions).all(axis=1))[0])
        raise PoseError(f"{where}: joint {skeleton.names[row]!r} has a non-finite position")
    if np.abs(positions).max() > MAX_COORDINATE:
        row = int(np.abs(positions).max(axis=1).argmax())
        x, y = positions[row]
        raise PoseError(f"{where}: joint {skeleton.names[row]!r} is at ({x:.3g}, {y:.3g}), beyond "
                        f"{MAX_COORDINATE:,.0f} pixels from the origin")
    bones = skeleton.bones
    rest = skeleton.bone_lengths
    posed = np.linalg.norm(positions[bones[:, 1]] - positions[bones[:, 0]], axis=1)
    collapsed = (rest > MIN_BONE_LENGTH) & (posed < MIN_POSED_FRACTION * rest)
    if collapsed.any():
        b = int(np.flatnonzero(collapsed)[0])
        raise PoseError(
            f"{where}: bone {skeleton.bone_names[b]!r} is squashed to {posed[b]:.3g} px "
            f"(rest length {rest[b]:.3g} px); keep it at least {MIN_POSED_FRACTION:.0%} of its rest length"
        )
    return pose


def descendants(skeleton: Skeleton, joint: int) -> NDArray[np.intp]:
    """Indices of every joint below ``joint`` (an index), in parents-first order."""
    below = np.zeros(len(skeleton), dtype=bool)
    for i in range(joint + 1, len(skeleton)):
        p = skeleton.parents[i]
        below[i] = p == joint or (p >= 0 and below[p])
    return np.flatnonzero(below)


def rotate_about(
    skeleton: Skeleton, positions: ArrayLike, joint: str, angle: float, *, scale: float = 1.0
) -> NDArray[np.float64]:
    """Turn everything below ``joint`` (a name) about it by ``angle`` radians, scaled by ``scale``.

    Bends an elbow (rotate about the elbow), raises an arm (about the shoulder). Angles are
    screen angles: positive turns from +x towards +y, clockwise as seen with y down.

    Examples
    --------
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> s = Skeleton.from_joints([("arm", None, (0, 0)), ("hand", "arm", (10, 0))])
    >>> np.round(rotate_about(s, s.positions, "arm", np.pi / 2), 9).tolist()
    [[0.0, 0.0], [0.0, 10.0]]
    """
    j = skeleton.index(joint)
    out = np.array(positions, dtype=float)
    below = descendants(skeleton, j)
    out[below] = transform(out[below], rotation(angle) * scale, about=out[j])
    return out


def carried_pose(before: Skeleton, after: Skeleton, pose: Pose) -> Pose:
    """``pose`` of skeleton ``before`` as a pose of ``after``: the same joints by name, some of them
    moved at rest (the animator placed them better), in ``after``'s joint order.

    A joint that did not move keeps its posed place exactly. One that moved goes where its bone's
    pose carries its new rest place: the turn, stretch and move that take the bone from its
    parent (``after``'s) at rest onto the pose, applied to the new rest place; a root, or a joint
    whose bone had no length at rest, keeps its offset from rest. So a key of the rest pose stays
    the rest pose, and a moved elbow sits as far along a posed arm as it was moved along the arm.

    Raises :class:`PoseError` if ``after`` names a joint ``before`` has not.

    Examples
    --------
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> raised = Pose(np.array([[0.0, 0.0], [0.0, -10.0]]))  # the arm turned up
    >>> longer = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (12, 0))])
    >>> carried_pose(arm, longer, raised).positions.round(9).tolist()
    [[0.0, 0.0], [0.0, -12.0]]
    """
    missing = [name for name in after.names if name not in before.names]
    if missing:
        raise PoseError(f"joint {missing[0]!r} is not in the skeleton the pose was made for")
    order = [before.names.index(name) for name in after.names]
    posed, rest = pose.positions[order], np.asarray(before.positions, dtype=float)[order]
    moved_rest = np.asarray(after.positions, dtype=float)
    out = posed.copy()
    for j in np.flatnonzero((moved_rest != rest).any(axis=1)):
        p = int(after.parents[j])
        bone = complex(*(rest[j] - rest[p])) if p >= 0 else 0j
        if abs(bone) <= MIN_BONE_LENGTH:
            out[j] = posed[j] + (moved_rest[j] - rest[j])
            continue
        # The complex ratio is the turn and stretch taking the rest bone onto the posed one.
        carried = complex(*(posed[j] - posed[p])) / bone * complex(*(moved_rest[j] - rest[p]))
        out[j] = posed[p] + (carried.real, carried.imag)
    return Pose(out)
