"""Key-frames on a timeline and the poses between them (thesis 3.6, 6.3d).

Key poses sit at frame numbers; any number of them, in any order on input. A frame between two
keys interpolates their skeletons bone by bone: every root joint moves in a straight line, every
bone turns the short way from one key's angle to the next (slerp of its direction) and its
length changes linearly, so a stretched bone stretches smoothly. Easing reshapes the parameter
within each stretch between two keys.
"""

from dataclasses import dataclass

import numpy as np

from toonmotion.errors import KeyframeError
from toonmotion.geometry.angles import lerp_angle
from toonmotion.rig.pose import Pose, bone_angles, check_pose
from toonmotion.rig.skeleton import MIN_BONE_LENGTH

EASES = ("linear", "in-out", "in", "out")


@dataclass(frozen=True, eq=False)
class Keyframe:
    """A key pose at a frame number, and fine-tuning edits made on its deformed mesh.

    ``edits`` are :mod:`toonmotion.deform.tuning` edits (sketch curves, point drags), applied in
    order after the key is deformed; in-betweens carry them along with stage two's displacement.
    """

    frame: int
    pose: Pose
    edits: tuple = ()


@dataclass(frozen=True, eq=False)
class Timeline:
    """Key-frames in frame order, a frame rate and an easing.

    Attributes
    ----------
    keys : tuple of Keyframe
        Sorted by frame; frame numbers are distinct whole numbers >= 0.
    fps : float
        Frames per second.
    ease : str
        One of :data:`EASES`: how the parameter runs between two keys.
    """

    keys: tuple
    fps: float
    ease: str = "linear"

    @property
    def frame_count(self):
        """Frames from 0 to the last key, inclusive."""
        return self.keys[-1].frame + 1

    @property
    def duration(self):
        """Seconds, from frame 0 to the last key."""
        return (self.frame_count - 1) / self.fps


def make_timeline(skeleton, keys, *, fps=24.0, ease="linear"):
    """Check and sort key-frames; returns a :class:`Timeline`.

    Parameters
    ----------
    skeleton : Skeleton
    keys : sequence of Keyframe
    fps : float
        Frames per second, > 0.
    ease : str
        ``"linear"``, ``"in-out"`` (slow at both keys), ``"in"`` (slow leaving a key) or
        ``"out"`` (slow arriving).
    """
    if ease not in EASES:
        raise KeyframeError(f"ease must be one of {', '.join(EASES)}, got {ease!r}")
    try:
        fps = float(fps)
    except (TypeError, ValueError):
        raise KeyframeError(f"fps must be a number, got {fps!r}") from None
    if not (np.isfinite(fps) and fps > 0):
        raise KeyframeError(f"fps must be a finite number > 0, got {fps}")
    keys = list(keys)
    if not keys:
        raise KeyframeError("there are no key-frames; give at least one key pose")
    frames = []
    for key in keys:
        if isinstance(key.frame, bool) or not isinstance(key.frame, (int, np.integer)) or key.frame < 0:
            raise KeyframeError(f"key-frame numbers must be whole numbers >= 0, got {key.frame!r}")
        frames.append(int(key.frame))
    repeated = sorted({f for f in frames if frames.count(f) > 1})
    if repeated:
        raise KeyframeError(f"frame {repeated[0]} has two key poses; give each frame at most one")
    for key in keys:
        check_pose(skeleton, key.pose, where=f"key-frame {key.frame}")
    keys.sort(key=lambda k: k.frame)
    keys = tuple(Keyframe(int(k.frame), k.pose, tuple(k.edits)) for k in keys)
    return Timeline(keys=keys, fps=fps, ease=ease)


def segment_at(timeline, frame):
    """``(i, t)``: frame lies between keys ``i`` and ``i + 1`` at eased parameter ``t`` in [0, 1).

    Frames before the first key or after the last hold that key (``t = 0``).
    """
    frames = np.array([k.frame for k in timeline.keys])
    if frame <= frames[0]:
        return 0, 0.0
    if frame >= frames[-1]:
        return len(frames) - 1, 0.0
    i = int(np.searchsorted(frames, frame, side="right") - 1)
    t = (frame - frames[i]) / (frames[i + 1] - frames[i])
    return i, ease(t, timeline.ease)


def ease(t, kind):
    """The eased parameter for ``t`` in [0, 1].

    >>> ease(0.5, "in-out"), ease(0.25, "linear")
    (0.5, 0.25)
    """
    if kind == "in-out":
        return t * t * (3 - 2 * t)
    if kind == "in":
        return t * t
    if kind == "out":
        return 1 - (1 - t) * (1 - t)
    return t


def interpolate_pose(skeleton, a, b, t):
    """The pose a fraction ``t`` of the way from pose ``a`` to pose ``b``.

    Roots move linearly; each bone turns the short way (which way an exact half turn goes
    depends on rounding) and its length changes linearly. Bones of zero length in either pose (no
    direction) interpolate their offset instead.
    """
    if t == 0:
        return a
    if t == 1:
        return b
    pa, pb = a.positions, b.positions
    angle_a, length_a = bone_angles(skeleton, pa)
    angle_b, length_b = bone_angles(skeleton, pb)
    angle = lerp_angle(angle_a, angle_b, t)
    length = (1 - t) * length_a + t * length_b
    out = (1 - t) * pa + t * pb  # right for roots and for direction-less bones
    bones = skeleton.bones
    directed = (length_a > MIN_BONE_LENGTH) & (length_b > MIN_BONE_LENGTH)
    row_of_child = {int(c): r for r, c in enumerate(bones[:, 1])}
    for joint in range(len(skeleton)):  # parents come first
        parent = skeleton.parents[joint]
        if parent < 0:
            continue
        r = row_of_child[joint]
        if directed[r]:
            offset = length[r] * np.array([np.cos(angle[r]), np.sin(angle[r])])
        else:
            offset = (1 - t) * (pa[joint] - pa[parent]) + t * (pb[joint] - pb[parent])
        out[joint] = out[parent] + offset
    return Pose(positions=out)


def pose_at(skeleton, timeline, frame):
    """The (interpolated) pose at ``frame``."""
    i, t = segment_at(timeline, frame)
    keys = timeline.keys
    if t == 0:
        return keys[i].pose
    return interpolate_pose(skeleton, keys[i].pose, keys[i + 1].pose, t)
