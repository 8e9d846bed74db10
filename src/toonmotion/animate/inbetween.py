"""In-betweens: a deformed mesh for every frame of a timeline (thesis 3.6, eq. 3.11).

Eq. 3.11 splits each in-between into the skeleton-driven part and the stage-two part: the
skeleton is interpolated (bones turn by slerp, see ``timeline.interpolate_pose``) and deformed
by the needle model, and stage two's displacement (final minus stage-one position of every
vertex) is interpolated linearly between the two keys. We interpolate that displacement in each
vertex's bone frame rather than the image frame, so a displacement on a limb that swings round
swings with it; the thesis' three-frame scheme is the case of two keys. Key frames are the
keys' own solved meshes, exactly.

``method="solve"`` instead runs stage two on every frame, warm-started from the previous one:
slower, but every in-between is itself a minimum of the stage-two energy.

Fine-tuning edits on a key (sketch curves, drags) are part of its mesh, so in-betweens carry
them in and out with the rest of stage two's displacement. When the frames' poses are replaced
(the cartoon filter's exaggerated poses), each frame takes its new pose's stage one plus the
displacement interpolated from the keys, turned with the new pose's bones.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.timeline import Timeline, interpolate_pose, segment_at
from toonmotion.deform.tuning import apply_tuning
from toonmotion.errors import SettingsError
from toonmotion.rig.kinematics import bone_angles, rotate
from toonmotion.rig.pose import Pose

if TYPE_CHECKING:
    from toonmotion.deform.deformer import Deformation, Deformer

METHODS = ("interpolate", "solve")


def solve_keys(deformer: Deformer, timeline: Timeline) -> list[Deformation]:
    """Deform every key pose (stage one and two, then its edits), each warm-started from the
    one before."""
    results, previous = [], None
    for key in timeline.keys:
        previous = deformer.deform(key.pose, previous=previous)
        results.append(apply_tuning(deformer, key.pose, previous, key.edits))
    return results


def motion_frames(
    deformer: Deformer, positions: NDArray[np.float64]
) -> Iterator[tuple[int, NDArray[np.float64]]]:
    """Yield ``(frame, U)`` for a pose per frame (``(T, k, 2)``, a motion), each frame solved
    warm-started from the one before."""
    previous = None
    for frame, P in enumerate(positions):
        previous = deformer.deform(Pose(P), previous=previous)
        yield frame, previous.U


def animate_frames(
    deformer: Deformer,
    timeline: Timeline,
    *,
    method: str = "interpolate",
    keys: list[Deformation] | None = None,
    poses: ArrayLike | None = None,
) -> Iterator[tuple[int, NDArray[np.float64]]]:
    """Yield ``(frame, U)`` for every frame from 0 to the last key.

    Parameters
    ----------
    deformer : Deformer
    timeline : Timeline
    method : str
        ``"interpolate"`` (eq. 3.11) or ``"solve"`` (stage two on every frame).
    keys : list of Deformation, optional
        The keys already solved by :func:`solve_keys`.
    poses : (frame_count, k, 2) float, optional
        Replacement joint positions for every frame (e.g. exaggerated by the cartoon filter);
        by default each frame's pose is interpolated from the keys.

    Yields
    ------
    frame : int
    U : (n, 2) float
        The deformed vertices.
    """
    if method not in METHODS:
        raise SettingsError(f"the in-between method must be one of {', '.join(METHODS)}, got {method!r}")
    if poses is not None:
        poses = np.asarray(poses, dtype=float)
        expected = (timeline.frame_count, len(deformer.character.skeleton), 2)
        if poses.shape != expected:
            raise SettingsError(f"replacement poses must have shape {expected}, got {poses.shape}")
    keys = solve_keys(deformer, timeline) if keys is None else keys
    return _frames(deformer, timeline, method, keys, poses)


def _frames(deformer, timeline, method, keys, poses):
    skeleton = deformer.character.skeleton
    bone = deformer.needles.bone
    rest_angle, _ = bone_angles(skeleton, skeleton.positions)
    local = [_turn(solved.U, solved.stage_one, bone, -_bone_turn(skeleton, key.pose, rest_angle))
             for solved, key in zip(keys, timeline.keys, strict=True)]
    previous = None
    for frame in range(timeline.frame_count):
        i, t = segment_at(timeline, frame)
        if t == 0 and poses is None:
            previous = keys[i]
            yield frame, keys[i].U
            continue
        if poses is not None:
            pose = Pose(poses[frame])
        else:
            pose = interpolate_pose(skeleton, timeline.keys[i].pose, timeline.keys[i + 1].pose, t)
        if method == "solve":
            previous = deformer.deform(pose, previous=previous)
            yield frame, previous.U
            continue
        U1 = deformer.stage_one(pose)
        displacement = local[i] if t == 0 else (1 - t) * local[i] + t * local[i + 1]
        yield frame, U1 + rotate(displacement, _bone_turn(skeleton, pose, rest_angle)[bone])


def _bone_turn(skeleton, pose, rest_angle):
    """How far each bone has turned from rest in ``pose`` (radians, ``(b,)``)."""
    angle, _ = bone_angles(skeleton, pose.positions)
    return angle - rest_angle


def _turn(U, U1, bone, angle):
    """Stage two's displacement ``U - U1`` turned by each vertex's bone angle, ``(n, 2)``."""
    return rotate(U - U1, angle[bone])
