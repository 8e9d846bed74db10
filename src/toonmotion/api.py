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
from numpy.typing import NDArray

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
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.project import load_project, save_project
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.progress import Progress
from toonmotion.render.frame import fit_view, render_frame
from toonmotion.render.sequence import write_animation
from toonmotion.rig.character import Character, RigSettings
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
    max_pixels : int, optional
        Refuse larger images (default :data:`toonmotion.io.image.DEFAULT_MAX_PIXELS`).
    progress : callable, optional
        ``progress(stage, index, count)`` before each rigging stage.
    """
    limit = {} if max_pixels is None else {"max_pixels": max_pixels}
    texture = load_image(image, **limit) if isinstance(image, (str, Path)) else image
    size = (texture.shape[1], texture.shape[0])
    figure = load_mask(mask, size=size, **limit) if isinstance(mask, (str, Path)) else mask
    bones = load_skeleton_file(skeleton, image_size=size) if isinstance(skeleton, (str, Path)) else skeleton
    return rig_drawing(texture, mask=figure, skeleton=bones, settings=settings, progress=progress)


def rotate_joint(character: Character, joint: str, angle: float) -> Pose:
    """The rest pose with the bones below ``joint`` turned by ``angle`` radians about it."""
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

    ``character`` may be a :class:`Deformer` already built for it (do that when posing many
    times: building one is the costly step). ``accel`` (pixels, at ``root``) with ``fixed`` joints
    first exaggerates the pose with the single-frame cartoon filter (thesis 5.2.1). ``edits`` are
    fine-tuning sketch curves and drags in drawing pixels.
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
    """A posed frame as an ``(H, W, 4)`` RGBA picture, its view grown to hold the whole figure."""
    U = frame.deformation.U
    return render_frame(
        character,
        U,
        pose=frame.pose,
        size=size,
        view=pose_view(character, frame),
        background=background,
        overlays=overlays,
    )


def pose_view(character: Character, frame: PosedFrame) -> tuple[float, float, float, float]:
    """The view :func:`render` draws: the drawing's canvas and the posed figure, in drawing pixels."""
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

    ``exaggeration`` runs the cartoon animation filter over the poses first. For key-frames,
    ``method`` is ``"interpolate"`` (thesis eq. 3.11) or ``"solve"`` (stage two on every frame);
    ``fps`` overrides a motion's frame rate (a timeline carries its own).
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

    ``frames`` are ``(T, H, W, 3)`` uint8 RGB (:func:`toonmotion.io.frames.load_frames`).
    ``joints`` is ``(skeleton, sizes)``: each joint's position at frame ``start`` and its rectangle's
    (width, height); without it joints are suggested from the first frame (on ``background``, a
    flat colour, when given). To correct an ``earlier`` tracking, give the ``corrections`` (joint
    name to true ``(x, y)``) at frame ``at``: tracking resumes there, frames before it are kept.
    """
    skeleton, sizes = joints if joints is not None else suggest_joints(frames, colour=background)
    if earlier is None:
        return capture_motion(
            frames, skeleton, sizes, fps=fps, start=start, settings=settings, progress=progress
        )
    if at is None or not corrections:
        raise ValueError("correcting an earlier tracking needs the corrections and the frame they are at")
    return correct_motion(
        earlier,
        frames,
        skeleton,
        sizes,
        at,
        corrections,
        fps=fps,
        start=start,
        settings=settings,
        progress=progress,
    )


def filter_motion(
    motion: Motion,
    strength: float,
    *,
    sigma: float = 3.0,
    shift: float = 0.0,
    joints: Sequence[str] | None = None,
) -> Motion:
    """The cartoon animation filter on a motion (thesis 5.2): anticipation and follow-through.

    ``strength`` is the filter's ``A`` (about 1 to 2 is lively), ``sigma`` its width in frames and
    ``shift`` a delay in frames. By default the root's path and every bone's angle and length are
    filtered; ``joints`` filters only those joints' paths.
    """
    return exaggerate(motion, FilterSettings(strength=strength, sigma=sigma, shift=shift), joints=joints)
