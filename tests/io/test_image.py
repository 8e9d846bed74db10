"""Tests for toonmotion.io.image and toonmotion.io.atomic."""

import numpy as np
import pytest
from PIL import Image

from toonmotion.errors import ImageReadError, ImageTooLargeError, MaskError, ToonmotionError
from toonmotion.io.atomic import atomic_path, write_bytes
from toonmotion.io.image import load_image, load_mask, png_bytes, save_png


def _rgba(h=12, w=17, seed=0):
    return np.random.default_rng(seed).integers(0, 256, size=(h, w, 4), dtype=np.uint8)


def _check_rgba(array, h, w):
    assert array.shape == (h, w, 4)
    assert array.dtype == np.uint8
    assert array.flags.writeable and array.flags.c_contiguous


def test_png_rgba_loads_exactly(tmp_path):
    rgba = _rgba()
    Image.fromarray(rgba, "RGBA").save(tmp_path / "a.png")
    out = load_image(tmp_path / "a.png")
    _check_rgba(out, 12, 17)
    np.testing.assert_array_equal(out, rgba)


@pytest.mark.parametrize("fmt", ["png", "bmp"])
def test_rgb_loads_with_opaque_alpha(tmp_path, fmt):
    rgb = _rgba()[..., :3]
    Image.fromarray(rgb, "RGB").save(tmp_path / f"a.{fmt}")
    out = load_image(str(tmp_path / f"a.{fmt}"))
    _check_rgba(out, 12, 17)
    np.testing.assert_array_equal(out[..., :3], rgb)
    assert np.all(out[..., 3] == 255)


def test_grey_png_loads_as_grey_rgb(tmp_path):
    grey = _rgba()[..., 0]
    Image.fromarray(grey, "L").save(tmp_path / "g.png")
    out = load_image(tmp_path / "g.png")
    _check_rgba(out, 12, 17)
    for c in range(3):
        np.testing.assert_array_equal(out[..., c], grey)
    assert np.all(out[..., 3] == 255)


def test_palette_png_loads_its_colours(tmp_path):
    index = np.arange(12 * 17, dtype=np.uint8).reshape(12, 17) % 3
    image = Image.fromarray(index, "P")
    image.putpalette([255, 0, 0, 0, 255, 0, 10, 20, 30] + [0] * (3 * 253))
    image.save(tmp_path / "p.png")
    out = load_image(tmp_path / "p.png")
    _check_rgba(out, 12, 17)
    palette = np.array([[255, 0, 0, 255], [0, 255, 0, 255], [10, 20, 30, 255]], dtype=np.uint8)
    np.testing.assert_array_equal(out, palette[index])


def test_palette_png_with_transparency_keeps_it(tmp_path):
    index = np.zeros((6, 6), dtype=np.uint8)
    index[2:4, 2:4] = 1
    image = Image.fromarray(index, "P")
    image.putpalette([0, 0, 0, 200, 100, 50] + [0] * (3 * 254))
    image.info["transparency"] = 0
    image.save(tmp_path / "t.png", transparency=0)
    out = load_image(tmp_path / "t.png")
    np.testing.assert_array_equal(out[..., 3], np.where(index == 1, 255, 0))
    np.testing.assert_array_equal(load_mask(tmp_path / "t.png"), index == 1)


def test_jpeg_loads_as_rgba(tmp_path):
    rgb = np.zeros((16, 24, 3), dtype=np.uint8)
    rgb[:, :12] = (200, 30, 30)
    rgb[:, 12:] = (30, 30, 200)
    Image.fromarray(rgb).save(tmp_path / "a.jpg", quality=95)
    out = load_image(tmp_path / "a.jpg")
    _check_rgba(out, 16, 24)
    assert np.all(out[..., 3] == 255)
    # Lossy, but away from the colour edge the colours survive.
    assert np.abs(out[4:12, 2:8, :3].astype(int) - (200, 30, 30)).max() <= 12
    assert np.abs(out[4:12, 16:22, :3].astype(int) - (30, 30, 200)).max() <= 12


def test_sixteen_bit_grey_is_scaled_to_eight_bits(tmp_path):
    grey = (np.arange(8 * 8, dtype=np.uint16).reshape(8, 8) * 1000).astype(np.uint16)
    Image.fromarray(grey).save(tmp_path / "16.png")
    out = load_image(tmp_path / "16.png")
    _check_rgba(out, 8, 8)
    assert out[..., 0].max() == 255 and out[0, 0, 0] == 0
    assert np.all(np.diff(out[..., 0].ravel().astype(int)) >= 0)  # order kept


def _check_one_line(error, path):
    message = str(error)
    assert "\n" not in message
    assert str(path) in message or path.name in message
    assert isinstance(error, ToonmotionError)


def test_missing_file(tmp_path):
    path = tmp_path / "nothing.png"
    with pytest.raises(ImageReadError, match="no such file") as info:
        load_image(path)
    _check_one_line(info.value, path)


def test_folder_is_not_an_image(tmp_path):
    with pytest.raises(ImageReadError, match="no such file"):
        load_image(tmp_path)


def test_text_file_named_png(tmp_path):
    path = tmp_path / "notes.png"
    path.write_text("this is not a picture\nreally\n")
    with pytest.raises(ImageReadError, match="not an image format Pillow knows") as info:
        load_image(path)
    _check_one_line(info.value, path)


def test_truncated_png(tmp_path):
    data = png_bytes(_rgba(64, 64))
    path = tmp_path / "cut.png"
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ImageReadError, match="damaged or truncated") as info:
        load_image(path)
    _check_one_line(info.value, path)


def test_empty_file(tmp_path):
    path = tmp_path / "empty.png"
    path.write_bytes(b"")
    with pytest.raises(ImageReadError) as info:
        load_image(path)
    _check_one_line(info.value, path)


def test_image_over_max_pixels_is_refused(tmp_path):
    path = tmp_path / "big.png"
    Image.fromarray(_rgba(10, 12)).save(path)
    assert load_image(path, max_pixels=120).shape == (10, 12, 4)
    with pytest.raises(ImageTooLargeError, match="--max-pixels") as info:
        load_image(path, max_pixels=119)
    assert "big.png is 12x10 = 120 pixels, over the limit of 119" in str(info.value)
    assert "\n" not in str(info.value)
    with pytest.raises(ImageTooLargeError):
        load_mask(path, max_pixels=119)


def test_load_mask_from_grey(tmp_path):
    grey = np.array([[0, 127, 128, 255], [255, 10, 200, 0]], dtype=np.uint8)
    Image.fromarray(grey, "L").save(tmp_path / "m.png")
    mask = load_mask(tmp_path / "m.png", size=(4, 2))
    assert mask.dtype == bool
    np.testing.assert_array_equal(mask, grey >= 128)


def test_load_mask_from_rgba_uses_transparency(tmp_path):
    rgba = np.zeros((5, 6, 4), dtype=np.uint8)
    rgba[..., :3] = 255  # white everywhere: brightness would say "all figure"
    rgba[1:4, 2:5, 3] = 255
    rgba[0, 0, 3] = 127
    rgba[4, 5, 3] = 128
    Image.fromarray(rgba, "RGBA").save(tmp_path / "m.png")
    mask = load_mask(tmp_path / "m.png")
    np.testing.assert_array_equal(mask, rgba[..., 3] >= 128)


def test_load_mask_from_opaque_rgb_uses_brightness(tmp_path):
    rgb = np.zeros((4, 4, 3), dtype=np.uint8)
    rgb[1:3, 1:3] = (250, 250, 250)
    rgb[0, 0] = (255, 0, 0)  # dark by luma (76)
    Image.fromarray(rgb, "RGB").save(tmp_path / "m.png")
    mask = load_mask(tmp_path / "m.png")
    expected = np.zeros((4, 4), dtype=bool)
    expected[1:3, 1:3] = True
    np.testing.assert_array_equal(mask, expected)


def test_load_mask_of_another_size_is_a_mask_error(tmp_path):
    Image.fromarray(np.zeros((5, 6), dtype=np.uint8), "L").save(tmp_path / "m.png")
    with pytest.raises(MaskError, match=r"mask m.png is 6x5 but the drawing is 5x6") as info:
        load_mask(tmp_path / "m.png", size=(5, 6))
    assert "\n" not in str(info.value)


def test_save_png_round_trips_and_leaves_no_temp_files(tmp_path):
    rgba = _rgba()
    save_png(tmp_path / "out.png", rgba)
    save_png(tmp_path / "mask.png", rgba[..., 3] > 100)
    save_png(tmp_path / "pil.png", Image.fromarray(rgba[..., :3]))
    save_png(tmp_path / "sub" / "deep.png", rgba)  # folders are made
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mask.png", "out.png", "pil.png", "sub"]
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["deep.png"]
    np.testing.assert_array_equal(load_image(tmp_path / "out.png"), rgba)
    np.testing.assert_array_equal(load_mask(tmp_path / "mask.png"), rgba[..., 3] > 100)
    np.testing.assert_array_equal(load_image(tmp_path / "pil.png")[..., :3], rgba[..., :3])
    with Image.open(tmp_path / "out.png") as image:
        assert image.format == "PNG"


@pytest.mark.parametrize(
    "bad",
    [np.zeros((4, 4, 5), dtype=np.uint8), np.zeros((4, 4), dtype=complex)],
    ids=["five-channels", "complex"],
)
def test_failed_save_png_keeps_the_old_file(tmp_path, bad):
    path = tmp_path / "keep.png"
    rgba = _rgba()
    save_png(path, rgba)
    before = path.read_bytes()
    with pytest.raises((TypeError, ValueError)):
        save_png(path, bad)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["keep.png"]


def test_error_mid_write_keeps_the_old_file_and_removes_the_temp(tmp_path):
    path = tmp_path / "keep.png"
    write_bytes(path, b"old")
    with pytest.raises(RuntimeError, match="disk on fire"):
        with atomic_path(path) as tmp:
            assert tmp.parent == tmp_path and tmp != path
            tmp.write_bytes(b"half a fi")
            raise RuntimeError("disk on fire")
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.png"]


def test_failed_rename_keeps_the_old_file(tmp_path, monkeypatch):
    import toonmotion.io.atomic as atomic

    path = tmp_path / "keep.png"
    write_bytes(path, b"old")

    def refuse(src, dst):
        raise OSError("rename refused")

    monkeypatch.setattr(atomic.os, "replace", refuse)
    with pytest.raises(OSError, match="rename refused"):
        write_bytes(path, b"new")
    assert path.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.png"]
