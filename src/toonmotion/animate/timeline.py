"""Key-frames on a timeline and the poses between them (thesis 3.6, 6.3d).

Key poses sit at frame numbers; any number of them, in any order on input. A frame between two
keys interpolates their skeletons bone by bone: every root joint moves in a straight line, every
bone turns the short way from one key's angle to the next (slerp of its direction) and its
length changes linearly, so a stretched bone stretches smoothly. Easing reshapes the parameter
within each stretch between two keys.
"""

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from toonmotion import limits
from toonmotion.deform.tuning import CurveEdit, DragEdit, TuningEdit
from toonmotion.errors import KeyframeError
from toonmotion.geometry.angles import lerp_angle
from toonmotion.geometry.arrays import frame_rate
from toonmotion.rig.kinematics import bone_angles, positions_from_bones
from toonmotion.rig.pose import Pose, check_pose
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

EASES = ("linear", "in-out", "in", "out")


@dataclass(frozen=True, eq=False)
class Keyframe:
    """A key pose at a frame number, and fine-tuning edits made on its deformed mesh.

    ``edits`` are :mod:`toonmotion.deform.tuning` edits (sketch curves, point drags), applied in
    order after the key is deformed; in-betweens carry them along with stage two's displacement.

    Construction raises ``TypeError`` unless ``pose`` is a :class:`Pose` and every edit a
    ``CurveEdit`` or ``DragEdit``. The frame number is checked where key-frames are gathered,
    by :class:`Timeline` (and :func:`make_timeline`, whose caller names the file it read).
    """

    frame: int
    pose: Pose
    edits: tuple[TuningEdit, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.pose, Pose):
            raise TypeError(f"a key-frame's pose must be a Pose, got {type(self.pose).__name__}")
        edits = tuple(self.edits)
        if not all(isinstance(edit, CurveEdit | DragEdit) for edit in edits):
            raise TypeError("a key-frame's edits must be CurveEdit or DragEdit objects")
        object.__setattr__(self, "edits", edits)


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

    Construction raises :class:`KeyframeError` unless that holds and there is at least one
    key; :func:`make_timeline` sorts and checks key-frames against a skeleton first.
    """

    keys: tuple[Keyframe, ...]
    fps: float
    ease: str = "linear"

    def __post_init__(self) -> None:
        keys = tuple(self.keys)
        if not all(isinstance(key, Keyframe) for key in keys):
            raise TypeError("a timeline's keys must be Keyframe objects")
        if not keys:
            raise KeyframeError("there are no key-frames; give at least one key pose")
        for key in keys:
            if isinstance(key.frame, bool) or not isinstance(key.frame, int | np.integer) or key.frame < 0:
                raise KeyframeError(f"key-frame numbers must be whole numbers >= 0, got {key.frame!r}")
        frames = [int(key.frame) for key in keys]
        if any(b <= a for a, b in zip(frames, frames[1:], strict=False)):
            raise KeyframeError(f"a timeline's keys must be in frame order, each frame once; got {frames}")
        if self.ease not in EASES:
            raise KeyframeError(f"ease must be one of {', '.join(EASES)}, got {self.ease!r}")
        object.__setattr__(self, "keys", keys)
        object.__setattr__(self, "fps", frame_rate(self.fps, error=KeyframeError))
        limits.check("frames", frames[-1] + 1, f"the last key-frame's number, {frames[-1]}, plus one",
                     hint="number the keys from 0 at the animation's frame rate")

    @property
    def frame_count(self) -> int:
        """Frames from 0 to the last key, inclusive."""
        return int(self.keys[-1].frame) + 1

    @property
    def duration(self) -> float:
        """Seconds, from frame 0 to the last key."""
        return (self.frame_count - 1) / self.fps


def make_timeline(
    skeleton: Skeleton, keys: Iterable[Keyframe], *, fps: float = 24.0, ease: str = "linear"
) -> Timeline:
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
    fps = frame_rate(fps, error=KeyframeError)
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


def segment_at(timeline: Timeline, frame: int) -> tuple[int, float]:
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


def ease(t: float, kind: str) -> float:
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


def interpolate_pose(skeleton: Skeleton, a: Pose, b: Pose, t: float) -> Pose:
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
    roots = pa + t * (pb - pa)  # only its root rows are used
    parent, child = skeleton.bones.T
    offset_a, offset_b = pa[child] - pa[parent], pb[child] - pb[parent]
    offsets = offset_a + t * (offset_b - offset_a)
    directed = (length_a > MIN_BONE_LENGTH) & (length_b > MIN_BONE_LENGTH)
    # A bone the same in both keys keeps its offset exactly (not rebuilt from its angle and length,
    # which rounds differently from one maths library to another).
    same = np.all(offset_a == offset_b, axis=1)
    positions = positions_from_bones(skeleton, roots, angle, length, offsets=offsets, given=~directed | same)
    return Pose(positions=positions)


def pose_at(skeleton: Skeleton, timeline: Timeline, frame: int) -> Pose:
    """The (interpolated) pose at ``frame``."""
    i, t = segment_at(timeline, frame)
    keys = timeline.keys
    if t == 0:
        return keys[i].pose
    return interpolate_pose(skeleton, keys[i].pose, keys[i + 1].pose, t)
