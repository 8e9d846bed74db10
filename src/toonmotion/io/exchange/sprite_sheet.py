"""Sprite sheets: an animation's frames packed into one PNG, with a TexturePacker "JSON (Hash)" atlas.

The atlas is the layout Phaser (``load.atlas``), PixiJS (``Spritesheet``) and Godot's importers
read: per frame its rectangle in the sheet (``frame``), where that rectangle sits in the
original frame (``spriteSourceSize``, after trimming), the original frame's size
(``sourceSize``) and its duration in ms; an ``animations`` list names the frames in order.

Each frame is trimmed to the box of its pixels with alpha > 0 (a fully transparent frame
keeps one transparent pixel). Frames identical after trimming, such as drawings held for two
frames, share one rectangle (TexturePacker's aliases). The rectangles are packed on shelves,
tallest first, never rotated, trying sheet widths for the squarest sheet within ``max_size``.
``padding`` transparent pixels separate rectangles from each other and from the sheet's edges,
so texture filtering never bleeds one frame into the next.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from numbers import Integral
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from toonmotion import __version__
from toonmotion.errors import ExportError
from toonmotion.geometry.arrays import frame_rate
from toonmotion.io.atomic import atomic_path
from toonmotion.io.video import _checked, frame_durations

# Sheet widths tried between the widest rectangle and the largest allowed.
_WIDTHS_TRIED = 48


@dataclass(frozen=True)
class SheetFrame:
    """One frame of a sprite sheet, as its atlas entry describes it (pixels, y down).

    Attributes
    ----------
    name : str
        Its key in the atlas, ``<name>_0000``, ...
    rect : (x, y, w, h) int
        Its rectangle in the sheet (``frame``); frames that share a drawing share it.
    offset : (x, y) int
        Where that rectangle's top-left corner sits in the original frame
        (``spriteSourceSize``'s ``x`` and ``y``; ``(0, 0)`` when not trimmed).
    source_size : (w, h) int
        The original frame's size (``sourceSize``).
    trimmed : bool
        Whether the rectangle is smaller than the original frame.
    duration : int
        How long the frame shows, ms.
    """

    name: str
    rect: tuple[int, int, int, int]
    offset: tuple[int, int]
    source_size: tuple[int, int]
    trimmed: bool
    duration: int


@dataclass(frozen=True)
class SheetLayout:
    """Where :func:`save_sprite_sheet` put every frame.

    Attributes
    ----------
    size : (w, h) int
        The sheet image's size.
    frames : tuple of SheetFrame
        One per frame, in frame order.
    """

    size: tuple[int, int]
    frames: tuple[SheetFrame, ...]


def save_sprite_sheet(path: str | os.PathLike[str], frames: Iterable[NDArray[np.uint8]], *, fps: float,
                      name: str = "frame", padding: int = 2, trim: bool = True,
                      max_size: int = 4096) -> SheetLayout:
    """Pack RGBA frames into one sheet image and write it with its JSON atlas, atomically.

    Parameters
    ----------
    path : str or Path
        The atlas, ``*.json``. The sheet is written beside it with the same name and ``.png``
        (``walk.json`` and ``walk.png``). Both are staged as temporary files and renamed into
        place only once both are written, so an error (in the frames too) leaves any earlier
        pair as it was.
    frames : iterable of (H, W, 4) uint8
        RGBA frames, all the same size. Frames are trimmed and compared as they come; only the
        distinct trimmed drawings are held.
    fps : float
        Frames per second; frames last whole ms summing to the exact total (see
        :func:`toonmotion.io.video.frame_durations`).
    name : str
        The animation's name in the atlas; frame keys are ``<name>_0000``, ... (more digits
        when there are more than 10 000 frames).
    padding : int
        Transparent pixels between rectangles and at the sheet's edges, >= 0.
    trim : bool
        Crop each frame to the box of its pixels with alpha > 0. The colour of fully
        transparent pixels outside that box is not kept: a reader fills them with (0, 0, 0, 0).
    max_size : int
        The sheet's largest allowed width and height (4096 suits most GPUs).

    Returns
    -------
    SheetLayout
        The sheet's size and every frame's place.

    Examples
    --------
    >>> import tempfile
    >>> frames = [np.zeros((10, 8, 4), np.uint8) for _ in range(3)]
    >>> frames[0][2:6, 1:4] = frames[1][2:6, 1:4] = (255, 0, 0, 255)  # held for two frames
    >>> frames[2][5:9, 3:7] = (0, 0, 255, 128)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     layout = save_sprite_sheet(Path(folder) / "blink.json", frames, fps=10, padding=1)
    ...     atlas = json.loads((Path(folder) / "blink.json").read_text())
    >>> [(f.rect, f.offset, f.duration) for f in layout.frames]
    [((6, 1, 3, 4), (1, 2), 100), ((6, 1, 3, 4), (1, 2), 100), ((1, 1, 4, 4), (3, 5), 100)]
    >>> layout.size, atlas["frames"]["frame_0002"]["spriteSourceSize"], atlas["meta"]["image"]
    ((10, 6), {'x': 3, 'y': 5, 'w': 4, 'h': 4}, 'blink.png')
    """
    path = Path(path)
    if path.suffix.lower() != ".json":
        raise ExportError(
            f"cannot write a sprite sheet atlas to {path.name}: give a .json file (the sheet goes beside "
            "it as .png)"
        )
    fps = frame_rate(fps, error=ExportError)
    if not isinstance(name, str) or not name:
        raise ExportError(f"name must be a non-empty string, got {name!r}")
    padding = _whole(padding, "padding", minimum=0)
    max_size = _whole(max_size, "max_size", minimum=1)

    drawings, placed, source = _trimmed(frames, trim)
    if not placed:
        raise ExportError(f"no frames to write to {path.name}; the animation is empty")
    sizes = [(d.shape[1], d.shape[0]) for d in drawings]
    packed = _best_packing(sizes, padding, max_size)
    if packed is None:
        raise ExportError(_too_big(sizes, [k for k, _ in placed], padding, max_size))
    positions, size = packed

    sheet = np.zeros((size[1], size[0], 4), np.uint8)
    for (x, y), drawing in zip(positions, drawings, strict=True):
        sheet[y:y + drawing.shape[0], x:x + drawing.shape[1]] = drawing
    digits = max(4, len(str(len(placed) - 1)))
    durations = frame_durations(len(placed), fps)
    layout = SheetLayout(size=size, frames=tuple(
        SheetFrame(
            name=f"{name}_{i:0{digits}d}", rect=(*positions[k], *sizes[k]), offset=offset,
            source_size=source, trimmed=sizes[k] != source, duration=duration,
        )
        for i, ((k, offset), duration) in enumerate(zip(placed, durations, strict=True))
    ))
    image = path.with_suffix(".png")
    text = json.dumps(_atlas(layout, name, image.name), indent=2) + "\n"
    # The sheet is renamed into place first, so once the new atlas is there, so is its image.
    with atomic_path(path) as atlas_tmp, atomic_path(image) as image_tmp:
        Image.fromarray(sheet).save(image_tmp, format="PNG")
        atlas_tmp.write_text(text, encoding="utf-8")
    return layout


def _whole(value, what, *, minimum):
    if isinstance(value, bool) or not isinstance(value, Integral) or value < minimum:
        raise ExportError(f"{what} must be a whole number of pixels >= {minimum}, got {value!r}")
    return int(value)


def _trimmed(frames, trim):
    """The distinct drawings, each frame's (drawing index, offset), and the frames' (w, h)."""
    drawings = []
    seen = {}  # (shape, digest) -> index of a drawing
    placed = []
    source = (0, 0)
    for rgba in _checked(frames):
        source = (rgba.shape[1], rgba.shape[0])
        drawing, offset = _trim(rgba) if trim else (rgba, (0, 0))
        key = (drawing.shape, hashlib.blake2b(drawing.tobytes(), digest_size=16).digest())
        index = seen.get(key)
        if index is None or not np.array_equal(drawings[index], drawing):
            index = len(drawings)
            drawings.append(drawing.copy())
            seen.setdefault(key, index)
        placed.append((index, offset))
    return drawings, placed, source


def _trim(rgba):
    """``rgba`` cropped to its pixels with alpha > 0, and the crop's (x, y) in it."""
    visible = rgba[..., 3] > 0
    rows, cols = np.flatnonzero(visible.any(axis=1)), np.flatnonzero(visible.any(axis=0))
    if rows.size == 0:
        return np.zeros((1, 1, 4), np.uint8), (0, 0)
    top, bottom, left, right = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    return rgba[top:bottom, left:right], (int(left), int(top))


def _best_packing(sizes, padding, max_size):
    """Positions and sheet (w, h) of the squarest shelf packing within ``max_size``, or None.

    ``max_size`` None means no limit, and then a packing is always found.
    """
    widest = max(w for w, _ in sizes) + 2 * padding
    tallest = max(h for _, h in sizes) + 2 * padding
    if max_size is not None and max(widest, tallest) > max_size:
        return None
    best = None
    for width in _widths(sizes, padding, widest, max_size):
        positions, size = _shelves(sizes, padding, width)
        if max_size is not None and size[1] > max_size:
            continue
        score = (max(size), size[0] * size[1], size[0])
        if best is None or score < best[0]:
            best = (score, positions, size)
    return None if best is None else best[1:]


def _widths(sizes, padding, widest, limit):
    """Sheet widths to try: around the square root of the area, then spread up to ``limit``."""
    area = sum((w + padding) * (h + padding) for w, h in sizes)
    side = math.isqrt(area) + padding
    near = [round(side * f) for f in (0.9, 1.0, 1.1, 1.25, 1.5)]
    if limit is None:  # a single shelf is as wide as a sheet gets
        limit = sum(w + padding for w, _ in sizes) + padding
    spread = np.geomspace(widest, max(limit, widest), _WIDTHS_TRIED).round().astype(int).tolist()
    return sorted({min(max(w, widest), limit) for w in near + spread})


def _shelves(sizes, padding, width):
    """Shelf packing within ``width``: tallest first, left to right, each shelf below the last."""
    order = sorted(range(len(sizes)), key=lambda i: (-sizes[i][1], -sizes[i][0], i))
    positions = [(0, 0)] * len(sizes)
    x = y = padding
    shelf = right = 0
    for i in order:
        w, h = sizes[i]
        if x > padding and x + w + padding > width:
            x, y, shelf = padding, y + shelf + padding, 0
        positions[i] = (x, y)
        right = max(right, x + w)
        x += w + padding
        shelf = max(shelf, h)
    return positions, (right + padding, y + shelf + padding)


def _too_big(sizes, used, padding, max_size):
    """The message for frames that do not fit: how many would, and the size all would need."""
    too_big = [i for i, k in enumerate(used) if max(sizes[k]) + 2 * padding > max_size]
    if too_big:
        frame = too_big[0]
        w, h = sizes[used[frame]]
        return (
            f"frame {frame} is {w}x{h} pixels (after any trimming), {max(w, h) + 2 * padding} with "
            f"padding {padding}, more than max_size {max_size}: raise max_size or render the frames smaller"
        )
    _, size = _best_packing(sizes, padding, None)
    low, high = 0, len(used)  # the most leading frames that fit: low fit, high + 1 do not
    while low < high:
        middle = (low + high + 1) // 2
        kept = sorted(set(used[:middle]))
        if _best_packing([sizes[k] for k in kept], padding, max_size) is not None:
            low = middle
        else:
            high = middle - 1
    return (
        f"the {len(used)} frames need a sheet of {size[0]}x{size[1]} pixels but max_size is {max_size}, "
        f"which holds the first {low}: raise max_size to {max(size)}, render the frames smaller or "
        "write fewer"
    )


def _atlas(layout, name, image):
    """The TexturePacker JSON (Hash) document of ``layout``."""
    frames = {}
    for f in layout.frames:
        x, y, w, h = f.rect
        frames[f.name] = {
            "frame": {"x": x, "y": y, "w": w, "h": h},
            "rotated": False,
            "trimmed": f.trimmed,
            "spriteSourceSize": {"x": f.offset[0], "y": f.offset[1], "w": w, "h": h},
            "sourceSize": {"w": f.source_size[0], "h": f.source_size[1]},
            "duration": f.duration,
        }
    return {
        "frames": frames,
        "animations": {name: [f.name for f in layout.frames]},
        "meta": {
            "app": "toonmotion",
            "version": __version__,
            "image": image,
            "format": "RGBA8888",
            "size": {"w": layout.size[0], "h": layout.size[1]},
            "scale": "1",
        },
    }
