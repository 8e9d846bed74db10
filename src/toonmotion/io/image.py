"""Reading drawings and masks (anything Pillow reads) and writing PNGs."""

import io
import warnings
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from toonmotion import limits
from toonmotion.errors import ImageReadError, ImageTooLargeError, MaskError
from toonmotion.io.atomic import write_bytes


def load_image(path, *, max_pixels=None):
    """Read an image as RGBA.

    Parameters
    ----------
    path : str or Path
    max_pixels : int, optional
        Refuse images with more pixels than this (:class:`ImageTooLargeError`), checked from the
        header before anything is decoded; by default the ``image_pixels`` limit.

    Returns
    -------
    (h, w, 4) uint8
        RGBA; images without alpha get alpha 255 everywhere.
    """
    with open_image(path, max_pixels) as image:
        if image.mode in ("I;16", "I;16B", "I;16L", "I"):
            grey = np.asarray(image, dtype=np.float64)
            scale = 255.0 / max(float(grey.max()), 1.0)
            image = Image.fromarray(np.clip(np.rint(grey * scale), 0, 255).astype(np.uint8), "L")
        return np.asarray(image.convert("RGBA")).copy()


def load_mask(path, *, size=None, max_pixels=None):
    """Read a mask image: its alpha when it has transparency, else its brightness >= 128.

    Parameters
    ----------
    size : (width, height), optional
        The drawing's size; a mask of another size is a :class:`MaskError`.

    Returns
    -------
    (h, w) bool
    """
    rgba = load_image(path, max_pixels=max_pixels)
    if size is not None and (rgba.shape[1], rgba.shape[0]) != tuple(size):
        raise MaskError(
            f"mask {Path(path).name} is {rgba.shape[1]}x{rgba.shape[0]} but the drawing is "
            f"{size[0]}x{size[1]}; give a mask of the same size"
        )
    if rgba[..., 3].min() < 255:
        return rgba[..., 3] >= 128
    grey = rgba[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
    return grey >= 128


def png_bytes(array):
    """Encode an (h, w), (h, w, 3) or (h, w, 4) uint8 or bool array as PNG bytes."""
    array = np.asarray(array)
    if array.dtype == bool:
        array = array.astype(np.uint8) * 255
    buffer = io.BytesIO()
    Image.fromarray(array).save(buffer, format="PNG")
    return buffer.getvalue()


def save_png(path, image):
    """Write an array or a PIL image as a PNG, atomically."""
    if isinstance(image, Image.Image):
        buffer = io.BytesIO()
        image.save(buffer, format="PNG")
        write_bytes(path, buffer.getvalue())
    else:
        write_bytes(path, png_bytes(image))


def open_image(path, max_pixels=None):
    """Open ``path`` with Pillow, its size checked against ``max_pixels`` before decoding.

    Pillow's own decompression-bomb check is set aside (toonmotion's limit replaces it, and its
    warning would print before toonmotion's message); the returned image is loaded and open.
    """
    path = Path(path)
    limit = limits.current().image_pixels if max_pixels is None else max_pixels
    if not path.is_file():
        raise ImageReadError(f"cannot read {path}: no such file")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = _open_unchecked(path)
    except UnidentifiedImageError:
        raise ImageReadError(
            f"cannot read {path}: not an image format Pillow knows (try PNG, JPEG or BMP)"
        ) from None
    except (OSError, SyntaxError, ValueError) as error:
        raise ImageReadError(f"cannot read {path}: {_first_line(error)}") from None
    width, height = image.size
    if width * height > limit:
        image.close()
        raise ImageTooLargeError(
            f"{path.name} is {width}x{height} = {width * height:,} pixels, over the limit of "
            f"{limit:,}; scale it down or raise the limit (--max-pixels, or --limit image_pixels=N)"
        )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # Pillow warns about odd but readable files
            image.load()
    except (OSError, SyntaxError, ValueError, EOFError, MemoryError, Image.DecompressionBombError) as error:
        image.close()
        raise ImageReadError(
            f"cannot read {path}: the file is damaged or truncated ({_first_line(error)})"
        ) from None
    return image


def _open_unchecked(path):
    """``Image.open`` without Pillow's pixel limit, which :func:`open_image` replaces."""
    saved = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = None
    try:
        return Image.open(path)
    finally:
        Image.MAX_IMAGE_PIXELS = saved


def _first_line(error):
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__
