"""Animating a rigged drawing and exaggerating motion: the calls behind ``animate`` and
``filter``."""

from __future__ import annotations

from collections.abc import Sequence

from toonmotion.animate.animation import (
    Animation,
    animate_motion,
    animate_timeline,
    exaggerate,
)
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.animate.motion import Motion
from toonmotion.animate.timeline import Keyframe, Timeline, make_timeline
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.deform.tuning import TuningEdit
from toonmotion.errors import KeyframeError
from toonmotion.render.sequence import frame_transform
from toonmotion.rig.character import Character
from toonmotion.rig.pose import Pose, carried_pose, check_pose
from toonmotion.rig.skeleton import Skeleton


def animate_character(
    character: Character | Deformer,
    source: Timeline | Motion,
    *,
    settings: DeformSettings | None = None,
    exaggeration: FilterSettings | None = None,
    method: str = "interpolate",
    fps: float | None = None,
) -> Animation:
    """Deform every frame of key-frames (a :class:`Timeline`) or of a :class:`Motion`.

    Parameters
    ----------
    character : Character or Deformer
    source : Timeline or Motion
        Key-frames (:func:`toonmotion.io.pose_json.load_keyframes`), or a motion captured,
        retargeted or read from a file; its skeleton must be ``character``'s.
    settings : DeformSettings, optional
        Used only when ``character`` is a Character.
    exaggeration : FilterSettings, optional
        Runs the cartoon animation filter (thesis 5.2) over the poses first.
    method : {"interpolate", "solve"}
        For key-frames: blend the keys' solved meshes (thesis eq. 3.11), or run stage two on every
        in-between too (slower, steadier on large turns).
    fps : float, optional
        Overrides a motion's frame rate (a timeline carries its own).

    Returns
    -------
    Animation
        Every frame's joints and deformed mesh, for :func:`write_animation`.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> keys = sample_keyframes(hero.skeleton)
    >>> animation = animate_character(hero, keys)
    >>> len(animation.meshes) == keys.keys[-1].frame - keys.keys[0].frame + 1
    True
    """
    deformer = character if isinstance(character, Deformer) else Deformer(character, settings)
    if isinstance(source, Motion):
        return animate_motion(deformer, source, exaggeration=exaggeration, fps=fps)
    return animate_timeline(deformer, source, exaggeration=exaggeration, method=method)


def filter_motion(
    motion: Motion,
    strength: float,
    *,
    sigma: float = 3.0,
    shift: float = 0.0,
    joints: Sequence[str] | None = None,
) -> Motion:
    """The cartoon animation filter on a motion (thesis 5.2): anticipation and follow-through.

    Parameters
    ----------
    motion : Motion
    strength : float
        The filter's ``A``: about 1 to 2 is lively, 0 leaves the motion as it is.
    sigma : float
        The filter's width in frames.
    shift : float
        A delay in frames (positive: the exaggeration lags the motion).
    joints : sequence of str, optional
        Filter only these joints' paths, carrying what hangs below them. By default the root's
        path and every bone's angle and length are filtered.

    Returns
    -------
    Motion
        Same skeleton, frames and fps.

    Raises
    ------
    FilterError
        A width or shift the motion cannot carry, or an unknown joint.

    Examples
    --------
    >>> import numpy as np
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> steps = np.zeros((20, 2, 2)); steps[:, 1, 0] = 10; steps[10:, :, 0] += 30  # a jump right
    >>> moved = filter_motion(Motion(arm, steps, fps=12.0), 1.0).positions[:, 0, 0]
    >>> bool(moved.min() < 0 and moved.max() > 30)  # it winds up and overshoots
    True
    """
    return exaggerate(motion, FilterSettings(strength=strength, sigma=sigma, shift=shift), joints=joints)


def set_key(skeleton: Skeleton, timeline: Timeline | None, frame: int, pose: Pose, *,
            fps: float = 12.0, ease: str = "in-out", edits: Sequence[TuningEdit] | None = None) -> Timeline:
    """``timeline`` with a key pose at ``frame`` (a new one, or replacing that frame's pose).

    Parameters
    ----------
    skeleton : Skeleton
        The character's skeleton; the pose is checked against it.
    timeline : Timeline or None
        The key-frames so far (None: the first key).
    frame : int
        The frame number, from 0 (within the ``frames`` limit).
    pose : Pose
    fps, ease : float, str
        For a first key: the animation's frame rate and easing; later keys keep the timeline's.
    edits : sequence of TuningEdit, optional
        The key's fine-tuning edits (sketch curves, point drags), applied after it is deformed
        and carried through the in-betweens; by default a replaced key keeps its own.

    Returns
    -------
    Timeline

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> keys = set_key(hero.skeleton, None, 0, Pose(hero.skeleton.positions))
    >>> from toonmotion.api import rotate_joint
    >>> keys = set_key(hero.skeleton, keys, 12, rotate_joint(hero, "right_elbow", 1.0))
    >>> [key.frame for key in keys.keys], keys.fps
    ([0, 12], 12.0)
    """
    old = {key.frame: key for key in timeline.keys} if timeline is not None else {}
    if edits is None:
        edits = old[frame].edits if frame in old else ()
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
        raise KeyframeError(f"a key's frame must be a whole number >= 0, got {frame!r}")
    old[frame] = Keyframe(frame, check_pose(skeleton, pose, where=f"key-frame {frame}"), tuple(edits))
    if timeline is not None:
        fps, ease = timeline.fps, timeline.ease
    return make_timeline(skeleton, old.values(), fps=fps, ease=ease)


def delete_key(skeleton: Skeleton, timeline: Timeline, frame: int) -> Timeline | None:
    """``timeline`` without its key at ``frame`` (None when it was the last key).

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> skeleton = sample_rig().skeleton
    >>> delete_key(skeleton, set_key(skeleton, None, 3, Pose(skeleton.positions)), 3) is None
    True

    Parameters
    ----------
    skeleton : Skeleton
    timeline : Timeline
    frame : int
        A frame that has a key.

    Returns
    -------
    Timeline or None
    """
    left = [key for key in timeline.keys if key.frame != frame]
    if len(left) == len(timeline.keys):
        raise KeyframeError(f"there is no key at frame {frame}")
    return make_timeline(skeleton, left, fps=timeline.fps, ease=timeline.ease) if left else None


def move_key(skeleton: Skeleton, timeline: Timeline, frame: int, to: int) -> Timeline:
    """``timeline`` with its key at ``frame`` moved to frame ``to`` (which must be free).

    Parameters
    ----------
    skeleton : Skeleton
    timeline : Timeline
    frame, to : int
        The key's frame, and where it goes.

    Returns
    -------
    Timeline

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> skeleton = sample_rig().skeleton
    >>> [key.frame for key in move_key(skeleton, sample_keyframes(skeleton), 36, 40).keys]
    [0, 6, 12, 18, 24, 30, 40]
    """
    frames = [key.frame for key in timeline.keys]
    if frame not in frames:
        raise KeyframeError(f"there is no key at frame {frame}")
    if to != frame and to in frames:
        raise KeyframeError(f"frame {to} has a key already; delete it first or choose another frame")
    if isinstance(to, bool) or not isinstance(to, int) or to < 0:
        raise KeyframeError(f"a key's frame must be a whole number >= 0, got {to!r}")
    moved = [Keyframe(to, key.pose, key.edits) if key.frame == frame else key for key in timeline.keys]
    return make_timeline(skeleton, moved, fps=timeline.fps, ease=timeline.ease)


def retime(skeleton: Skeleton, timeline: Timeline, *, fps: float | None = None,
           ease: str | None = None) -> Timeline:
    """``timeline`` with another frame rate or easing (the keys stay on their frames).

    Parameters
    ----------
    skeleton : Skeleton
    timeline : Timeline
    fps : float, optional
        Frames per second, 0.01 to 1000.
    ease : str, optional
        ``"linear"``, ``"in-out"``, ``"in"`` or ``"out"``.

    Returns
    -------
    Timeline

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> skeleton = sample_rig().skeleton
    >>> faster = retime(skeleton, sample_keyframes(skeleton), fps=24, ease="linear")
    >>> faster.fps, faster.ease
    (24.0, 'linear')
    """
    return make_timeline(skeleton, timeline.keys, fps=timeline.fps if fps is None else fps,
                         ease=timeline.ease if ease is None else ease)


def carry_keys(before: Skeleton, after: Skeleton, timeline: Timeline) -> Timeline:
    """``timeline``'s key poses, made for skeleton ``before``, carried onto ``after``: the same
    joints, some moved at rest (a drawing rigged again with its joints placed better). A joint
    that did not move keeps its keyed places exactly; one that moved goes where its keyed bone
    carries its new rest place (:func:`~toonmotion.rig.pose.carried_pose`), so a key of the rest
    pose is still the rest pose. Each key keeps its frame and fine-tuning edits.

    Parameters
    ----------
    before, after : Skeleton
        The skeleton the keys were made for, and the new one (the same joint names).
    timeline : Timeline

    Returns
    -------
    Timeline

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> skeleton = sample_rig().skeleton
    >>> higher = skeleton.positions.copy()
    >>> higher[skeleton.index("head")] -= (0, 6)  # the head joint placed 6 px higher
    >>> moved = Skeleton(skeleton.names, skeleton.parents, higher)
    >>> bool((carry_keys(skeleton, moved, sample_keyframes(skeleton)).keys[0].pose.positions == higher).all())
    True
    """
    carried = [Keyframe(key.frame, carried_pose(before, after, key.pose), key.edits) for key in timeline.keys]
    return make_timeline(after, carried, fps=timeline.fps, ease=timeline.ease)


def motion_in_frames(character: Character, animation: Animation, *,
                     size: tuple[int, int] | None = None) -> Motion:
    """The animation's joints in the pixels of the frames :func:`write_animation` writes.

    An animation's motion is in the drawing's pixels (it replays on the character); its frames
    show a view that holds every frame, scaled to ``size``. This is the motion as the frames show
    it: what tracking the frames would find, and what ``lift`` needs beside them.

    Parameters
    ----------
    character : Character
    animation : Animation
        From :func:`animate_character`.
    size : (int, int), optional
        The frames' ``(width, height)``, as given to :func:`write_animation`.

    Returns
    -------
    Motion
        Its skeleton's rest pose and every frame mapped by the same scale and offset.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> hero = sample_rig()
    >>> animation = animate_character(hero, sample_keyframes(hero.skeleton, fps=4.0))
    >>> seen = motion_in_frames(hero, animation, size=(80, 100))
    >>> bool(seen.positions[..., 0].max() < 80 and seen.positions[..., 1].max() < 100)
    True
    """
    scale, offset = frame_transform(character, animation, size=size)
    motion = animation.motion
    skeleton = Skeleton(names=motion.skeleton.names, parents=motion.skeleton.parents.copy(),
                        positions=motion.skeleton.positions * scale + offset)
    return Motion(skeleton, motion.positions * scale + offset, fps=motion.fps)
