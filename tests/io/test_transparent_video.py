"""Tests for the formats of toonmotion.io.video that keep alpha: APNG, animated WebP and WebM (VP9)."""

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image, ImageSequence

from toonmotion.errors import ExportError, ToonmotionError
from toonmotion.io.ffmpeg_video import read_webm_rgba
from toonmotion.io.video import (
    FORMATS,
    TRANSPARENT_FORMATS,
    animation_format,
    frame_durations,
    save_animation,
)

FPS = 12.0


@pytest.fixture(scope="module")
def rendered(sample_frames):
    """Ten rendered frames of the sample character (the WebM bounds below were measured on them)."""
    return sample_frames[:10]


@pytest.fixture(scope="module")
def held(rendered):
    """The rendered frames with frame 3 held for a second frame and colour under clear pixels."""
    frames = [f.copy() for f in rendered]
    frames.insert(4, frames[3].copy())
    clear = frames[6][..., 3] == 0
    frames[6][clear, :3] = (77, 140, 9)
    return frames


def _decoded(path):
    """Every frame Pillow decodes, as RGBA, with its duration in ms and the file's loop count."""
    with Image.open(path) as image:
        loop = image.info.get("loop")
        frames = [(np.asarray(f.convert("RGBA")).copy(), f.info.get("duration"))
                  for f in ImageSequence.Iterator(image)]
    return frames, loop


def _runs(frames, fps):
    """Runs of identical consecutive frames: (frame, summed duration in ms)."""
    runs = []
    for rgba, duration in zip(frames, frame_durations(len(frames), fps), strict=True):
        if runs and np.array_equal(runs[-1][0], rgba):
            runs[-1][1] += duration
        else:
            runs.append([rgba, duration])
    return runs


def _cleared(rgba):
    rgba = rgba.copy()
    rgba[rgba[..., 3] == 0] = 0
    return rgba


def _failing(frames, after, error):
    yield from frames[:after]
    raise error


def _synthetic(count, *, h=23, w=31):
    """Distinct odd-sized frames: a half-transparent field, an opaque square moving right, a clear
    band at the top, and opaque pixels in the last row and column."""
    frames = []
    for i in range(count):
        rgba = np.zeros((h, w, 4), np.uint8)
        rgba[6:, :] = (30, 160, 90, 128)
        rgba[10:18, 2 + 2 * i: 10 + 2 * i] = (230, 40, 40, 255)
        rgba[-1, :] = rgba[:, -1] = (20, 20, 200, 255)
        frames.append(rgba)
    return frames


# --- animation_format -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "path, kind",
    [("walk.png", "apng"), ("out/Walk.APNG", "apng"), ("walk.webp", "webp"), ("walk.WebM", "webm"),
     ("frames", "png"), ("out/f_%04d.png", "png")],
)
def test_new_formats_from_the_path(path, kind):
    assert animation_format(path) == kind
    assert kind in FORMATS and kind in TRANSPARENT_FORMATS


def test_an_existing_folder_named_like_a_png_still_means_png_frames(tmp_path):
    (tmp_path / "take.png").mkdir()
    assert animation_format(tmp_path / "take.png") == "png"


@pytest.mark.parametrize("path", ["walk.avi", "walk.webmx", "frames/frame_%04d.webp"])
def test_other_forms_are_rejected_naming_the_new_formats(path):
    with pytest.raises(ExportError, match=r"\.webm|\.png"):
        animation_format(path)


# --- APNG and WebP: lossless ---------------------------------------------------------------------


def test_apng_frames_decode_back_exactly_with_their_durations(tmp_path, held):
    path = tmp_path / "walk.png"
    assert save_animation(path, iter(held), fps=FPS) == len(held)
    read, loop = _decoded(path)
    assert loop == 0
    runs = _runs(held, FPS)
    assert len(read) == len(runs) == len(held) - 1  # the held frame shows once, twice as long
    for (rgba, duration), (expected, total) in zip(read, runs, strict=True):
        assert np.array_equal(rgba, expected)  # every RGBA value, colour under clear pixels too
        assert duration == pytest.approx(total, abs=1e-6)
    assert abs(sum(d for _, d in read) - len(held) / FPS * 1000) <= 1


def test_apng_frame_times_are_whole_milliseconds_on_time(tmp_path, rendered):
    path = tmp_path / "walk.apng"
    save_animation(path, rendered, fps=24)
    durations = [d for _, d in _decoded(path)[0]]
    assert len(durations) == len(rendered)
    assert set(durations) <= {41, 42}
    assert abs(sum(durations) - len(rendered) / 24 * 1000) <= 1


def test_webp_frames_decode_back_exactly_where_visible(tmp_path, held):
    path = tmp_path / "walk.webp"
    assert save_animation(path, held, fps=FPS) == len(held)
    read, loop = _decoded(path)
    assert loop == 0
    runs = _runs([_cleared(f) for f in held], FPS)
    assert len(read) == len(runs) == len(held) - 1
    for (rgba, duration), (expected, total) in zip(read, runs, strict=True):
        # Exact wherever alpha > 0; fully clear pixels are stored as (0, 0, 0, 0).
        assert np.array_equal(rgba, expected)
        assert duration == total
    assert abs(sum(d for _, d in read) - len(held) / FPS * 1000) <= 1


@pytest.mark.parametrize("name", ["one.png", "one.webp"])
def test_a_single_frame_is_kept_exactly(tmp_path, rendered, name):
    save_animation(tmp_path / name, rendered[:1], fps=FPS)
    read, _ = _decoded(tmp_path / name)
    assert len(read) == 1 and np.array_equal(read[0][0], rendered[0])


@pytest.mark.parametrize("name", ["walk.png", "walk.webp"])
def test_alpha_formats_ignore_the_background(tmp_path, rendered, name):
    save_animation(tmp_path / name, rendered[:3], fps=FPS, background=(0, 0, 255))
    read, _ = _decoded(tmp_path / name)
    assert all(np.array_equal(rgba, expected) for (rgba, _), expected in zip(read, rendered[:3], strict=True))


# --- WebM: VP9 with alpha ----------------------------------------------------------------------------

# Alpha error bounds: measured on these frames with CRF 10 and the bundled ffmpeg 9.0 / libvpx, mean
# absolute error 0.096, 99th percentile 2, clear pixels at most alpha 8, opaque ones at least 241 (and
# colours of opaque pixels off by 7.4 on average), with a little room for other libvpx builds.
ALPHA_MEAN, ALPHA_P99, CLEAR_MAX, OPAQUE_MIN = 0.12, 2, 12, 238


def test_webm_keeps_alpha_within_the_codecs_loss(tmp_path, rendered):
    path = tmp_path / "walk.webm"
    assert save_animation(path, iter(rendered), fps=FPS, background=(0, 0, 255)) == len(rendered)
    read = read_webm_rgba(path)
    assert read.shape == (len(rendered), 120, 96, 4) and read.dtype == np.uint8
    truth = np.stack(rendered)[..., 3].astype(int)
    alpha = read[..., 3].astype(int)
    error = np.abs(alpha - truth)
    assert error.mean() <= ALPHA_MEAN
    assert np.percentile(error, 99) <= ALPHA_P99
    assert alpha[truth == 0].max() <= CLEAR_MAX  # clear stays clear: no ghost of the background
    assert alpha[truth == 255].min() >= OPAQUE_MIN
    # Colours of opaque pixels survive too (outlines make 4:2:0 chroma the largest error).
    opaque = truth == 255
    colour = np.abs(read[..., :3].astype(int) - np.stack(rendered)[..., :3])[opaque]
    assert colour.mean() <= 8.5


def test_webm_keeps_odd_sizes_and_the_frame_rate(tmp_path):
    frames = _synthetic(5)
    path = tmp_path / "odd.webm"
    save_animation(path, frames, fps=FPS)
    read = read_webm_rgba(path)
    assert read.shape == (5, 23, 31, 4)  # not padded: VP9 codes odd sizes
    truth = np.stack(frames)
    assert np.abs(read[..., 3].astype(int) - truth[..., 3]).max() <= 3  # measured 2: flat alpha codes well
    assert read[:, -1, :, 3].min() >= OPAQUE_MIN and read[:, :, -1, 3].min() >= OPAQUE_MIN
    assert read[:, :4, :-2, 3].max() <= CLEAR_MAX
    reader = imageio_ffmpeg.read_frames(str(path))
    try:
        meta = next(reader)
    finally:
        reader.close()
    assert meta["codec"] == "vp9" and meta["fps"] == pytest.approx(FPS)


def test_read_webm_rgba_refuses_what_it_cannot_decode(tmp_path):
    with pytest.raises(ExportError, match="no such file"):
        read_webm_rgba(tmp_path / "missing.webm")
    (tmp_path / "junk.webm").write_bytes(b"not a video")
    with pytest.raises(ExportError, match="cannot decode junk.webm"):
        read_webm_rgba(tmp_path / "junk.webm")
    save_animation(tmp_path / "clip.mp4", _synthetic(2, h=24, w=32), fps=FPS)
    with pytest.raises(ExportError, match="cannot decode clip.mp4"):
        read_webm_rgba(tmp_path / "clip.mp4")


# --- errors and atomicity ------------------------------------------------------------------------------

NEW = ["walk.png", "walk.apng", "walk.webp", "walk.webm"]


@pytest.mark.parametrize("name", NEW)
def test_zero_frames_is_an_export_error_and_writes_nothing(tmp_path, name):
    with pytest.raises(ExportError, match="no frames to write"):
        save_animation(tmp_path / name, iter([]), fps=FPS)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", NEW)
def test_mismatched_frame_sizes_are_an_export_error(tmp_path, name):
    frames = _synthetic(2) + _synthetic(1, h=25)
    with pytest.raises(ExportError, match="frame 2 is 31x25 but frame 0 is 31x23"):
        save_animation(tmp_path / name, frames, fps=FPS)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", NEW)
@pytest.mark.parametrize("error", [KeyboardInterrupt(), ToonmotionError("pose broke")])
def test_a_failure_midway_leaves_the_old_file_and_no_temporary(tmp_path, name, error):
    path = tmp_path / name
    save_animation(path, _synthetic(3), fps=FPS)
    before = path.read_bytes()
    with pytest.raises(type(error)):
        save_animation(path, _failing(_synthetic(5)[::-1], 3, error), fps=FPS)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_webp_refuses_frames_too_big_for_it(tmp_path):
    frame = np.zeros((2, 16384, 4), np.uint8)
    with pytest.raises(ExportError, match="too big for WebP"):
        save_animation(tmp_path / "wide.webp", [frame], fps=FPS)
    assert list(tmp_path.iterdir()) == []
