"""Writing animations: animated GIF, MP4 (H.264) or a sequence of PNG frames.

Frames are (H, W, 4) uint8 RGBA arrays, all the same size, given as any iterable (a
generator is streamed: MP4 and PNG never hold more than one frame). GIF and MP4 have no
partial transparency, so frames are composited over a background colour; PNGs keep alpha.

Nothing is half-written: GIF and MP4 go to a temporary file beside the target that is
renamed over it after the last frame, and PNG frames go to a temporary folder and are moved
into place only once all of them are written. If the frames raise midway (a user error, a
KeyboardInterrupt), the previous output is untouched and no temporary file is left.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from itertools import chain
from numbers import Integral
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from toonmotion.errors import ExportError
from toonmotion.geometry.arrays import frame_rate
from toonmotion.io.atomic import atomic_path, sweep_leftovers, temporary_prefix
from toonmotion.render.composite import over, premultiply

FORMATS = ("gif", "mp4", "png")

_ACCEPTED = "a .gif or .mp4 file, a folder for PNG frames, or a pattern like frames/frame_%04d.png"
# x264 constant rate factor: 18 is visually lossless for flat cartoon colours.
_CRF = 18


def animation_format(path: str | os.PathLike[str]) -> str:
    """The format an animation path asks for.

    Parameters
    ----------
    path : str or Path
        ``*.gif``, ``*.mp4``, a folder (no suffix, or an existing folder) for PNG frames named
        ``frame_00000.png``, ..., or a file-name pattern containing ``%`` or ``{`` such as
        ``out/frame_%04d.png`` or ``out/f{:04d}.png``.

    Returns
    -------
    str
        One of :data:`FORMATS`.

    Examples
    --------
    >>> [animation_format(p) for p in ("walk.gif", "walk.MP4", "frames", "out/f_%03d.png")]
    ['gif', 'mp4', 'png', 'png']
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if "%" in path.name or "{" in path.name:
        if suffix != ".png":
            raise ExportError(f"frame pattern {path.name} must end in .png, like frame_%04d.png")
        return "png"
    if suffix in (".gif", ".mp4"):
        return suffix[1:]
    if suffix == "" or path.is_dir():
        return "png"
    raise ExportError(f"cannot write an animation to {path.name}: give {_ACCEPTED}")


def save_animation(path: str | os.PathLike[str], frames: Iterable[NDArray[np.uint8]], *, fps: float,
                   background: Sequence[int] = (255, 255, 255)) -> int:
    """Write frames as an animated GIF, an MP4 video or a sequence of PNGs.

    Parameters
    ----------
    path : str or Path
        Where to write; its form picks the format (see :func:`animation_format`).
    frames : iterable of (H, W, 4) uint8
        RGBA frames, all the same size; a generator is streamed.
    fps : float
        Frames per second, positive. GIF stores frame times in whole centiseconds: frames
        last 1/fps rounded to 10 ms, alternating so the total stays on time (fps 24 gives
        40 and 50 ms frames), and browsers slow frames under 20 ms (fps above 50) down.
        Identical consecutive GIF frames are merged into one longer frame. PNG ignores fps.
    background : (r, g, b) int 0-255
        Colour GIF and MP4 frames are composited over. MP4 frames of odd width or height
        are padded with it by one pixel at the right or bottom (H.264 needs even sizes).

    Returns
    -------
    int
        Number of frames written.
    """
    fps = frame_rate(fps, error=ExportError)
    background = _check_background(background)
    kind = animation_format(path)
    frames = _checked(frames)
    if kind == "gif":
        return _save_gif(Path(path), frames, float(fps), background)
    if kind == "mp4":
        return _save_mp4(Path(path), frames, float(fps), background)
    return _save_png(Path(path), frames)


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
            duration=_gif_durations(len(images), fps), loop=0,
        )
    return len(images)


def _gif_durations(count, fps):
    """Frame durations in ms, whole centiseconds, summing to the exact total when rounded."""
    ends = np.rint(np.arange(count + 1) * (100 / fps)).astype(int)
    return [int(cs) * 10 for cs in np.maximum(np.diff(ends), 1)]


def _save_mp4(path, frames, fps, background):
    import imageio_ffmpeg

    first = next(frames, None)
    if first is None:
        raise ExportError(f"no frames to write to {path.name}; the animation is empty")
    H, W = first.shape[:2]
    size = (W + W % 2, H + H % 2)
    canvas = np.empty((size[1], size[0], 3), np.uint8)
    canvas[...] = background
    count = 0
    with atomic_path(path) as tmp:
        writer = imageio_ffmpeg.write_frames(
            str(tmp), size, fps=fps, codec="libx264", pix_fmt_in="rgb24", pix_fmt_out="yuv420p",
            quality=None, macro_block_size=1, ffmpeg_log_level="error",
            # The temporary file has no .mp4 suffix, so name the container.
            output_params=["-crf", str(_CRF), "-movflags", "+faststart", "-f", "mp4"],
        )
        writer.send(None)  # start ffmpeg
        try:
            for rgba in chain([first], frames):
                canvas[:H, :W] = _flatten(rgba, background)
                try:
                    writer.send(canvas.tobytes())
                except OSError as error:
                    message = str(error).splitlines()[0]
                    raise ExportError(f"ffmpeg failed writing {path.name}: {message}") from None
                count += 1
        finally:
            writer.close()  # waits for ffmpeg to finish (or stop) before the file is renamed or removed
        if tmp.stat().st_size == 0:
            raise ExportError(f"ffmpeg wrote nothing for {path.name}; check that it supports libx264")
    return count


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
