"""Writing animations: GIF, MP4 (H.264), APNG, animated WebP, WebM (VP9 with alpha) or PNG frames.

Frames are (H, W, 4) uint8 RGBA arrays, all the same size, given as any iterable (a
generator is streamed: MP4, WebM and PNG frames never hold more than one frame; Pillow needs
every GIF, APNG and WebP frame at once). GIF and MP4 have no partial transparency, so frames are
composited over a background colour; APNG, WebP, WebM and PNG frames keep alpha
(:data:`TRANSPARENT_FORMATS`). APNG and WebP are lossless: every visible pixel decodes back
exactly. WebM is lossy; :func:`~toonmotion.io.ffmpeg_video.read_webm_rgba` decodes it with its alpha.

Nothing is half-written: single files go to a temporary file beside the target that is
renamed over it after the last frame, and PNG frames go to a temporary folder and are moved
into place only once all of them are written. If the frames raise midway (a user error, a
KeyboardInterrupt), the previous output is untouched and no temporary file is left.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from numbers import Integral
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image
from PIL.PngImagePlugin import Blend, Disposal

from toonmotion import limits
from toonmotion.errors import ExportError
from toonmotion.geometry.arrays import frame_rate
from toonmotion.io.atomic import atomic_path, sweep_leftovers, temporary_prefix
from toonmotion.io.ffmpeg_video import save_mp4, save_webm
from toonmotion.render.composite import over, premultiply

FORMATS = ("gif", "mp4", "png", "apng", "webp", "webm")
# The formats that keep alpha and ignore the background colour.
TRANSPARENT_FORMATS = ("png", "apng", "webp", "webm")

# Single-file formats named by their suffix; a .png file without a number field is an APNG.
_SUFFIXES = {".gif": "gif", ".mp4": "mp4", ".apng": "apng", ".webp": "webp", ".webm": "webm"}
_ACCEPTED = (
    "a .gif or .mp4 file, a .webm, .webp or .png (.apng) file to keep transparency, "
    "a folder for PNG frames, or a pattern like frames/frame_%04d.png"
)
# The largest WebP canvas side.
_WEBP_MAX_SIDE = 16383


def animation_format(path: str | os.PathLike[str]) -> str:
    """The format an animation path asks for.

    Parameters
    ----------
    path : str or Path
        ``*.gif``, ``*.mp4``, ``*.webm``, ``*.webp``, ``*.apng`` or ``*.png`` (one animated PNG
        file); a folder (no suffix, or an existing folder) for PNG frames named
        ``frame_00000.png``, ..., or a file-name pattern containing ``%`` or ``{`` such as
        ``out/frame_%04d.png`` or ``out/f{:04d}.png``.

    Returns
    -------
    str
        One of :data:`FORMATS`.

    Examples
    --------
    >>> [animation_format(p) for p in ("walk.gif", "walk.MP4", "walk.webm", "walk.webp")]
    ['gif', 'mp4', 'webm', 'webp']
    >>> [animation_format(p) for p in ("walk.png", "walk.apng", "frames", "out/f_%03d.png")]
    ['apng', 'apng', 'png', 'png']
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if "%" in path.name or "{" in path.name:
        if suffix != ".png":
            raise ExportError(f"frame pattern {path.name} must end in .png, like frame_%04d.png")
        return "png"
    if suffix in _SUFFIXES:
        return _SUFFIXES[suffix]
    if suffix == "" or path.is_dir():
        return "png"
    if suffix == ".png":
        return "apng"
    raise ExportError(f"cannot write an animation to {path.name}: give {_ACCEPTED}")


def save_animation(path: str | os.PathLike[str], frames: Iterable[NDArray[np.uint8]], *, fps: float,
                   background: Sequence[int] = (255, 255, 255)) -> int:
    """Write frames as a GIF, an MP4 or WebM video, an APNG or WebP animation, or PNG frames.

    Parameters
    ----------
    path : str or Path
        Where to write; its form picks the format (see :func:`animation_format`).
    frames : iterable of (H, W, 4) uint8
        RGBA frames, all the same size; a generator is streamed to MP4, WebM and PNG frames.
    fps : float
        Frames per second, positive. GIF stores frame times in whole centiseconds: frames
        last 1/fps rounded to 10 ms, alternating so the total stays on time (fps 24 gives
        40 and 50 ms frames), and browsers slow frames under 20 ms (fps above 50) down.
        APNG and WebP do the same in whole milliseconds (fps 24 gives 42 and 41 ms frames; see
        :func:`frame_durations`). Identical consecutive GIF, APNG and WebP frames are merged
        into one longer frame, so a reader may find fewer, longer frames (an APNG of one
        distinct frame is a still PNG). PNG frames ignore fps.
    background : (r, g, b) int 0-255
        Colour GIF and MP4 frames are composited over. MP4 frames of odd width or height
        are padded with it by one pixel at the right or bottom (H.264 needs even sizes).
        APNG, WebP, WebM and PNG frames keep their alpha and ignore it.

    Returns
    -------
    int
        Number of frames written (as given, before identical frames are merged).

    Notes
    -----
    APNG frames decode back exactly, every RGBA value. WebP frames decode back exactly
    wherever alpha > 0; a fully transparent pixel is stored as (0, 0, 0, 0), since Pillow's
    animated WebP encoder cannot keep the colour under it. WebM is VP9 with an alpha plane,
    4:2:0 and lossy (constant quality): alpha comes back within a few levels (more right at
    sharp edges), colours within the YUV conversion's error, and any width and height, odd
    ones too, are kept as they are. Not every player shows its alpha; ffmpeg needs
    ``-c:v libvpx-vp9`` before ``-i``, as :func:`~toonmotion.io.ffmpeg_video.read_webm_rgba` does.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> frames = [np.zeros((8, 8, 4), np.uint8) for _ in range(3)]
    >>> for i, rgba in enumerate(frames):
    ...     rgba[i:i + 2, i:i + 2] = (200, 30, 30, 128)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     count = save_animation(Path(folder) / "blink.png", frames, fps=12)
    ...     with Image.open(Path(folder) / "blink.png") as image:
    ...         image.seek(2)
    ...         same = np.array_equal(np.asarray(image.convert("RGBA")), frames[2])
    >>> count, same
    (3, True)
    """
    fps = frame_rate(fps, error=ExportError)
    background = _check_background(background)
    kind = animation_format(path)
    frames = _checked(frames)
    if kind == "gif":
        return _save_gif(Path(path), _held(frames, "GIF"), float(fps), background)
    if kind == "mp4":
        return save_mp4(Path(path), (_flatten(rgba, background) for rgba in frames), float(fps), background)
    if kind == "apng":
        return _save_apng(Path(path), _held(frames, "APNG"), float(fps))
    if kind == "webp":
        return _save_webp(Path(path), _held(frames, "WebP"), float(fps))
    if kind == "webm":
        return save_webm(Path(path), frames, float(fps))
    return _save_png(Path(path), frames)


# A GIF's frames last whole hundredths of a second, and browsers play those under two hundredths
# at ten: above this rate a GIF plays slower than asked.
GIF_MAX_FPS = 50.0


def rate_note(kind: str, fps: float) -> str | None:
    """A note when an animation of format ``kind`` cannot play at ``fps``, else None.

    >>> rate_note("gif", 24) is None, rate_note("mp4", 1000) is None
    (True, True)
    >>> rate_note("gif", 1000)[:40]
    'a GIF plays at most 50 frames a second ('
    """
    if kind == "gif" and fps > GIF_MAX_FPS:
        return (f"a GIF plays at most {GIF_MAX_FPS:g} frames a second (its frames last whole hundredths of a "
                f"second, and browsers show shorter ones for a tenth): at {fps:g} it plays slower; write MP4 "
                "or WebP for a faster rate")
    return None


def frame_durations(count: int, fps: float, *, tick: int = 1) -> list[int]:
    """Frame durations in ms, whole multiples of ``tick`` ms, keeping the total on time.

    Frame ``i`` ends at ``(i + 1) / fps`` rounded to a whole tick, so durations alternate between
    the two nearest whole ticks and every frame ends within half a tick of its true time. A
    frame is never shorter than one tick (which matters only when ``fps > 1000 / tick``).

    Parameters
    ----------
    count : int
        Number of frames.
    fps : float
        Frames per second, positive.
    tick : int, optional
        The unit durations are whole multiples of, in ms: 1 for APNG, WebP and sprite sheets,
        10 for GIF (centiseconds).

    Returns
    -------
    list of int
        ``count`` durations in ms.

    Examples
    --------
    >>> frame_durations(3, 24)
    [42, 41, 42]
    >>> frame_durations(6, 24, tick=10), sum(frame_durations(12, 24, tick=10))
    ([40, 40, 40, 50, 40, 40], 500)
    """
    ends = np.rint(np.arange(count + 1) * (1000 / tick / fps)).astype(int)
    return [int(t) * tick for t in np.maximum(np.diff(ends), 1)]


def _save_gif(path, frames, fps, background):
    with atomic_path(path) as tmp:
        # Each frame gets its own palette; no dithering, so flat colours stay flat.
        images = [
            Image.fromarray(_flatten(rgba, background)).quantize(
                256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE
            )
            for rgba in frames
        ]
        if not images:
            raise ExportError(f"no frames to write to {path.name}; the animation is empty")
        images[0].save(
            tmp, format="GIF", save_all=True, append_images=images[1:],
            duration=frame_durations(len(images), fps, tick=10), loop=0,
        )
    return len(images)


def _save_apng(path, frames, fps):
    with atomic_path(path) as tmp:
        images = [Image.fromarray(rgba) for rgba in frames]
        if not images:
            raise ExportError(f"no frames to write to {path.name}; the animation is empty")
        # Pillow stores each frame as the rectangle that changed since the canvas before it.
        # Blend OP_SOURCE replaces that rectangle, alpha included, rather than drawing over it,
        # and disposal OP_NONE leaves the canvas as the last frame: each frame decodes exactly.
        images[0].save(
            tmp, format="PNG", save_all=True, append_images=images[1:],
            duration=frame_durations(len(images), fps), loop=0,
            disposal=Disposal.OP_NONE, blend=Blend.OP_SOURCE,
        )
    return len(images)


def _save_webp(path, frames, fps):
    with atomic_path(path) as tmp:
        images = []
        for rgba in frames:
            if max(rgba.shape[:2]) > _WEBP_MAX_SIDE:
                raise ExportError(
                    f"frames of {rgba.shape[1]}x{rgba.shape[0]} are too big for WebP "
                    f"(at most {_WEBP_MAX_SIDE} pixels a side); render them smaller"
                )
            images.append(Image.fromarray(_clear_transparent(rgba)))
        if not images:
            raise ExportError(f"no frames to write to {path.name}; the animation is empty")
        # Lossless; method 2 at quality (effort) 50 measured 25 % smaller than the fastest
        # setting, at about 0.1 s a 480x600 frame; higher efforts gained under 5 % more.
        images[0].save(
            tmp, format="WEBP", save_all=True, append_images=images[1:],
            duration=frame_durations(len(images), fps), loop=0,
            lossless=True, quality=50, method=2, allow_mixed=False,
        )
    return len(images)


def _clear_transparent(rgba):
    """``rgba`` with fully transparent pixels set to (0, 0, 0, 0), as animated WebP stores them."""
    clear = rgba[..., 3] == 0
    if not clear.any():
        return rgba
    rgba = rgba.copy()
    rgba[clear] = 0
    return rgba


def _save_png(path, frames):
    folder, name_of = _png_names(path)
    if folder.exists() and not folder.is_dir():
        raise ExportError(f"cannot write PNG frames into {folder}: it is a file; give a folder")
    created = not folder.exists()
    folder.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=temporary_prefix(_STAGING), suffix=".tmp", dir=folder))
    count, done = 0, False
    try:
        for rgba in frames:
            Image.fromarray(rgba).save(staging / name_of(count), format="PNG", compress_level=3)
            count += 1
        if count == 0:
            raise ExportError(f"no frames to write to {path}; the animation is empty")
        for i in range(count):
            os.replace(staging / name_of(i), folder / name_of(i))
        # The tail of an older, longer sequence with the same names would play on: remove it.
        stale = count
        while (folder / name_of(stale)).is_file():
            (folder / name_of(stale)).unlink()
            stale += 1
        done = True
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        if not done and created and not any(folder.iterdir()):
            folder.rmdir()
    sweep_leftovers(folder, _STAGING)
    return count


# The name PNG frames are staged under (in a hidden folder beside them) until all are written.
_STAGING = "frames"


def _png_names(path):
    """The folder PNG frames go into and a function from frame number to file name."""
    name = path.name
    if "%" not in name and "{" not in name:
        return path, lambda i: f"frame_{i:05d}.png"

    def name_of(i):
        return name % i if "%" in name else name.format(i)

    try:
        names = {name_of(0), name_of(1)}
    except (TypeError, ValueError, KeyError, IndexError):
        raise ExportError(
            f"frame pattern {name} needs one number field, like frame_%04d.png or frame_{{:04d}}.png"
        ) from None
    if len(names) < 2 or any(os.sep in n or (os.altsep and os.altsep in n) for n in names):
        raise ExportError(
            f"frame pattern {name} must give each frame its own file name, like frame_%04d.png"
        )
    return path.parent, name_of


def _held(frames, kind):
    """The frames of a GIF, APNG or WebP, whose writer (Pillow's) holds them all before it writes:
    their pixels are counted against the ``held_pixels`` limit as they come (a 4000x3000 APNG
    took 92 MB more a frame, and 150 frames would have run out of memory with no word)."""
    total = 0
    for rgba in frames:
        total += rgba.shape[0] * rgba.shape[1]
        limits.check("held_pixels", total, f"writing this {kind} (its frames are held)",
                     hint="write MP4, WebM or PNG frames, written a frame at a time, or draw it smaller")
        yield rgba


def _checked(frames):
    """Yield the frames, checking each is (H, W, 4) uint8 and the same size as the first."""
    try:
        iterator = iter(frames)
    except TypeError:
        raise ExportError(
            f"frames must be an iterable of RGBA arrays, got {type(frames).__name__}"
        ) from None
    shape = None
    for i, frame in enumerate(iterator):
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 4 or frame.dtype != np.uint8:
            raise ExportError(
                f"frame {i} must be an (H, W, 4) uint8 RGBA array, "
                f"got shape {frame.shape} dtype {frame.dtype}"
            )
        if shape is None:
            shape = frame.shape
        elif frame.shape != shape:
            raise ExportError(
                f"frame {i} is {frame.shape[1]}x{frame.shape[0]} but frame 0 is {shape[1]}x{shape[0]}; "
                "render every frame at the same size"
            )
        yield np.ascontiguousarray(frame)


def _flatten(rgba, background):
    """(H, W, 3) uint8: RGBA composited over an opaque background colour, rounded."""
    if rgba[..., 3].min() == 255:
        return rgba[..., :3]
    flat = over(premultiply(rgba).reshape(-1, 4), (*background, 255))
    return flat.reshape(rgba.shape)[..., :3]


def _check_background(background):
    try:
        values = tuple(background)
    except TypeError:
        values = ()
    if len(values) != 3 or not all(
        isinstance(v, Integral) and not isinstance(v, bool) and 0 <= v <= 255 for v in values
    ):
        raise ExportError(f"background must be an (r, g, b) tuple of ints 0-255, got {background!r}")
    return tuple(int(v) for v in values)
