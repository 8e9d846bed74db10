"""Reading image sequences to capture motion from: a video, an animated image, numbered images.

Accepted inputs, picked by the path's form:

* a **video** file (MP4, MOV, AVI, MKV, WebM, ... anything ffmpeg decodes), read with the ffmpeg
  binary that imageio-ffmpeg ships (``imageio_ffmpeg.read_frames``, the reader behind imageio's
  ``FFMPEG`` plugin; PyAV is not installed). One ffmpeg run reports the frame size and rate
  before any frame is decoded, so the size limits are checked first, and reading stops as soon
  as a clip proves too long;
* an **animated image** (GIF, APNG, animated WebP), read with Pillow, which composites every
  frame onto the ones before it (GIF frames usually store only the part that changed). A frame
  shown for several frame times (a hold; :func:`~toonmotion.io.video.save_animation` merges
  identical frames into one) is repeated so frames are evenly spaced in time again: each frame
  is repeated ``round(duration / median duration)`` times;
* a **folder** of numbered images (PNG, JPEG, BMP, TIFF, WebP, ...), in natural order of their
  names (``f_2.png`` before ``f_10.png``); hidden files and other files are ignored;
* a **file pattern** with one number field, printf or format style (``frames/f_%04d.png``,
  ``frames/f_{:04d}.png``): every file in the folder whose name matches, with any number of
  digits in the field, in numeric order.

Frames come back as RGB: an alpha channel is dropped, not composited, so a fully transparent
pixel keeps whatever colour it stores (often black; for GIF, its palette colour). That is
enough for background subtraction, which only needs the background to stay the same colour.

The whole sequence is held in memory, ``T * h * w * 3`` bytes, so ``max_pixels`` caps the
pixels of all frames together (by default the ``footage_pixels`` limit, 500 million: 1.5 GB,
240 frames of 1920x1080, 2000 frames of 640x360), and ``max_frames`` the frame count (the
``footage_frames`` limit, 2000); each frame must also keep within ``image_pixels``
(:mod:`toonmotion.limits`).
"""

from __future__ import annotations

import os
import re
import struct
from pathlib import Path

import numpy as np
from numba import njit
from numpy.typing import NDArray
from PIL import ImageSequence

from toonmotion import limits as resource_limits
from toonmotion.errors import ImageReadError, ImageTooLargeError, VideoReadError
from toonmotion.io.image import load_image, open_image

# Single files Pillow reads, with their animation, better than ffmpeg does.
ANIMATED_SUFFIXES = (".gif", ".png", ".apng", ".webp")
# Files a folder of frames may hold; anything else in it is ignored.
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".gif", ".tga", ".ppm")

_CUT_HINT = "cut the clip to the part to track (e.g. ffmpeg -ss START -t SECONDS -i IN OUT)"
_SCALE_HINT = "scale it down (e.g. ffmpeg -i IN -vf scale=iw/2:-2 OUT)"
_PATTERN_FIELD = re.compile(r"%0?\d*d|\{[^{}]*\}")


def load_frames(path: str | os.PathLike[str], *, max_frames: int | None = None,
                max_pixels: int | None = None, alpha: bool = False) -> tuple[NDArray[np.uint8], float | None]:
    """Read a video, an animated image, a folder of numbered images or a file pattern.

    Parameters
    ----------
    path : str or Path
        A video file, a ``.gif``/``.png``/``.webp`` (animated or not), a folder of images, or a
        pattern such as ``frames/f_%04d.png``; see the module docstring.
    max_frames : int
        Refuse sequences of more frames than this (:class:`VideoReadError`).
    max_pixels : int
        Refuse sequences whose frames hold more pixels than this together, ``T * h * w``.
    alpha : bool
        Keep the images' alpha: frames are RGBA, opaque where the file has no alpha (videos).

    Returns
    -------
    frames : (T, h, w, 3) uint8, or (T, h, w, 4) with ``alpha``
        RGB frames, T >= 1; alpha is dropped unless asked for.
    fps : float or None
        Frames per second from the video's metadata or the animation's frame durations; None
        for image folders and patterns, and when the file does not say.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.io.image import save_png
    >>> folder = Path(tempfile.mkdtemp())
    >>> for i in (1, 2, 10):
    ...     save_png(folder / f"f_{i}.png", np.full((4, 6, 3), i, np.uint8))
    >>> frames, fps = load_frames(folder)
    >>> frames.shape, frames[:, 0, 0, 0].tolist(), fps
    ((3, 4, 6, 3), [1, 2, 10], None)
    """
    in_force = resource_limits.current()
    max_frames = in_force.footage_frames if max_frames is None else max_frames
    max_pixels = in_force.footage_pixels if max_pixels is None else max_pixels
    if isinstance(max_frames, bool) or not isinstance(max_frames, int) or max_frames < 1:
        raise ValueError(f"max_frames must be a positive whole number, got {max_frames!r}")
    if isinstance(max_pixels, bool) or not isinstance(max_pixels, int) or max_pixels < 1:
        raise ValueError(f"max_pixels must be a positive whole number, got {max_pixels!r}")
    limits = _Limits(max_frames, max_pixels)
    path = Path(path)
    channels = 4 if alpha else 3
    if _PATTERN_FIELD.search(path.name):
        return _load_files(_pattern_files(path), str(path), limits, channels), None
    if path.is_dir():
        return _load_files(_folder_files(path), str(path), limits, channels), None
    if not path.is_file():
        raise VideoReadError(f"cannot read {path}: no such file or folder")
    if path.suffix.lower() in ANIMATED_SUFFIXES:
        return _load_animated(path, limits, channels)
    frames, fps = _load_video(path, limits)
    if alpha:
        frames = np.concatenate([frames, np.full(frames.shape[:3] + (1,), 255, np.uint8)], axis=3)
    return frames, fps


class _Limits:
    """The frame and pixel limits, and the errors for going over them."""

    def __init__(self, max_frames, max_pixels):
        self.max_frames, self.max_pixels = max_frames, max_pixels

    def check(self, name, count, width, height, *, amount=None):
        """Raise unless ``count`` frames of ``width`` x ``height`` fit; ``amount`` words the count."""
        amount = amount or str(count)
        if count > self.max_frames:
            raise VideoReadError(
                f"{name} has {amount} frames, over the limit of {self.max_frames}; {_CUT_HINT}"
            )
        # No frame may exceed one image's limit: that guards against decompression bombs.
        per_frame = min(self.max_pixels, resource_limits.current().image_pixels)
        if width * height > per_frame:
            raise VideoReadError(
                f"{name} has frames of {width}x{height} = {width * height:,} pixels, over the limit of "
                f"{per_frame:,} per frame; {_SCALE_HINT}"
            )
        if count * width * height > self.max_pixels:
            raise VideoReadError(
                f"{name} has {amount} frames of {width}x{height}, {count * width * height:,} pixels in all, "
                f"over the limit of {self.max_pixels:,}; {_SCALE_HINT} or {_CUT_HINT}"
            )


# --- folders and patterns ------------------------------------------------------------------------


def _natural_key(name):
    """Sort key putting ``f_2`` before ``f_10``: digit runs compare as numbers."""
    parts = re.split(r"(\d+)", name.lower())
    return [(0, int(p), "") if p.isdigit() else (1, 0, p) for p in parts], name


def _folder_files(folder):
    files = [
        p for p in folder.iterdir()
        if p.is_file() and not p.name.startswith(".") and p.suffix.lower() in IMAGE_SUFFIXES
    ]
    if not files:
        raise VideoReadError(
            f"no frames in {folder}: it holds no image files ({', '.join(IMAGE_SUFFIXES[:4])}, ...); "
            "give a folder of numbered images, a video or a GIF"
        )
    return sorted(files, key=lambda p: _natural_key(p.name))


def _pattern_files(pattern):
    fields = _PATTERN_FIELD.findall(pattern.name)
    if len(fields) != 1:
        raise VideoReadError(
            f"frame pattern {pattern.name} needs exactly one number field, like f_%04d.png or f_{{:04d}}.png"
        )
    before, after = _PATTERN_FIELD.split(pattern.name)
    name_re = re.compile(re.escape(before) + r"(\d+)" + re.escape(after))
    folder = pattern.parent
    if not folder.is_dir():
        raise VideoReadError(f"cannot read frames {pattern}: no such folder {folder}")
    numbered = []
    for p in folder.iterdir():
        match = name_re.fullmatch(p.name)
        if match and p.is_file():
            numbered.append((int(match.group(1)), p.name, p))
    if not numbered:
        raise VideoReadError(f"no frames match {pattern}; check the folder and the file-name pattern")
    return [p for _, _, p in sorted(numbered)]


def _load_files(files, name, limits, channels):
    first = _read_image(files[0], channels)
    h, w = first.shape[:2]
    limits.check(name, len(files), w, h)
    frames = np.empty((len(files), h, w, channels), np.uint8)
    frames[0] = first
    for i, file in enumerate(files[1:], start=1):
        image = _read_image(file, channels)
        if image.shape[:2] != (h, w):
            raise VideoReadError(
                f"frame {file.name} is {image.shape[1]}x{image.shape[0]} but the first frame "
                f"{files[0].name} is {w}x{h}; give frames of one size"
            )
        frames[i] = image
    return frames


def _read_image(file, channels):
    try:
        return load_image(file)[..., :channels]
    except (ImageReadError, ImageTooLargeError) as error:
        raise VideoReadError(str(error)) from None


# --- animated images (Pillow) --------------------------------------------------------------------


def _load_animated(path, limits, channels):
    try:
        image = open_image(path, max_pixels=min(limits.max_pixels, resource_limits.current().image_pixels))
    except ImageTooLargeError as error:
        raise VideoReadError(str(error)) from None
    except ImageReadError:
        raise VideoReadError(
            f"cannot read {path}: it could not be decoded as an image; check the file opens in a viewer"
        ) from None
    with image:
        w, h = image.size
        durations: list[float] = []
        try:  # Pillow counts frames by reading past each one: a damaged file can fail here too
            count = getattr(image, "n_frames", 1)
            limits.check(path.name, count, w, h)
            # Decoded straight into the array (a list of frames, then a copy, held them twice).
            out = np.empty((count, h, w, channels), np.uint8)
            for i, frame in enumerate(ImageSequence.Iterator(image)):
                if i == count:
                    break
                out[i] = np.asarray(frame.convert("RGBA" if channels == 4 else "RGB"))
                durations.append(frame.info.get("duration") or 0)
        except (OSError, EOFError, SyntaxError, ValueError, IndexError, struct.error) as error:
            raise VideoReadError(
                f"cannot read {path}: frame {len(durations)} is damaged or truncated ({error})"
            ) from None
    times = np.asarray(durations, dtype=float)
    if len(times) == 0:
        raise VideoReadError(f"no frames in {path}")
    out = out[: len(times)]
    if not np.all(times > 0):
        return out, None
    # Holds become repeated frames, so frames are evenly spaced in time.
    repeats = np.maximum(1, np.rint(times / np.median(times)).astype(int))
    total = int(repeats.sum())
    limits.check(path.name, total, w, h)
    fps = 1000.0 * total / float(times.sum())
    return (out if total == len(out) else np.repeat(out, repeats, axis=0)), fps


# --- video (ffmpeg) ------------------------------------------------------------------------------


def _load_video(path, limits):
    import imageio_ffmpeg

    def undecodable(error):
        return VideoReadError(
            f"cannot read {path}: it could not be decoded as a video ({_ffmpeg_reason(error, path)}); "
            "check that it plays, or convert it to MP4 with ffmpeg"
        )

    reader = imageio_ffmpeg.read_frames(str(path), pix_fmt="rgb24")
    try:
        try:
            meta = next(reader)
            w, h = (int(v) for v in meta["size"])
        except (OSError, RuntimeError, ValueError, IndexError, KeyError, StopIteration) as error:
            raise undecodable(error) from None
        fps = float(meta.get("fps") or 0.0)
        fps = fps if np.isfinite(fps) and fps > 0 else None
        duration = float(meta.get("duration") or 0.0)
        # The container's duration only estimates the frame count: refuse early only when far over.
        estimate = int(duration * fps) if fps and np.isfinite(duration) else 0
        surely = int(estimate / 1.1) - 10
        if surely > limits.max_frames or surely * w * h > limits.max_pixels:
            limits.check(path.name, estimate, w, h, amount=f"about {estimate}")
        limits.check(path.name, 1, w, h)
        frames = []
        try:
            for data in reader:
                frames.append(np.frombuffer(data, np.uint8).reshape(h, w, 3))
                limits.check(path.name, len(frames), w, h, amount=f"more than {len(frames) - 1}")
        except (OSError, RuntimeError, ValueError) as error:
            raise undecodable(error) from None
    finally:
        reader.close()  # stops ffmpeg when reading ends early
    if not frames:
        raise VideoReadError(f"no frames in {path}: ffmpeg decoded none; check that it plays")
    return _stacked(frames), fps


def _stacked(frames):
    """Stack frames into one array, dropping each from the list once copied (peak memory ~1x)."""
    out = np.empty((len(frames), *frames[0].shape), np.uint8)
    for i in range(len(frames)):
        out[i], frames[i] = frames[i], None
    return out


def _ffmpeg_reason(error, path):
    """The last informative line of ffmpeg's complaint, without the file's path."""
    text = str(error)
    if "Stream #" in text and "Video:" not in text:
        return "it has no video stream"
    lines = [line.strip() for line in text.split("=== stderr ===")[-1].splitlines()]
    lines = [
        line for line in lines
        if line and not line.startswith(("ffmpeg version", "built with", "configuration:", "lib"))
    ]
    reason = lines[-1] if lines else text.splitlines()[0] if text else type(error).__name__
    for prefix in (str(path), path.name):
        reason = reason.replace(f"{prefix}: ", "")
    return reason[:160]


def lay_on(frames: NDArray[np.uint8],
           background: tuple[int, int, int] = (255, 255, 255)) -> NDArray[np.uint8]:
    """RGBA frames (or one frame) laid on a background colour, RGB; RGB frames are returned as they are.

    >>> lay_on(np.array([[[0, 0, 0, 0], [0, 0, 0, 255]]], np.uint8)).tolist()
    [[[255, 255, 255], [0, 0, 0]]]
    """
    if frames.shape[-1] == 3:
        return frames
    out = np.empty(frames.shape[:-1] + (3,), np.uint8)
    _laid(np.ascontiguousarray(frames).reshape(-1, 4), np.asarray(background, dtype=np.int64),
          out.reshape(-1, 3))
    return out


@njit(cache=True)
def _laid(rgba, background, out):  # pragma: no cover - compiled
    """``(a c + (255 - a) b + 127) // 255`` per channel: each pixel over the background, rounded to
    nearest, in whole numbers (eight times faster than NumPy's temporaries on a 640 x 480 frame)."""
    for n in range(len(rgba)):
        a = np.int64(rgba[n, 3])
        for c in range(3):
            out[n, c] = (a * rgba[n, c] + (255 - a) * background[c] + 127) // 255
