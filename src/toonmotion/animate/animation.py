"""An animation of a rigged character: key-frames or a motion in, a deformed mesh per frame out.

This is the one place that strings together what the ``animate`` and ``retarget`` commands and
the editor's timeline do: sample the poses of every frame, optionally exaggerate them with the
cartoon filter, deform every frame, and report where regions at the same depth overlap in the
key-frames.

>>> from toonmotion.animate.cartoon_filter import FilterSettings
>>> from toonmotion.animate.motion import Motion
>>> from toonmotion.rig.skeleton import Skeleton
>>> import numpy as np
>>> bones = Skeleton.from_joints([("a", None, (0, 0)), ("b", "a", (10, 0))])
>>> still = Motion(skeleton=bones, positions=np.tile(bones.positions, (5, 1, 1)), fps=12)
>>> bool(np.allclose(exaggerate(still, FilterSettings(strength=2.0)).positions, still.positions))
True
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.animate.cartoon_filter import FilterSettings, filter_bones, filter_trajectories
from toonmotion.animate.inbetween import METHODS, animate_frames, motion_frames, solve_keys
from toonmotion.animate.motion import Motion, motion_for, motion_from_timeline
from toonmotion.animate.timeline import Keyframe, Timeline
from toonmotion.deform.deformer import Deformation, Deformer
from toonmotion.deform.depth import find_overlaps
from toonmotion.errors import SettingsError
from toonmotion.rig.character import Character


@dataclass(frozen=True)
class Animation:
    """Every frame of an animation, deformed.

    Attributes
    ----------
    motion : Motion
        The joint positions of every frame (after exaggeration, when asked for), (x, y) pixels.
    meshes : tuple of (int, (n, 2) float)
        ``(frame, U)``: the deformed vertices of every frame, in order.
    keys : tuple of Keyframe
        The key-frames the animation was made from (empty for a motion).
    solved : tuple of Deformation
        Each key's own solve (stage one, stage two, its fine-tuning edits); same length as ``keys``.
    """

    motion: Motion
    meshes: tuple[tuple[int, NDArray[np.float64]], ...]
    keys: tuple[Keyframe, ...] = ()
    solved: tuple[Deformation, ...] = ()


@dataclass(frozen=True)
class SameDepthOverlap:
    """Two bone regions that overlap at the same depth in some key-frames.

    ``area`` is the largest overlap in square pixels; ``frames`` the key-frames where it happens.
    """

    bone_a: str
    bone_b: str
    area: float
    frames: tuple[int, ...]


def exaggerate(
    motion: Motion, settings: FilterSettings | None, *, joints: Sequence[str] | None = None
) -> Motion:
    """``motion`` through the cartoon animation filter, or as it is when ``settings`` is None.

    Parameters
    ----------
    motion : Motion
    settings : FilterSettings or None
        The filter's strength, width and shift.
    joints : sequence of str, optional
        Filter only these joints' paths, carrying what hangs below them. By default the root's
        path and every bone's angle and length are filtered (thesis eq. 5.6).

    Returns
    -------
    Motion
        Same skeleton, frames and fps.

    Examples
    --------
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> still = Motion(arm, np.tile(arm.positions, (8, 1, 1)), fps=12.0)
    >>> exaggerate(still, FilterSettings(strength=2.0)).positions.tolist() == still.positions.tolist()
    True
    """
    if settings is None:
        return motion
    if joints is None:
        positions = filter_bones(motion.skeleton, motion.positions, settings)
    else:
        positions = filter_trajectories(motion.skeleton, motion.positions, settings, joints=tuple(joints))
    return Motion(skeleton=motion.skeleton, positions=positions, fps=motion.fps)


def animate_timeline(
    deformer: Deformer,
    timeline: Timeline,
    *,
    exaggeration: FilterSettings | None = None,
    method: str = "interpolate",
) -> Animation:
    """Deform every frame from the first key to the last.

    Parameters
    ----------
    deformer : Deformer
        Built once for the character.
    timeline : Timeline
        Key-frames for the deformer's skeleton.
    exaggeration : FilterSettings, optional
        Run the cartoon filter over the sampled poses; frames then follow the filtered poses.
    method : str
        ``"interpolate"`` (stage two's displacement interpolated between keys, thesis eq. 3.11) or
        ``"solve"`` (stage two on every frame).
    """
    if method not in METHODS:
        raise SettingsError(f"method must be one of {METHODS}, got {method!r}")
    skeleton = deformer.character.skeleton
    motion = exaggerate(motion_from_timeline(skeleton, timeline), exaggeration)
    poses = motion.positions if exaggeration is not None else None
    solved = tuple(solve_keys(deformer, timeline))
    meshes = tuple(animate_frames(deformer, timeline, method=method, keys=list(solved), poses=poses))
    return Animation(motion=motion, meshes=meshes, keys=tuple(timeline.keys), solved=solved)


def animate_motion(
    deformer: Deformer,
    motion: Motion,
    *,
    exaggeration: FilterSettings | None = None,
    fps: float | None = None,
) -> Animation:
    """Deform a pose per frame, each frame warm-started from the one before.

    ``motion`` must name every joint of the deformer's skeleton (it may have more); ``fps``
    overrides its frame rate.
    """
    skeleton = deformer.character.skeleton
    positions = motion_for(skeleton, motion)
    own = Motion(skeleton=skeleton, positions=positions, fps=motion.fps if fps is None else fps)
    own = exaggerate(own, exaggeration)
    return Animation(motion=own, meshes=tuple(motion_frames(deformer, own.positions)))


def same_depth_overlaps(
    character: Character, results: Iterable[tuple[int, NDArray[np.float64]]]
) -> list[SameDepthOverlap]:
    """Pairs of regions at the same depth that overlap in any of ``results``, each pair once.

    A bone is never reported against its own ancestor or descendant: a limb folding over its own
    chain is covered by the depth rule for joint areas, not by depth layers.

    Parameters
    ----------
    character : Character
    results : iterable of (int, (n, 2) float)
        ``(frame, U)`` pairs: the key-frames of an animation, or a single pose.

    Returns
    -------
    list of SameDepthOverlap
        Each overlapping pair once, with its largest area and every frame it overlaps in; give
        one of the two bones another depth (``toonmotion depth``) to settle which is in front.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.rig.pipeline import rig_drawing
    >>> hero = sample_rig()
    >>> same_depth_overlaps(hero, [(0, hero.mesh.V)])  # the rest pose overlaps nothing
    []
    """
    parents = character.skeleton.parents
    found: dict[tuple[str, str], SameDepthOverlap] = {}
    for frame, U in results:
        for o in find_overlaps(character.mesh, character.binding, character.skeleton, U, character.depth):
            if not o.same_depth or _in_one_chain(character, o.bone_a, o.bone_b, parents):
                continue
            key = (o.bone_a, o.bone_b)
            seen = found.get(key)
            found[key] = SameDepthOverlap(
                bone_a=o.bone_a,
                bone_b=o.bone_b,
                area=max(o.area, seen.area if seen else 0.0),
                frames=(*seen.frames, frame) if seen else (frame,),
            )
    return list(found.values())


def _in_one_chain(character: Character, a: str, b: str, parents: NDArray[np.int64]) -> bool:
    """True when bone ``a`` is an ancestor or a descendant of bone ``b`` (bones named by child)."""
    index = character.skeleton.index
    ja, jb = index(a), index(b)
    return _is_ancestor(parents, ja, jb) or _is_ancestor(parents, jb, ja)


def _is_ancestor(parents: NDArray[np.int64], ancestor: int, joint: int) -> bool:
    while joint >= 0:
        joint = int(parents[joint])
        if joint == ancestor:
            return True
    return False
