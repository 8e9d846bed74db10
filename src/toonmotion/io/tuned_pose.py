"""The pose that fine-tuning edits belong to: a pose file, or one key of a key-frames file.

``toonmotion tune`` and the editor read a pose with its edits, add or take back an edit, and write
it back where it came from; :class:`TunedPose` remembers where that is.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from toonmotion.animate.timeline import Keyframe, Timeline
from toonmotion.deform.tuning import TuningEdit
from toonmotion.errors import EditError, SettingsError
from toonmotion.io.pose_json import load_keyframes, load_pose, load_pose_edits, save_keyframes, save_pose
from toonmotion.rig.pose import Pose
from toonmotion.rig.skeleton import Skeleton


@dataclass(frozen=True)
class TunedPose:
    """A pose and its fine-tuning edits, and the file (and key) they are kept in.

    Attributes
    ----------
    path : Path
        The pose file, or the key-frames file when ``key`` is given.
    pose : Pose
    edits : tuple of CurveEdit or DragEdit
        Applied in order after the pose is deformed.
    key : int or None
        The frame number of the key in a key-frames file; None for a pose file.
    timeline : Timeline or None
        The whole key-frames file (to write it back), None for a pose file.
    """

    path: Path
    pose: Pose
    edits: tuple[TuningEdit, ...]
    key: int | None = None
    timeline: Timeline | None = None


def load_tuned_pose(path: str | Path, skeleton: Skeleton, *, key: int | None = None) -> TunedPose:
    """Read the pose of a pose (or skeleton) file, or the key at frame ``key`` of a key-frames file."""
    path = Path(path)
    if key is None:
        return TunedPose(path=path, pose=load_pose(path, skeleton), edits=tuple(load_pose_edits(path)))
    timeline = load_keyframes(path, skeleton)
    frames = [k.frame for k in timeline.keys]
    if key not in frames:
        raise SettingsError(f"{path} has no key at frame {key}; its keys are at {frames}")
    found = timeline.keys[frames.index(key)]
    return TunedPose(path=path, pose=found.pose, edits=tuple(found.edits), key=key, timeline=timeline)


def with_edits(tuned: TunedPose, edits: tuple[TuningEdit, ...]) -> TunedPose:
    """``tuned`` with its edits replaced."""
    return dataclasses.replace(tuned, edits=tuple(edits))


def without_last_edit(tuned: TunedPose) -> tuple[TunedPose, TuningEdit]:
    """``tuned`` with its last edit taken back, and that edit."""
    if not tuned.edits:
        raise EditError(f"{tuned.path} has no edits to undo")
    return with_edits(tuned, tuned.edits[:-1]), tuned.edits[-1]


def save_tuned_pose(tuned: TunedPose, skeleton: Skeleton) -> None:
    """Write ``tuned`` back where it came from (atomically, like every toonmotion file)."""
    if tuned.timeline is None:
        save_pose(tuned.path, skeleton, tuned.pose, tuned.edits)
        return
    keys = [
        Keyframe(k.frame, tuned.pose, tuned.edits) if k.frame == tuned.key else k for k in tuned.timeline.keys
    ]
    save_keyframes(tuned.path, skeleton, dataclasses.replace(tuned.timeline, keys=tuple(keys)))
