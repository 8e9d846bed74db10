"""Retargeting a captured motion onto another character's skeleton (thesis 4.5, eq. 4.7-4.8).

Each bone of the target copies the captured bone's changes from frame to frame: its length is
multiplied by the captured length ratio ``l_t / l_{t-1}`` and its angle turned by the captured
increment ``a_t - a_{t-1}`` (eq. 4.7-4.8). Summed over the frames these telescope to

    l'_t = l'_0 * l_t / l_0,        a'_t = a'_0 + (a_t - a_0),

which is how it is computed here (no error builds up frame by frame), with the captured angles
unwrapped along time first so a bone turning through +-pi keeps turning the same way. Frame 0 of
the result is the target's rest pose: the thesis asks that the target be drawn in about the
pose of the first captured frame.

Choices where the thesis leaves them open:

- **Which bones match.** A target joint takes the captured joint of the same name, or the one
  ``joint_map`` names. A target bone follows the captured bone between the captured joints of
  its two ends; those must be parent and child in the capture, or the motion and the target do
  not match (:class:`MotionError`). A target bone whose ends are not both captured keeps its
  rest angle relative to its parent bone and its rest length: it turns with what it hangs from.
- **Bones seen end-on.** A captured bone may foreshorten to nothing; its target bone keeps at
  least :data:`SHORTEST` of its length, so every frame can be posed.
- **Roots.** A root of the target (a forest is allowed: a hat tracked apart from a man) moves
  by its captured joint's displacement from frame 0, scaled by the ratio of the two figures'
  sizes (the summed lengths of the matched bones, target over capture), so a smaller character
  jumps proportionally lower. A root with no captured joint stays put.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from toonmotion.animate.motion import Motion
from toonmotion.errors import MotionError
from toonmotion.rig.kinematics import bone_angles, positions_from_bones
from toonmotion.rig.skeleton import Skeleton

# Captured bones shorter than this (px) at frame 0 keep the target's length.
_MIN_LENGTH = 1e-6
# A target bone is drawn at least this fraction of its length. A captured bone seen end-on (a
# forearm pointing at the camera) squashes to nothing, which no drawing can be posed to (the
# needle model divides by the stretch, rig.pose.MIN_POSED_FRACTION): the zombie walk retargeted
# onto char2 failed at frame 137 of 450 with "bone 'right_elbow' is squashed to 1 px". Kept at
# twice that fraction (4%), the frame posed, but the forearm's drawing was torn into spikes; at a
# quarter it is drawn short and whole, as an animator would draw a limb pointing at the viewer.
SHORTEST = 0.25


def retarget(motion: Motion, skeleton: Skeleton, *, joint_map: Mapping[str, str] | None = None) -> Motion:
    """Replay ``motion`` on ``skeleton`` (the target's rest pose at frame 0).

    Parameters
    ----------
    motion : Motion
        The captured motion; its skeleton names its joints and parents.
    skeleton : Skeleton
        The target character's skeleton, in its rest pose.
    joint_map : dict, optional
        Target joint name -> captured joint name, for joints named differently; joints not in
        it match by name.

    Returns
    -------
    Motion
        For ``skeleton``, at the captured frame rate: each target bone turns as its captured
        bone does and keeps its own length; the root follows the captured root's path.

    Raises
    ------
    MotionError
        No bone of the target matches a bone of the motion.

    Examples
    --------
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> raised = np.array([[[0, 0], [10, 0]], [[0, 0], [0, -10]]], dtype=float)
    >>> long_arm = Skeleton.from_joints([("shoulder", None, (50, 50)), ("hand", "shoulder", (80, 50))])
    >>> retarget(Motion(arm, raised, fps=12.0), long_arm).positions[-1].round(6).tolist()
    [[50.0, 50.0], [50.0, 20.0]]
    """
    source = motion.skeleton
    match = _match_joints(source, skeleton, joint_map or {})
    followed = _followed_bones(source, skeleton, match)
    if not any(f is not None for f in followed):
        raise MotionError(
            "no bone of the target matches a bone of the motion; name the target's joints as the "
            f"motion does ({', '.join(source.names)}) or give a joint map"
        )
    S = motion.positions
    angle, length = bone_angles(source, S)
    angle = np.unwrap(angle, axis=0)
    rest_angle, rest_length = bone_angles(skeleton, skeleton.positions)
    T = len(S)
    turn = np.zeros((T, len(rest_angle)))  # each target bone's turn from rest
    stretch = np.ones((T, len(rest_angle)))
    for b, f in enumerate(followed):
        if f is not None:
            turn[:, b] = angle[:, f] - angle[0, f]
            if length[0, f] > _MIN_LENGTH:  # a captured bone of no length has no ratio to copy
                stretch[:, b] = np.maximum(length[:, f] / length[0, f], SHORTEST)
    scale = _size_ratio(rest_length, length[0], followed)
    return Motion(skeleton=skeleton, positions=_pose_frames(skeleton, S, match, turn, stretch, scale,
                                                            rest_angle, rest_length, followed),
                  fps=motion.fps)


def _match_joints(source, target, joint_map):
    unknown = [t for t in joint_map if t not in target.names]
    if unknown:
        raise MotionError(f"the joint map names {unknown[0]!r}, which the target does not have; its joints "
                          f"are: {', '.join(target.names)}")
    missing = [s for s in joint_map.values() if s not in source.names]
    if missing:
        raise MotionError(f"the joint map names {missing[0]!r}, which the motion does not have; its joints "
                          f"are: {', '.join(source.names)}")
    match = {}
    for j, name in enumerate(target.names):
        other = joint_map.get(name, name)
        if other in source.names:
            match[j] = source.names.index(other)
    return match


def _followed_bones(source, target, match):
    """For each target bone, the index of the captured bone it follows, or None."""
    source_bone = {int(c): r for r, (p, c) in enumerate(source.bones)}
    followed = []
    for parent, child in target.bones:
        if parent in match and child in match:
            r = source_bone.get(match[child])
            if r is None or source.bones[r][0] != match[parent]:
                raise MotionError(
                    f"the target's bone {target.names[parent]} -> {target.names[child]} has no matching "
                    f"bone in the motion ({source.names[match[parent]]} is not the parent of "
                    f"{source.names[match[child]]} there); map the joints so bones match"
                )
            followed.append(r)
        else:
            followed.append(None)
    return followed


def _size_ratio(rest_length, source_length, followed):
    pairs = [(rest_length[b], source_length[f]) for b, f in enumerate(followed) if f is not None]
    target_size, source_size = (sum(v) for v in zip(*pairs, strict=True))
    return target_size / source_size if source_size > 1e-9 else 1.0


def _pose_frames(target, S, match, turn, stretch, scale, rest_angle, rest_length, followed):
    T, k = len(S), len(target)
    roots = np.empty((T, k, 2))  # only the root rows are filled and used
    for j in np.flatnonzero(target.parents < 0):
        moved = (S[:, match[j]] - S[0, match[j]]) * scale if j in match else 0.0
        roots[:, j] = target.positions[j] + moved
    angle = rest_angle + turn  # (T, b); unmatched bones are set below
    total_turn = np.zeros((T, k))  # how far each joint's bone frame has turned, for unmatched children
    for b, (parent, child) in enumerate(target.bones):  # parents come first
        if followed[b] is None:
            angle[:, b] = rest_angle[b] + total_turn[:, parent]
        total_turn[:, child] = angle[:, b] - rest_angle[b]
    # A bone not turned or stretched on a frame keeps its rest offset exactly (rebuilding it from
    # its angle and length rounds differently from one maths library to another).
    parent, child = target.bones.T
    rest = target.positions[child] - target.positions[parent]
    still = (angle == rest_angle) & (stretch == 1)
    return positions_from_bones(target, roots, angle, rest_length * stretch, offsets=rest, given=still)
