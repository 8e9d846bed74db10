"""Tests for toonmotion.io.video."""

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image, ImageSequence

from toonmotion.errors import ExportError, ToonmotionError
from toonmotion.io.video import FORMATS, animation_format, save_animation

H, W = 24, 32


def _frames(count, *, h=H, w=W, alpha=255):
    """Distinct frames: a coloured square moving right over a flat, partly transparent field."""
    frames = []
    for i in range(count):
        rgba = np.zeros((h, w, 4), np.uint8)
        rgba[...] = (30, 160, 90, alpha)
        rgba[4:12, 2 + 2 * i: 10 + 2 * i] = (230, 40, 40, 255)
        frames.append(rgba)
    return frames


def _flat(rgba, background=(255, 255, 255)):
    a = rgba[..., 3:] / 255
    return rgba[..., :3] * a + np.array(background) * (1 - a)


def _luma(rgb):
    return float(np.dot([0.299, 0.587, 0.114], rgb))


def _gif_frames(path):
    with Image.open(path) as image:
        loop = image.info.get("loop")
        frames = [(np.asarray(f.convert("RGB")).astype(int), f.info["duration"])
                  for f in ImageSequence.Iterator(image)]
    return frames, loop


def _mp4_frames(path):
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    w, h = meta["size"]
    frames = [np.frombuffer(b, np.uint8).reshape(h, w, 3).astype(int) for b in reader]
    return meta, frames


def _failing(frames, after, error):
    yield from frames[:after]
    raise error


# --- animation_format ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "path, kind",
    [
        ("walk.gif", "gif"),
        ("out/Walk.GIF", "gif"),
        ("walk.mp4", "mp4"),
        ("frames", "png"),
        ("out/frame_%04d.png", "png"),
        ("out/f{:04d}.png", "png"),
    ],
)
def test_animation_format_from_the_path(path, kind):
    assert animation_format(path) == kind
    assert kind in FORMATS


def test_an_existing_folder_is_a_png_sequence_whatever_its_name(tmp_path):
    (tmp_path / "take.2").mkdir()
    assert animation_format(tmp_path / "take.2") == "png"


@pytest.mark.parametrize("path", ["walk.avi", "frames/frame_%04d.jpg"])
def test_animation_format_rejects_other_forms(path):
    with pytest.raises(ExportError, match=r"\.gif|\.png"):
        animation_format(path)


# --- GIF ---------------------------------------------------------------------------------------


def test_gif_round_trip(tmp_path):
    frames = _frames(5, alpha=128)
    path = tmp_path / "walk.gif"
    assert save_animation(path, frames, fps=10, background=(255, 255, 255)) == 5
    read, loop = _gif_frames(path)
    assert loop == 0  # loops forever
    assert len(read) == 5
    assert all(duration == 100 for _, duration in read)
    for (rgb, _), rgba in zip(read, frames, strict=True):
        assert rgb.shape == (H, W, 3)
        assert np.abs(rgb - _flat(rgba)).max() <= 3  # no dithering noise, close colours


def test_gif_timing_keeps_the_total_in_whole_centiseconds(tmp_path):
    path = tmp_path / "walk.gif"
    save_animation(path, _frames(12), fps=24)
    durations = [d for _, d in _gif_frames(path)[0]]
    assert set(durations) <= {40, 50}
    assert sum(durations) == 500  # 12 frames at 24 fps


def test_gif_keeps_many_colours_close(tmp_path):
    ys, xs = np.mgrid[0:64, 0:64]
    rgba = np.stack([xs * 4, ys * 4, (xs + ys) * 2, np.full_like(xs, 255)], axis=2).astype(np.uint8)
    frames = [rgba, np.roll(rgba, 3, axis=1)]
    save_animation(tmp_path / "ramp.gif", frames, fps=5)
    for (rgb, _), original in zip(_gif_frames(tmp_path / "ramp.gif")[0], frames, strict=True):
        error = np.abs(rgb - original[..., :3]).max(axis=2)
        assert error.mean() < 6 and error.max() <= 20


# --- MP4 ---------------------------------------------------------------------------------------


def test_mp4_round_trip_pads_odd_sizes_with_the_background(tmp_path):
    frames = _frames(6, h=23, w=31)
    path = tmp_path / "walk.mp4"
    assert save_animation(path, frames, fps=12, background=(0, 0, 255)) == 6
    meta, read = _mp4_frames(path)
    assert tuple(meta["size"]) == (32, 24)
    assert meta["fps"] == pytest.approx(12)
    assert len(read) == 6
    for rgb, rgba in zip(read, frames, strict=True):
        # Chroma is stored at half resolution, so the padding bleeds into the last column.
        inner = np.abs(rgb[:22, :30].mean(axis=(0, 1)) - _flat(rgba)[:22, :30].mean(axis=(0, 1)))
        assert inner.max() < 4
        # The padding column is background blue (compare luma: chroma is shared with column 30).
        assert abs(_luma(rgb[10, 31]) - _luma([0, 0, 255])) < 15
    # Not rescaled: the red square's edges stay on their pixels.
    assert read[0][8, 3, 0] > 180 and read[0][8, 11, 0] < 80


# --- PNG ---------------------------------------------------------------------------------------


def test_png_folder_keeps_alpha(tmp_path):
    frames = _frames(3, alpha=0)
    folder = tmp_path / "frames"
    assert save_animation(folder, iter(frames), fps=24) == 3
    assert sorted(p.name for p in folder.iterdir()) == [f"frame_0000{i}.png" for i in range(3)]
    for i, rgba in enumerate(frames):
        assert np.array_equal(np.asarray(Image.open(folder / f"frame_{i:05d}.png")), rgba)


@pytest.mark.parametrize("pattern, names", [("f_%03d.png", ["f_000.png", "f_001.png"]),
                                            ("f{:02d}.png", ["f00.png", "f01.png"])])
def test_png_pattern_names_the_frames(tmp_path, pattern, names):
    save_animation(tmp_path / "out" / pattern, _frames(2), fps=24)
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == names


def test_png_rewrite_removes_the_tail_of_a_longer_older_sequence(tmp_path):
    folder = tmp_path / "frames"
    save_animation(folder, _frames(5), fps=24)
    (folder / "notes.txt").write_text("mine")
    save_animation(folder, _frames(2), fps=24)
    assert sorted(p.name for p in folder.iterdir()) == ["frame_00000.png", "frame_00001.png", "notes.txt"]


# --- errors and atomicity ------------------------------------------------------------------------


@pytest.mark.parametrize("fps", [0, -5, float("nan"), float("inf"), "24", True, None])
def test_bad_fps_is_an_export_error(tmp_path, fps):
    with pytest.raises(ExportError, match="fps"):
        save_animation(tmp_path / "a.gif", _frames(2), fps=fps)


@pytest.mark.parametrize("name", ["a.gif", "a.mp4", "frames"])
def test_zero_frames_is_an_export_error_and_writes_nothing(tmp_path, name):
    with pytest.raises(ExportError, match="no frames"):
        save_animation(tmp_path / name, [], fps=10)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["a.gif", "a.mp4", "frames"])
def test_mismatched_frame_sizes_are_an_export_error(tmp_path, name):
    frames = _frames(2) + _frames(1, h=H + 2)
    with pytest.raises(ExportError, match="frame 2 is"):
        save_animation(tmp_path / name, frames, fps=10)


@pytest.mark.parametrize(
    "frame, match",
    [(np.zeros((H, W, 3), np.uint8), "RGBA"), (np.zeros((H, W, 4), np.float32), "uint8")],
)
def test_frames_that_are_not_rgba_bytes_are_an_export_error(tmp_path, frame, match):
    with pytest.raises(ExportError, match=match):
        save_animation(tmp_path / "a.gif", [frame], fps=10)


@pytest.mark.parametrize("background", [(255, 255), (0, 0, 256), (0.5, 0, 0), "white"])
def test_bad_background_is_an_export_error(tmp_path, background):
    with pytest.raises(ExportError, match="background"):
        save_animation(tmp_path / "a.gif", _frames(1), fps=10, background=background)


def test_pattern_without_a_number_field_is_an_export_error(tmp_path):
    with pytest.raises(ExportError, match="pattern"):
        save_animation(tmp_path / "f_{name}.png", _frames(1), fps=10)


@pytest.mark.parametrize("name", ["walk.gif", "walk.mp4"])
@pytest.mark.parametrize("error", [KeyboardInterrupt(), ToonmotionError("pose broke")])
def test_a_failure_midway_leaves_the_old_file_and_no_temporary(tmp_path, name, error):
    path = tmp_path / name
    save_animation(path, _frames(3), fps=10)
    before = path.read_bytes()
    with pytest.raises(type(error)):
        save_animation(path, _failing(_frames(4), 2, error), fps=10)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [name]


@pytest.mark.parametrize("error", [KeyboardInterrupt(), ToonmotionError("pose broke")])
def test_a_failure_midway_leaves_old_png_frames_untouched(tmp_path, error):
    folder = tmp_path / "frames"
    save_animation(folder, _frames(3), fps=10)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    with pytest.raises(type(error)):
        save_animation(folder, _failing(_frames(5)[::-1], 4, error), fps=10)
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before
    with pytest.raises(type(error)):
        save_animation(tmp_path / "new" / "f_%02d.png", _failing(_frames(3), 1, error), fps=10)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]


@pytest.mark.parametrize("name", ["a.gif", "a.apng", "a.webp"])
def test_formats_written_whole_are_refused_over_held_pixels_before_the_frames_pile_up(tmp_path, name):
    """GIF, APNG and WebP are written by Pillow from every frame at once: their pixels count
    against held_pixels as the frames come, and the frames after the refusal are never drawn."""
    from toonmotion import limits
    from toonmotion.errors import LimitError

    drawn = []

    def frames():
        for i in range(50):
            drawn.append(i)
            yield np.zeros((40, 50, 4), np.uint8)

    (tmp_path / name).write_bytes(b"earlier")
    with limits.using(held_pixels=10 * 40 * 50), pytest.raises(LimitError, match="held_pixels=20,000"):
        save_animation(tmp_path / name, frames(), fps=12)
    assert len(drawn) == 11 and (tmp_path / name).read_bytes() == b"earlier"
    with limits.using(held_pixels=10 * 40 * 50):  # MP4 and PNG frames are written a frame at a time
        assert save_animation(tmp_path / "a.mp4", frames(), fps=12) == 50
