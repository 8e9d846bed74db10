"""Rigging a drawing and editing its regions: the library calls behind ``rig``, ``depth``,
``correct``, ``undo``, ``redo`` and the editor's Regions panel."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import EditError
from toonmotion.geometry.arrays import finite_point
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.progress import Progress
from toonmotion.rig.binding import Correction
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.edits import DepthEdit, Edit, apply_edit, redo, region_at, replay, undo
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.skeleton import Skeleton


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
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> hero = set_depth(hero, 0, at=tuple(hero.skeleton.positions[7]), by=1)
    >>> int(hero.depth.max()), len(hero.edits)
    (1, 1)
    """
    if at is not None:
        at = finite_point(at, name="a depth edit's point", error=EditError)
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
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
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
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
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
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> again = redo_edits(undo_edits(set_depth(hero, 2, bone="head")))
    >>> int(again.depth.max()), len(again.edits)
    (2, 1)
    """
    return redo(character, steps)[0]


def rig_again(character: Character, skeleton: Skeleton) -> tuple[Character, list[tuple[Edit, str]]]:
    """Rig ``character``'s drawing again with a new ``skeleton``, keeping its mask and settings,
    and replay its region edits on the new rig (the undone ones stay, to redo).

    Parameters
    ----------
    character : Character
    skeleton : Skeleton
        The new animation skeleton (joints placed, named and parented by the user).

    Returns
    -------
    character : Character
    skipped : list of (edit, str)
        Edits that no longer apply (a correction to a bone that is gone), with the reason.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> joints = [(n, None if p < 0 else hero.skeleton.names[p], tuple(x))
    ...           for n, p, x in zip(hero.skeleton.names, hero.skeleton.parents, hero.skeleton.positions)]
    >>> fewer = Skeleton.from_joints([j for j in joints if not j[0].startswith("left_")])
    >>> again, skipped = rig_again(hero, fewer)
    >>> len(again.skeleton), skipped
    (11, [])
    """
    fresh = rig_drawing(character.texture, mask=character.mask, skeleton=skeleton,
                        settings=character.settings)
    again, skipped = replay(fresh, character.edits)
    return dataclasses.replace(again, undone=character.undone), skipped  # still there to redo
