"""Rigging a drawing, start to finish: mask, silhouette, curve skeleton, skeleton, mesh, binding.

This is the one place the steps are put in order; each step lives in its own module.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion import limits
from toonmotion.errors import MaskError, SkeletonError
from toonmotion.progress import Progress
from toonmotion.rig.auto_skeleton import skeleton_from_curve_skeleton
from toonmotion.rig.binding import decompose
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.edits import Edit, replay
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton
from toonmotion.shape.curve_skeleton import curve_skeleton
from toonmotion.shape.mesh import choose_spacing, left_out, triangulate
from toonmotion.shape.segment import (
    check_mask,
    clean_mask,
    mask_from_alpha,
    segment_foreground,
)
from toonmotion.shape.silhouette import trace_silhouette

STAGES = ("mask", "silhouette", "curve skeleton", "skeleton", "mesh", "binding")

# How far (as a fraction of the figure's bounding-box diagonal, at least _FAR_MIN_PX) a joint
# may lie from the figure before the skeleton is taken to belong to another drawing.
_FAR_FRACTION = 0.1
_FAR_MIN_PX = 8.0
_BASE_TOLERANCE = 1.0
# A mesh whose outline leaves out more of the figure than this is too coarse for its thin parts
# (the shared drawings: 0.2-0.8% at 1,500 vertices, 1-2% at 300, 6-25% at 120 and 10-26% at 50).
LEFT_OUT_WARNING = 0.05


def rig_drawing(
    texture: ArrayLike,
    *,
    mask: ArrayLike | None = None,
    skeleton: Skeleton | None = None,
    settings: RigSettings | None = None,
    progress: Progress | None = None,
) -> Character:
    """Rig a drawing.

    Parameters
    ----------
    texture : (h, w, 4) or (h, w, 3) uint8
        The drawing. A non-opaque alpha channel is the mask.
    mask : (h, w) bool, optional
        The figure's pixels; overrides alpha. Without either, the figure is segmented from
        its background automatically.
    skeleton : Skeleton, optional
        The animation skeleton; built from the curve skeleton when not given.
    settings : RigSettings, optional
    progress : callable, optional
        Called as ``progress(stage, index, count)`` before each of :data:`STAGES`.

    Returns
    -------
    Character
    """
    settings = settings or RigSettings()
    asked = settings.vertices
    if asked is not None:  # before any work: a mesh asked for too fine is refused at once
        limits.check("mesh_vertices", asked, f"the mesh asked for, {asked:,} vertices,", hint="ask for fewer")
    report = progress or (lambda stage, index, count: None)
    rgba = _as_rgba(texture)

    report("mask", 0, len(STAGES))
    figure = _figure_mask(rgba, mask, settings)

    report("silhouette", 1, len(STAGES))
    silhouette = trace_silhouette(figure, tolerance=settings.tolerance or _BASE_TOLERANCE)

    report("curve skeleton", 2, len(STAGES))
    cskel = curve_skeleton(figure, prune=settings.prune)

    report("skeleton", 3, len(STAGES))
    if skeleton is None:
        skeleton = skeleton_from_curve_skeleton(cskel, max_bone=settings.max_bone)
    else:
        check_skeleton_on_figure(skeleton, figure)

    report("mesh", 4, len(STAGES))
    refine = _meeting_joints(skeleton) if settings.refine_joints else None
    spacing = settings.spacing
    if spacing is None:
        target = settings.vertices or 1500
        spacing = choose_spacing(silhouette, target, refine_points=refine)
        if settings.tolerance is None and spacing / 10 > _BASE_TOLERANCE:
            silhouette = trace_silhouette(figure, tolerance=spacing / 10)
            spacing = choose_spacing(silhouette, target, refine_points=refine)
    elif settings.tolerance is None and spacing / 10 > _BASE_TOLERANCE:
        silhouette = trace_silhouette(figure, tolerance=spacing / 10)
    mesh = triangulate(silhouette, spacing=spacing, refine_points=refine)
    limits.check("mesh_vertices", len(mesh.V), f"the mesh, {len(mesh.V):,} vertices,",
                 hint="mesh it coarser (a larger spacing)")

    report("binding", 5, len(STAGES))
    binding = decompose(mesh, skeleton, figure, rule=settings.decomposition)
    return Character(texture=rgba, mask=figure, silhouette=silhouette, curve_skeleton=cskel,
                     skeleton=skeleton, mesh=mesh, binding=binding, settings=settings)


def remesh(
    character: Character, settings: RigSettings, *, progress: Progress | None = None
) -> tuple[Character, list[tuple[Edit, str]]]:
    """Rig ``character``'s drawing again with new ``settings`` (a finer or coarser mesh), keeping
    its mask and skeleton, and replay its edits on the new mesh.

    Returns
    -------
    character : Character
    skipped : list of (edit, str)
        Edits that no longer apply, with the reason (see :func:`toonmotion.rig.edits.replay`).
    """
    fresh = rig_drawing(character.texture, mask=character.mask, skeleton=character.skeleton,
                        settings=settings, progress=progress)
    return replay(fresh, character.edits)


def check_skeleton_on_figure(skeleton: Skeleton, mask: NDArray[np.bool_]) -> None:
    """Raise :class:`SkeletonError` when a joint lies far from the figure."""
    from scipy import ndimage as ndi

    rows, cols = np.nonzero(mask)
    diagonal = float(np.hypot(np.ptp(rows) + 1, np.ptp(cols) + 1))
    limit = max(_FAR_MIN_PX, _FAR_FRACTION * diagonal)
    h, w = mask.shape
    to_figure = ndi.distance_transform_edt(~mask)
    for name, (x, y) in zip(skeleton.names, skeleton.positions, strict=True):
        xi, yi = int(np.clip(np.rint(x), 0, w - 1)), int(np.clip(np.rint(y), 0, h - 1))
        off_image = float(np.hypot(x - xi, y - yi))
        distance = to_figure[yi, xi] + off_image
        if distance > limit:
            raise SkeletonError(
                f"joint {name!r} at ({x:.0f}, {y:.0f}) is {distance:.0f} px from the figure "
                f"(more than {limit:.0f} px); is the skeleton for this drawing and at its scale?"
            )


def _as_rgba(texture: ArrayLike) -> NDArray[np.uint8]:
    texture = np.asarray(texture)
    if texture.ndim != 3 or texture.shape[2] not in (3, 4) or texture.dtype != np.uint8:
        raise ValueError("texture must be an (h, w, 3|4) uint8 array")
    if texture.shape[2] == 3:
        alpha = np.full(texture.shape[:2] + (1,), 255, dtype=np.uint8)
        texture = np.concatenate([texture, alpha], axis=2)
    return np.ascontiguousarray(texture)


def _figure_mask(texture: NDArray[np.uint8], mask: ArrayLike | None, settings: RigSettings
                 ) -> NDArray[np.bool_]:
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != texture.shape[:2]:
            raise MaskError(
                f"the mask is {mask.shape[1]}x{mask.shape[0]} but the drawing is "
                f"{texture.shape[1]}x{texture.shape[0]}; give a mask of the same size"
            )
        what = "mask"
    else:
        mask = mask_from_alpha(texture[..., 3])
        what = "alpha channel"
        if mask is None:
            mask = segment_foreground(texture[..., :3], method=settings.segmentation)
            what = "figure found on the background"
    check_mask(mask, what=what)
    return clean_mask(mask, min_fraction=settings.min_part, largest_only=settings.largest_only)


def _meeting_joints(skeleton):
    """Positions of joints where two or more bones of non-zero length meet."""
    bones = skeleton.bones[skeleton.bone_lengths > MIN_BONE_LENGTH]
    degree = np.bincount(bones.ravel(), minlength=len(skeleton))
    return skeleton.positions[degree >= 2]


def coarse_mesh_warning(character: Character) -> str | None:
    """A warning when ``character``'s mesh leaves out more than :data:`LEFT_OUT_WARNING` of its
    figure (:func:`~toonmotion.shape.mesh.left_out`): what is left out does not show when posed."""
    share = left_out(character.mesh, character.mask)
    if share <= LEFT_OUT_WARNING:
        return None
    return (f"the mesh leaves out {share:.0%} of the figure (parts thinner than its "
            f"{character.mesh.spacing:.0f} px spacing are cut off, and do not show when posed); "
            f"mesh it finer (more --vertices)")
