"""Animated Drawings character folders: ``texture.png``, ``mask.png`` and ``char_cfg.yaml``.

Meta's Animated Drawings keeps each character in a folder of three files: the drawing
(``texture.png``), the figure's pixels (``mask.png``, white on black) and the skeleton placed on
the drawing (``char_cfg.yaml``, see :mod:`toonmotion.io.char_cfg`). Only the texture is required:
without a mask the figure is found from alpha or the background, without a skeleton one is
built along the curve skeleton (:func:`toonmotion.rig.pipeline.rig_drawing`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import ImageReadError
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.skeleton import Skeleton

TEXTURE = "texture.png"
MASK = "mask.png"
CHAR_CFG = "char_cfg.yaml"


@dataclass(frozen=True, eq=False)
class DrawingFolder:
    """The contents of an Animated Drawings character folder, read.

    Attributes
    ----------
    texture : (h, w, 4) uint8
        The drawing, RGBA (alpha 255 where the file has none).
    mask : (h, w) bool or None
        The figure's pixels, when the folder has ``mask.png``.
    skeleton : Skeleton or None
        The ``char_cfg.yaml`` skeleton, in the drawing's pixels (x right, y down), when given.
    """

    texture: NDArray[np.uint8]
    mask: NDArray[np.bool_] | None
    skeleton: Skeleton | None


def load_drawing_folder(folder: str | Path, *, max_pixels: int | None = None) -> DrawingFolder:
    """Read a character folder: ``texture.png``, and ``mask.png`` and ``char_cfg.yaml`` if present.

    Parameters
    ----------
    folder : str or Path
    max_pixels : int
        Refuse drawings with more pixels than this.

    Returns
    -------
    DrawingFolder

    Raises
    ------
    ImageReadError
        ``folder`` is not a folder or has no ``texture.png``.
    MaskError
        ``mask.png`` is not the drawing's size.
    SkeletonError
        ``char_cfg.yaml`` is malformed or was made for a drawing of another size.
    """
    folder = Path(folder)
    if not (folder / TEXTURE).is_file():
        what = "has no texture.png" if folder.is_dir() else "is not a folder"
        raise ImageReadError(
            f"{folder} {what}; give a character folder holding texture.png (and mask.png, char_cfg.yaml)"
        )
    texture = load_image(folder / TEXTURE, max_pixels=max_pixels)
    size = (texture.shape[1], texture.shape[0])
    mask = load_mask(folder / MASK, size=size, max_pixels=max_pixels) if (folder / MASK).is_file() else None
    cfg = folder / CHAR_CFG
    skeleton = load_skeleton_file(cfg, image_size=size) if cfg.is_file() else None
    return DrawingFolder(texture=texture, mask=mask, skeleton=skeleton)


def rig_drawing_folder(
    folder: str | Path,
    *,
    settings: RigSettings | None = None,
    progress: Callable[[str, int, int], None] | None = None,
) -> Character:
    """Rig the drawing in a character folder with its own mask and skeleton, where given.

    Parameters
    ----------
    folder : str or Path
        Holds ``texture.png``, and optionally ``mask.png`` and ``char_cfg.yaml``.
    settings : RigSettings, optional
    progress : callable, optional
        Called as ``progress(stage, index, count)`` before each rigging stage.

    Returns
    -------
    Character

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.io.char_cfg import save_char_cfg
    >>> from toonmotion.io.image import save_png
    >>> from toonmotion.samples import sample_character
    >>> rgba, skeleton = sample_character()
    >>> folder = Path(tempfile.mkdtemp())
    >>> save_png(folder / "texture.png", rgba)
    >>> save_char_cfg(folder / "char_cfg.yaml", skeleton, (rgba.shape[1], rgba.shape[0]))
    >>> hero = rig_drawing_folder(folder, settings=RigSettings(vertices=300))
    >>> hero.skeleton.names == skeleton.names
    True
    """
    drawing = load_drawing_folder(folder)
    return rig_drawing(drawing.texture, mask=drawing.mask, skeleton=drawing.skeleton, settings=settings,
                       progress=progress)
