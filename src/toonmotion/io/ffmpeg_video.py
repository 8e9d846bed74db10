"""MP4 and WebM through the ffmpeg that imageio-ffmpeg bundles (:func:`toonmotion.io.video.save_animation`
writes them): frames piped to the encoder into a temporary file renamed over the target, and
WebM read back with its alpha."""

from __future__ import annotations

import os
from itertools import chain
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import ExportError
from toonmotion.io.atomic import atomic_path

# x264 constant rate factor: 18 is visually lossless for flat cartoon colours.
_CRF = 18


# VP9 in constant-quality mode (-b:v 0). Flat colour fills lose little at any low CRF (2-3 levels on
# average, mostly the YUV conversion's); what the CRF decides is ringing at edges, which shows most in
# the alpha plane as a faint fringe on transparent pixels beside the outlines. Measured on the sample
# character at 96x120: CRF 10 keeps that fringe at alpha <= 11 (4 %), on 3 % of transparent pixels,
# at about half the size of lossless VP9; CRF 20 saved a quarter more but let the fringe reach 26.
_VP9_CRF = 10


def save_mp4(path, frames, fps, background):
    """RGB ``frames`` (flattened) as H.264 MP4, padded to even sides with ``background``."""
    first = next(frames, None)
    if first is None:
        raise ExportError(f"no frames to write to {path.name}; the animation is empty")
    H, W = first.shape[:2]
    size = (W + W % 2, H + H % 2)
    canvas = np.empty((size[1], size[0], 3), np.uint8)
    canvas[...] = background

    def picture(rgb):
        canvas[:H, :W] = rgb
        return canvas

    # The temporary file has no .mp4 suffix, so name the container.
    params = ["-crf", str(_CRF), "-movflags", "+faststart", "-f", "mp4"]
    return encode(path, chain([first], frames), fps, size, picture, codec="libx264",
                   pix_fmt_in="rgb24", pix_fmt_out="yuv420p", output_params=params)


def save_webm(path, frames, fps):
    """RGBA ``frames`` as VP9 WebM with its alpha."""
    first = next(frames, None)
    if first is None:
        raise ExportError(f"no frames to write to {path.name}; the animation is empty")
    H, W = first.shape[:2]
    # libvpx encodes alpha as a second stream beside the colour one; alt-ref (hidden) frames
    # would break their one-to-one pairing, so they are off. -b:v 0 makes -crf constant quality.
    # cpu-used 2 (0 is slowest) and row multithreading keep encoding quick.
    params = ["-crf", str(_VP9_CRF), "-b:v", "0", "-auto-alt-ref", "0", "-deadline", "good",
              "-cpu-used", "2", "-row-mt", "1", "-f", "webm"]
    return encode(path, chain([first], frames), fps, (W, H), lambda rgba: rgba, codec="libvpx-vp9",
                   pix_fmt_in="rgba", pix_fmt_out="yuva420p", output_params=params)


def encode(path, frames, fps, size, picture, *, codec, **options):
    """Pipe ``picture(frame)`` for every frame to the bundled ffmpeg; the number of frames."""
    import imageio_ffmpeg

    count = 0
    with atomic_path(path) as tmp:
        writer = imageio_ffmpeg.write_frames(
            str(tmp), size, fps=fps, codec=codec, quality=None, macro_block_size=1,
            ffmpeg_log_level="error", **options,
        )
        writer.send(None)  # start ffmpeg
        try:
            for rgba in frames:
                try:
                    writer.send(picture(rgba).tobytes())
                except OSError as error:
                    message = str(error).splitlines()[0]
                    raise ExportError(f"ffmpeg failed writing {path.name}: {message}") from None
                count += 1
        finally:
            writer.close()  # waits for ffmpeg to finish (or stop) before the file is renamed or removed
        if tmp.stat().st_size == 0:
            raise ExportError(f"ffmpeg wrote nothing for {path.name}; check that it supports {codec}")
    return count


def read_webm_rgba(path: str | os.PathLike[str]) -> NDArray[np.uint8]:
    """Decode a WebM (VP9) video with its alpha channel, through the bundled ffmpeg.

    ffmpeg's own VP9 decoder drops the alpha plane, so libvpx's decoder is forced. A video
    without alpha comes back opaque (alpha 255).

    Parameters
    ----------
    path : str or Path
        A ``.webm`` file, such as :func:`save_animation` writes.

    Returns
    -------
    (T, H, W, 4) uint8
        Every frame, RGBA. The whole video is held in memory.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.io.video import save_animation
    >>> rgba = np.zeros((6, 10, 4), np.uint8)
    >>> rgba[:, :5] = (40, 90, 200, 255)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     count = save_animation(Path(folder) / "half.webm", [rgba] * 2, fps=10)
    ...     read = read_webm_rgba(Path(folder) / "half.webm")
    >>> read.shape, int(read[0, 3, 1, 3]), int(read[0, 3, 8, 3])
    ((2, 6, 10, 4), 255, 0)
    """
    import imageio_ffmpeg

    path = Path(path)
    if not path.is_file():
        raise ExportError(f"cannot read {path}: no such file")
    reader = imageio_ffmpeg.read_frames(
        str(path), pix_fmt="rgba", bits_per_pixel=32, input_params=["-c:v", "libvpx-vp9"]
    )
    try:
        meta = next(reader)
        W, H = meta["size"]
        frames = [np.frombuffer(data, np.uint8).reshape(H, W, 4) for data in reader]
    except (OSError, RuntimeError, ValueError, KeyError, StopIteration):
        raise ExportError(
            f"cannot decode {path.name} as a VP9 WebM video; check that it is one and that it plays"
        ) from None
    finally:
        reader.close()
    if not frames:
        raise ExportError(f"no frames in {path.name}: ffmpeg decoded none; check that it plays")
    return np.stack(frames)
