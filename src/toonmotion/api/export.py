"""Exporting an animation into the formats other tools read: the call behind ``export``.

Two kinds of export:

- **rigs**, which replay the animation in another tool from the drawing itself: binary glTF
  (``.glb``: game engines, Blender, three.js) and Spine 4.2 JSON (with its atlas and page image).
  Both reproduce toonmotion's frames: stage one as skinned bones, stage two as per-frame
  offsets (morph targets, deform timelines).
- **pictures**, rendered frames: a sprite sheet (one PNG and a JSON atlas in TexturePacker's hash
  layout, which Phaser, PixiJS and Godot's importers load), APNG, animated WebP and WebM (VP9)
  keeping partial transparency, and the GIF, MP4 and PNG frames ``animate`` writes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from toonmotion.animate.animation import Animation
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import ExportError
from toonmotion.io.exchange.drawing_gltf import PIXELS_PER_METRE, save_animation_glb
from toonmotion.io.exchange.drawing_rig import drawing_rig
from toonmotion.io.exchange.spine_json import save_spine
from toonmotion.io.exchange.sprite_sheet import save_sprite_sheet
from toonmotion.io.video import animation_format
from toonmotion.progress import Progress
from toonmotion.render.frame import natural_size
from toonmotion.render.sequence import animation_view, render_animation, write_animation
from toonmotion.rig.character import Character

# Every format, with the file names it takes.
FORMATS = {
    "glb": "a .glb file (binary glTF 2.0)",
    "spine": "a .json file (Spine 4.2; its .atlas and .png are written beside it)",
    "sheet": "a .json file (the sprite sheet's atlas; its .png is written beside it)",
    "apng": "a .apng or .png file",
    "webp": "a .webp file",
    "webm": "a .webm file",
    "gif": "a .gif file",
    "mp4": "a .mp4 file",
    "png": "a folder or a pattern like frames/f_%04d.png",
}
RIGS = ("glb", "spine")


@dataclass(frozen=True)
class Exported:
    """What an export wrote.

    Attributes
    ----------
    format : str
        One of :data:`FORMATS`.
    frames : int
    files : tuple of Path
        Every file written (a Spine export writes three, a sprite sheet two).
    size : (int, int) or None
        The pictures' ``(width, height)``; None for a rig.
    """

    format: str
    frames: int
    files: tuple[Path, ...]
    size: tuple[int, int] | None = None


def export_format(path: str | os.PathLike[str], format: str | None = None) -> str:
    """The format an export to ``path`` writes: ``format`` if given (checked against the path),
    else the one its name asks for.

    Parameters
    ----------
    path : str or Path
        The file (or folder) an export would write.
    format : str, optional
        One of :data:`FORMATS`.

    Returns
    -------
    str
        One of :data:`FORMATS`.

    Raises
    ------
    ExportError
        An unknown format, a name the format cannot take, or a ``.json`` without a format (a
        Spine skeleton and a sprite sheet's atlas are both JSON).

    Examples
    --------
    >>> [export_format(p) for p in ("hero.glb", "hero.webm", "hero.apng", "frames")]
    ['glb', 'webm', 'apng', 'png']
    >>> export_format("hero.json", "spine")
    'spine'
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if format is not None and format not in FORMATS:
        raise ExportError(f"unknown export format {format!r}; give one of {', '.join(FORMATS)}")
    if suffix == ".json" or format in ("spine", "sheet"):
        if format is None:
            raise ExportError(f"{path.name} could be a Spine skeleton or a sprite sheet's atlas: "
                              "give --format spine or --format sheet")
        if suffix != ".json":
            raise ExportError(f"a {format} export is {FORMATS[format]}, not {path.name}")
        return format
    if suffix == ".glb" or format == "glb":
        if suffix != ".glb" or format not in (None, "glb"):
            raise ExportError(f"a {format or 'glb'} export is {FORMATS[format or 'glb']}, not {path.name}")
        return "glb"
    try:
        kind = animation_format(path)
    except ExportError:
        raise ExportError(f"cannot export to {path.name}: give .glb, .json with --format spine or sheet, "
                          ".apng (or .png), .webp, .webm, .gif, .mp4, or a folder for PNG frames") from None
    if format is not None and format != kind:
        raise ExportError(f"a {format} export is {FORMATS[format]}, not {path.name}")
    return kind


def export_animation(
    path: str | os.PathLike[str],
    character: Character,
    animation: Animation,
    *,
    format: str | None = None,
    settings: DeformSettings | None = None,
    size: tuple[int, int] | None = None,
    background: tuple[int, int, int] | None = None,
    padding: int = 2,
    trim: bool = True,
    max_size: int = 4096,
    progress: Progress | None = None,
) -> Exported:
    """Write ``animation`` of ``character`` as ``format`` (default: as ``path``'s name asks).

    Parameters
    ----------
    path : str or Path
        The file (or folder) to write; see :data:`FORMATS`.
    character : Character
    animation : Animation
        From :func:`~toonmotion.api.animation.animate_character`.
    format : str, optional
        One of :data:`FORMATS`; needed for ``.json``.
    settings : DeformSettings, optional
        The settings the animation was made with: rigs skin the drawing as they say.
    size, background
        For pictures: as for :func:`~toonmotion.render.sequence.write_animation` (GIF and MP4
        are composited over white without a background; the other pictures keep transparency).
    padding, trim, max_size
        For a sprite sheet: pixels between frames, cropping frames to what is drawn, the largest
        sheet side.
    progress : callable, optional
        ``progress(stage, index, count)`` per frame.

    Returns
    -------
    Exported

    Raises
    ------
    ExportError
        A format or name that cannot be written, a sheet that cannot fit ``max_size``. Nothing
        already on disk is replaced unless the whole export is written.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.sample_animation import sample_animated
    >>> hero, animation = sample_animated()
    >>> folder = Path(tempfile.mkdtemp())
    >>> done = export_animation(folder / "hero.glb", hero, animation)
    >>> done.format, done.frames == len(animation.meshes), [p.name for p in done.files]
    ('glb', True, ['hero.glb'])
    """
    kind = export_format(path, format)
    path = Path(path)
    count = len(animation.meshes)
    if kind in RIGS:
        rig = drawing_rig(character, animation, settings=settings,
                          unit=PIXELS_PER_METRE if kind == "glb" else 1.0)
        if kind == "glb":
            save_animation_glb(path, rig)
            return Exported(kind, count, (path,))
        save_spine(path, rig, name=path.stem)
        return Exported(kind, count, (path, path.with_suffix(".atlas"), path.with_suffix(".png")))
    if kind == "sheet":
        view = animation_view(character, animation)
        out_size = natural_size(view, size=size)
        frames = _reported(render_animation(character, animation, size=out_size, background=background,
                                            view=view), count, progress)
        save_sprite_sheet(path, frames, fps=animation.motion.fps, name=path.stem, padding=padding, trim=trim,
                          max_size=max_size)
        return Exported(kind, count, (path, path.with_suffix(".png")), out_size)
    written, out_size = write_animation(path, character, animation, size=size, background=background,
                                        progress=progress)
    return Exported(kind, written, (path,), out_size)


def _reported(frames, count, progress):
    for index, frame in enumerate(frames, start=1):
        yield frame
        if progress is not None:
            progress("rendering", index, count)
