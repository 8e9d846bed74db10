"""toonmotion's public library API: the calls every front end makes.

The command line (:mod:`toonmotion.cli`) and the editor parse what the user gave, call one of
these, and report. Each is a thin, documented wrapper; the work sits in the layers below
(``docs/architecture.md``). They are re-exported from the package, so ``toonmotion.rig_image(...)`` works.

>>> import numpy as np
>>> import toonmotion
>>> from toonmotion.samples import sample_character
>>> drawing, skeleton = sample_character()
>>> hero = toonmotion.rig_image(drawing, skeleton=skeleton)
>>> frame = toonmotion.pose_character(hero, toonmotion.rotate_joint(hero, "right_elbow", 0.8))
>>> frame.deformation.U.shape == hero.mesh.V.shape
True
>>> picture = toonmotion.render_pose(hero, frame)
>>> picture.dtype, picture.shape[2]
(dtype('uint8'), 4)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.animation import (
    Animation,
    SameDepthOverlap,
    animate_motion,
    animate_timeline,
    exaggerate,
    same_depth_overlaps,
)
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.animate.motion import Motion
from toonmotion.animate.pose_filter import exaggerate_pose
from toonmotion.animate.timeline import Timeline
from toonmotion.capture.footage import Capture, capture_motion, correct_motion, suggest_joints
from toonmotion.capture.retarget import retarget
from toonmotion.capture.tracker import TrackSettings
from toonmotion.deform.deformer import Deformation, Deformer, DeformSettings
from toonmotion.deform.tuning import TuningEdit, apply_tuning
from toonmotion.errors import SettingsError
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.project import load_project, save_project
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.progress import Progress
from toonmotion.render.frame import fit_view, render_frame
from toonmotion.render.sequence import write_animation
from toonmotion.rig.binding import Correction
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.edits import DepthEdit, apply_edit, redo, region_at, undo
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.rig.skeleton import Skeleton

__all__ = [
    "Animation",
    "Capture",
    "Character",
    "DeformSettings",
    "FilterSettings",
    "Motion",
    "PosedFrame",
    "RigSettings",
    "SameDepthOverlap",
    "TrackSettings",
    "animate_character",
    "correct_regions",
    "set_depth",
    "undo_edits",
    "redo_edits",
    "track_footage",
    "exaggerate",
    "filter_motion",
    "load_project",
    "pose_character",
    "pose_view",
    "render_pose",
    "retarget",
    "rig_image",
    "rotate_joint",
    "same_depth_overlaps",
    "save_project",
    "suggest_joints",
    "write_animation",
]


@dataclass(frozen=True)
class PosedFrame:
    """A character deformed to one pose.

    Attributes
    ----------
    pose : Pose
        The joint positions used (after the single-frame filter, when asked for).
    deformation : Deformation
        ``U`` (the deformed vertices), stage one's result, stage two's iterations and energies.
    """

    pose: Pose
    deformation: Deformation


def rig_image(image: str | Path | NDArray[np.uint8], *, mask: str | Path | NDArray[np.bool_] | None = None,
              skeleton: str | Path | Skeleton | None = None, settings: RigSettings | None = None,
              max_pixels: int | None = None, progress: Progress | None = None) -> Character:
    """Rig a drawing: silhouette, mesh, curve skeleton, animation skeleton and decomposition.

    Parameters
    ----------
    image : path or (h, w, 3|4) uint8
        The drawing. A non-opaque alpha channel is the figure's mask.
    mask : path or (h, w) bool, optional
        The figure (white or opaque pixels); overrides alpha. Without either, the figure is found
        automatically (``settings.segmentation``).
    skeleton : path or Skeleton, optional
        An Animated Drawings ``char_cfg.yaml`` or a toonmotion skeleton ``.json``; without one, a
        skeleton is built along the curve skeleton.
    settings : RigSettings, optional
        Mesh density, segmentation and skeleton options; the defaults suit most drawings.
    max_pixels : int, optional
        Refuse larger images (default :data:`toonmotion.io.image.DEFAULT_MAX_PIXELS`).
    progress : callable, optional
        ``progress(stage, index, count)`` before each rigging stage.

    Returns
    -------
    Character
        The rigged drawing, for :func:`pose_character`, :func:`animate_character` and
        :func:`save_project`.

    Raises
    ------
    ToonmotionError
        A subclass naming what is wrong: an unreadable or too large image, an empty mask, a
        skeleton that does not fit the drawing.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> hero.skeleton.names == skeleton.names, hero.mesh.V.shape[1]
    (True, 2)
    """
    limit = {} if max_pixels is None else {"max_pixels": max_pixels}
    texture = load_image(image, **limit) if isinstance(image, (str, Path)) else image
    size = (texture.shape[1], texture.shape[0])
    figure = load_mask(mask, size=size, **limit) if isinstance(mask, (str, Path)) else mask
    bones = load_skeleton_file(skeleton, image_size=size) if isinstance(skeleton, (str, Path)) else skeleton
    return rig_drawing(texture, mask=figure, skeleton=bones, settings=settings, progress=progress)


def rotate_joint(character: Character, joint: str, angle: float) -> Pose:
    """The rest pose with the bones below ``joint`` turned by ``angle`` radians about it.

    Parameters
    ----------
    character : Character
    joint : str
        A joint of ``character.skeleton``; it stays put and everything below it turns.
    angle : float
        Radians; positive turns from +x towards +y (clockwise on screen, where y points down).

    Returns
    -------
    Pose
        Every joint's position, for :func:`pose_character`.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> pose = rotate_joint(hero, "right_elbow", 0.5)
    >>> moved = np.linalg.norm(pose.positions - hero.skeleton.positions, axis=1) > 1e-9
    >>> [name for name, m in zip(hero.skeleton.names, moved) if m]
    ['right_hand']
    """
    skeleton = character.skeleton
    return Pose(rotate_about(skeleton, skeleton.positions, joint, angle))


def pose_character(
    character: Character | Deformer,
    pose: Pose,
    *,
    edits: Sequence[TuningEdit] = (),
    accel: tuple[float, float] | None = None,
    fixed: Sequence[str] = (),
    root: str | None = None,
    settings: DeformSettings | None = None,
) -> PosedFrame:
    """Deform a character to a pose (needle model, then the joint-area solve), then apply ``edits``.

    Parameters
    ----------
    character : Character or Deformer
        The rigged drawing, or a :class:`Deformer` already built for it: build one when posing
        many times, since building it is the costly step.
    pose : Pose
        Every joint's position, in ``character.skeleton``'s order.
    edits : sequence of TuningEdit, optional
        Fine-tuning sketch curves and drags, in drawing pixels, applied in order.
    accel : (float, float), optional
        An acceleration in pixels at ``root``: the single-frame cartoon filter (thesis 5.2.1)
        first exaggerates the pose as if it moved so.
    fixed : sequence of str, optional
        Joints ``accel`` must not move (feet on the ground).
    root : str, optional
        Where ``accel`` acts; the skeleton's root by default.
    settings : DeformSettings, optional
        Used only when ``character`` is a Character.

    Returns
    -------
    PosedFrame
        The pose used and the deformation (``deformation.U``: the deformed mesh vertices).

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> frame = pose_character(hero, rotate_joint(hero, "right_elbow", 0.8))
    >>> frame.deformation.U.shape == hero.mesh.V.shape
    True
    """
    deformer = character if isinstance(character, Deformer) else Deformer(character, settings)
    if accel is not None:
        pose = exaggerate_pose(deformer.character.skeleton, pose, accel, tuple(fixed), root=root)
    result = apply_tuning(deformer, pose, deformer.deform(pose), tuple(edits))
    return PosedFrame(pose=pose, deformation=result)


def render_pose(
    character: Character,
    frame: PosedFrame,
    *,
    size: tuple[int, int] | None = None,
    background: tuple[int, int, int] | None = None,
    overlays: Sequence[str] = (),
) -> NDArray[np.uint8]:
    """A posed frame as a picture, its view grown to hold the whole figure (:func:`pose_view`).

    Parameters
    ----------
    character : Character
    frame : PosedFrame
        From :func:`pose_character`.
    size : (int, int), optional
        ``(width, height)`` of the picture; by default the view at one pixel per drawing pixel.
    background : (int, int, int), optional
        An opaque RGB background; transparent by default.
    overlays : sequence of str, optional
        Drawn over the figure: any of :data:`toonmotion.render.frame.OVERLAYS` (the mesh, the
        skeleton, ...).

    Returns
    -------
    (H, W, 4) uint8
        RGBA pixels.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> picture = render_pose(hero, pose_character(hero, rotate_joint(hero, "head", 0.3)),
    ...                       size=(120, 160), background=(255, 255, 255))
    >>> picture.shape, bool((picture[..., 3] == 255).all())
    ((160, 120, 4), True)
    """
    return render_frame(character, frame.deformation.U, pose=frame.pose, size=size,
                        view=pose_view(character, frame), background=background, overlays=overlays)


def pose_view(character: Character, frame: PosedFrame) -> tuple[float, float, float, float]:
    """The view :func:`render_pose` draws: the drawing's canvas and the posed figure.

    Parameters
    ----------
    character : Character
    frame : PosedFrame
        From :func:`pose_character`.

    Returns
    -------
    (x0, y0, x1, y1) float
        In drawing pixels; it holds the drawing's own canvas and every deformed vertex.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> x0, y0, x1, y1 = pose_view(hero, pose_character(hero, rotate_joint(hero, "hip", 3.0)))
    >>> (x0, y0) <= (0, 0) and (x1, y1) >= (drawing.shape[1], drawing.shape[0])
    True
    """
    return fit_view(character, [frame.deformation.U])


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
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
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


def track_footage(
    frames: NDArray[np.uint8],
    *,
    joints: tuple[Skeleton, NDArray[np.float64]] | None = None,
    start: int = 0,
    fps: float = 24.0,
    background: tuple[int, int, int] | None = None,
    settings: TrackSettings | None = None,
    earlier: Motion | None = None,
    corrections: Mapping[str, tuple[float, float]] | None = None,
    at: int | None = None,
    progress: Progress | None = None,
) -> Capture:
    """Track a character's joints through footage (thesis ch. 4).

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
        RGB frames (:func:`toonmotion.io.frames.load_frames` reads videos, GIFs and folders).
    joints : (Skeleton, (k, 2) float), optional
        Each joint's position at frame ``start`` and its rectangle's (width, height). Without it,
        joints are suggested from the first frame's figure (:func:`suggest_joints`).
    start : int
        The frame ``joints`` are placed on; tracking runs forwards from it.
    fps : float
        The footage's frame rate, carried into the motion.
    background : (int, int, int), optional
        A flat background colour, to find the figure by when suggesting joints.
    settings : TrackSettings, optional
    earlier : Motion, optional
        A tracking to correct: give the ``corrections`` (joint name to true ``(x, y)``) at frame
        ``at``; tracking resumes there and the frames before it are kept.
    corrections : mapping of str to (float, float), optional
    at : int, optional
    progress : callable, optional
        ``progress(stage, index, count)`` after each frame.

    Returns
    -------
    Capture
        The motion (with each joint's confidence per frame), its first frame and the rectangles'
        angles.

    Raises
    ------
    SettingsError
        ``earlier`` without ``corrections`` or ``at``.
    TrackingError
        No figure to suggest joints from, or joints outside the frame.

    Examples
    --------
    >>> from toonmotion.samples import sample_character_on
    >>> picture, skeleton = sample_character_on("white", scale=0.5)
    >>> frames = np.stack([np.roll(picture, 2 * t, axis=1) for t in range(4)])  # walks right
    >>> sizes = np.full((len(skeleton), 2), 16.0)
    >>> capture = track_footage(frames, joints=(skeleton, sizes))
    >>> np.round(capture.motion.positions[-1, 0] - capture.motion.positions[0, 0]).tolist()
    [6.0, 0.0]
    """
    skeleton, sizes = joints if joints is not None else suggest_joints(frames, colour=background)
    if earlier is None:
        return capture_motion(frames, skeleton, sizes, fps=fps, start=start, settings=settings,
                              progress=progress)
    if at is None or not corrections:
        raise SettingsError("correcting an earlier tracking needs the corrections and the frame they are at")
    return correct_motion(earlier, frames, skeleton, sizes, at, corrections, fps=fps, start=start,
                          settings=settings, progress=progress)


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
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> steps = np.zeros((20, 2, 2)); steps[:, 1, 0] = 10; steps[10:, :, 0] += 30  # a jump right
    >>> moved = filter_motion(Motion(arm, steps, fps=12.0), 1.0).positions[:, 0, 0]
    >>> bool(moved.min() < 0 and moved.max() > 30)  # it winds up and overshoots
    True
    """
    return exaggerate(motion, FilterSettings(strength=strength, sigma=sigma, shift=shift), joints=joints)


def set_depth(character: Character, value: int, *, bone: str | None = None,
              at: tuple[float, float] | None = None, by: int | None = None) -> Character:
    """``character`` with a bone region's depth layer set (thesis 3.5); higher is in front.

    Parameters
    ----------
    character : Character
    value : int
        The depth, within ±1,000,000 (ignored when ``by`` is given).
    bone : str, optional
        The region's bone (named after its child joint).
    at : (float, float), optional
        Instead of ``bone``: the region holding the rest-mesh vertex nearest this point, as a
        click on the drawing picks it.
    by : int, optional
        Change the region's current depth by this much instead of setting ``value``.

    Returns
    -------
    Character
        With the edit applied and recorded (:func:`undo_edits` takes it back); save it with
        :func:`save_project`.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> hero = set_depth(hero, 0, at=tuple(hero.skeleton.positions[7]), by=1)
    >>> int(hero.depth.max()), len(hero.edits)
    (1, 1)
    """
    if by is not None:
        index = region_at(character, at) if at is not None else character.skeleton.bone_names.index(bone)
        value = int(character.depth[index]) + int(by)
    return apply_edit(character, DepthEdit(value=value, bone=bone, at=at))


def correct_regions(character: Character, bone: str, curve: ArrayLike) -> Character:
    """``character`` with every vertex inside a closed ``curve`` attached to ``bone`` (thesis 3.5).

    Parameters
    ----------
    character : Character
    bone : str
        The bone (named after its child joint) the vertices go to.
    curve : sequence of (x, y)
        A closed curve in drawing pixels, at least three points (a lasso).

    Returns
    -------
    Character
        With the correction applied and recorded (:func:`undo_edits` takes it back).

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> x, y = hero.skeleton.positions[hero.skeleton.index("head")]
    >>> lasso = [(x - 9, y - 9), (x + 9, y - 9), (x + 9, y + 9), (x - 9, y + 9)]
    >>> fixed = correct_regions(hero, "neck", lasso)
    >>> bool((fixed.binding.bone != hero.binding.bone).any())
    True
    """
    return apply_edit(character, Correction(curve=np.asarray(curve, dtype=float), bone=bone))


def undo_edits(character: Character, steps: int = 1) -> Character:
    """``character`` with its last ``steps`` region corrections and depth settings taken back.

    Parameters
    ----------
    character : Character
    steps : int
        How many edits, at least 1.

    Returns
    -------
    Character
        The edits taken back can be made again with :func:`redo_edits` until a new edit is made.

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> back = undo_edits(set_depth(hero, 2, bone="head"))
    >>> int(back.depth.max()), len(back.undone)
    (0, 1)
    """
    return undo(character, steps)[0]


def redo_edits(character: Character, steps: int = 1) -> Character:
    """``character`` with its last ``steps`` undone edits made again.

    Parameters
    ----------
    character : Character
    steps : int
        How many, at least 1.

    Returns
    -------
    Character

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> drawing, skeleton = sample_character(scale=0.5)
    >>> hero = rig_image(drawing, skeleton=skeleton)
    >>> again = redo_edits(undo_edits(set_depth(hero, 2, bone="head")))
    >>> int(again.depth.max()), len(again.edits)
    (2, 1)
    """
    return redo(character, steps)[0]
