"""Tests for toonmotion.io.frames."""

import wave

import numpy as np
import pytest
from PIL import Image

from toonmotion.errors import ToonmotionError, VideoReadError
from toonmotion.io.frames import lay_on, load_frames
from toonmotion.io.image import save_png
from toonmotion.io.video import save_animation

H, W = 48, 64


def _frames(count, *, h=H, w=W):
    """Distinct RGB frames: a red square moving right over 8 x 8 tiles (few colours, so GIF is exact)."""
    y, x = np.mgrid[0:h, 0:w] // 8
    base = np.stack([25 * x + 40, 30 * y + 30, np.full_like(x, 120)], axis=2).astype(np.uint8)
    frames = []
    for i in range(count):
        frame = base.copy()
        frame[10:26, 4 + 3 * i : 20 + 3 * i] = (230, 40, 40)
        frames.append(frame)
    return np.stack(frames)


def _rgba(frames):
    return [np.dstack([f, np.full(f.shape[:2], 255, np.uint8)]) for f in frames]


def test_mp4_round_trip_is_close(tmp_path):
    truth = _frames(12)
    save_animation(tmp_path / "clip.mp4", _rgba(truth), fps=24)
    frames, fps = load_frames(tmp_path / "clip.mp4")
    assert frames.shape == truth.shape and frames.dtype == np.uint8
    assert fps == pytest.approx(24.0)
    # H.264 is lossy, but at crf 18 only slightly.
    assert np.abs(frames.astype(int) - truth).mean() < 3.0


def test_gif_round_trip_is_exact_and_fps_comes_from_durations(tmp_path):
    truth = _frames(8)
    save_animation(tmp_path / "clip.gif", _rgba(truth), fps=10)
    frames, fps = load_frames(tmp_path / "clip.gif")
    assert frames.shape == truth.shape
    assert fps == pytest.approx(10.0)
    # Later GIF frames store only the changed box; the reader composites them back.
    np.testing.assert_array_equal(frames, truth)



def test_a_gif_is_read_into_its_frames_without_a_second_copy(tmp_path):
    """Footage is held in memory (the footage_pixels limit counts it once): a GIF's frames are
    decoded straight into the array, not gathered in a list and copied (twice the memory)."""
    import tracemalloc

    truth = np.repeat(_frames(8), 4, axis=1).repeat(4, axis=2)  # larger frames: the arrays dominate
    save_animation(tmp_path / "clip.gif", _rgba(truth), fps=10)
    tracemalloc.start()
    try:
        frames, _ = load_frames(tmp_path / "clip.gif")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(frames, truth)
    assert peak < 1.5 * frames.nbytes, (peak, frames.nbytes)

def test_gif_holds_become_repeated_frames(tmp_path):
    truth = _frames(3)
    images = [Image.fromarray(f) for f in truth]
    images[0].save(tmp_path / "hold.gif", save_all=True, append_images=images[1:], duration=[100, 300, 100])
    frames, fps = load_frames(tmp_path / "hold.gif")
    assert len(frames) == 5 and fps == pytest.approx(10.0)
    np.testing.assert_array_equal(frames[1], frames[3])
    np.testing.assert_array_equal(frames[4], truth[2])


def test_png_folder_is_exact_and_in_natural_order(tmp_path):
    truth = _frames(12)
    for i, frame in enumerate(truth):
        save_png(tmp_path / f"frame_{i}.png", frame)  # frame_2 must come before frame_10
    (tmp_path / "notes.txt").write_text("not a frame")
    frames, fps = load_frames(tmp_path)
    assert fps is None
    np.testing.assert_array_equal(frames, truth)


def test_alpha_is_dropped(tmp_path):
    rgba = np.zeros((4, 5, 4), np.uint8)
    rgba[..., :3] = (10, 20, 30)
    rgba[0, 0, 3] = 255
    save_png(tmp_path / "a_1.png", rgba)
    frames, _ = load_frames(tmp_path)
    assert frames.shape == (1, 4, 5, 3)
    assert (frames == [10, 20, 30]).all()


def test_alpha_is_kept_when_asked_and_videos_are_opaque(tmp_path):
    rgba = np.zeros((4, 5, 4), np.uint8)
    rgba[..., :3] = (10, 20, 30)
    rgba[0, 0, 3] = 255
    rgba[1, 1, 3] = 100
    save_png(tmp_path / "a_1.png", rgba)
    frames, _ = load_frames(tmp_path, alpha=True)
    assert frames.shape == (1, 4, 5, 4) and np.array_equal(frames[0], rgba)
    # Laid on white: opaque pixels keep their colour, transparent ones are white.
    laid = lay_on(frames)
    assert laid[0, 0, 0].tolist() == [10, 20, 30] and laid[0, 3, 3].tolist() == [255, 255, 255]
    assert laid[0, 1, 1].tolist() == [round(100 / 255 * c + 155 / 255 * 255) for c in (10, 20, 30)]
    truth = _frames(3)
    save_animation(tmp_path / "clip.gif", _rgba(truth), fps=10)
    save_animation(tmp_path / "clip.mp4", _rgba(truth), fps=10)
    for name in ("clip.gif", "clip.mp4"):
        frames, _ = load_frames(tmp_path / name, alpha=True)
        assert frames.shape == (3, H, W, 4) and (frames[..., 3] == 255).all()


@pytest.mark.parametrize("pattern", ["f_%04d.png", "f_{:04d}.png", "f_%d.png"])
def test_file_pattern(tmp_path, pattern):
    truth = _frames(3)
    for i, frame in enumerate(truth):
        save_png(tmp_path / f"f_{9 + i:04d}.png", frame)  # 0009, 0010, 0011
    save_png(tmp_path / "other_0001.png", truth[0])
    frames, fps = load_frames(tmp_path / pattern)
    assert fps is None
    np.testing.assert_array_equal(frames, truth)


def test_missing_path(tmp_path):
    with pytest.raises(VideoReadError, match="nope.mp4: no such file or folder"):
        load_frames(tmp_path / "nope.mp4")


def test_undecodable_video_names_the_file(tmp_path):
    (tmp_path / "noise.mp4").write_bytes(np.random.default_rng(0).bytes(4000))
    with pytest.raises(VideoReadError, match=r"noise\.mp4: it could not be decoded") as info:
        load_frames(tmp_path / "noise.mp4")
    assert "\n" not in str(info.value)


def test_audio_without_video_says_so(tmp_path):
    with wave.open(str(tmp_path / "tone.wav"), "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(8000)
        out.writeframes(np.zeros(800, np.int16).tobytes())
    with pytest.raises(VideoReadError, match=r"tone\.wav: it could not be decoded as a video \(it has no"):
        load_frames(tmp_path / "tone.wav")


def test_undecodable_gif(tmp_path):
    (tmp_path / "noise.gif").write_bytes(b"GIF89a" + np.random.default_rng(0).bytes(100))
    with pytest.raises(VideoReadError, match="noise.gif"):
        load_frames(tmp_path / "noise.gif")


def test_empty_folder_and_unmatched_pattern(tmp_path):
    (tmp_path / "readme.txt").write_text("no images here")
    with pytest.raises(VideoReadError, match="no frames in"):
        load_frames(tmp_path)
    with pytest.raises(VideoReadError, match="no frames match"):
        load_frames(tmp_path / "f_%04d.png")
    with pytest.raises(VideoReadError, match="no such folder"):
        load_frames(tmp_path / "missing" / "f_%04d.png")
    with pytest.raises(VideoReadError, match="one number field"):
        load_frames(tmp_path / "f_%d_%d.png")


def test_frames_of_differing_sizes_name_the_frame_and_sizes(tmp_path):
    save_png(tmp_path / "f_1.png", _frames(1)[0])
    save_png(tmp_path / "f_2.png", _frames(1)[0])
    save_png(tmp_path / "f_3.png", _frames(1, h=40, w=50)[0])
    with pytest.raises(VideoReadError, match=r"f_3\.png is 50x40 but the first frame f_1\.png is 64x48"):
        load_frames(tmp_path)


def test_unreadable_image_in_folder_is_a_video_read_error(tmp_path):
    save_png(tmp_path / "f_1.png", _frames(1)[0])
    (tmp_path / "f_2.png").write_bytes(b"not a png")
    with pytest.raises(VideoReadError, match="f_2.png"):
        load_frames(tmp_path)


def test_too_many_frames(tmp_path):
    for i, frame in enumerate(_frames(4)):
        save_png(tmp_path / f"f_{i}.png", frame)
    with pytest.raises(VideoReadError, match="has 4 frames, over the limit of 3; cut the clip"):
        load_frames(tmp_path, max_frames=3)
    save_animation(tmp_path / "clip.mp4", _rgba(_frames(6)), fps=24)
    with pytest.raises(VideoReadError, match="more than 5 frames, over the limit of 5"):
        load_frames(tmp_path / "clip.mp4", max_frames=5)
    save_animation(tmp_path / "clip.gif", _rgba(_frames(6)), fps=24)
    with pytest.raises(VideoReadError, match="clip.gif has 6 frames"):
        load_frames(tmp_path / "clip.gif", max_frames=5)


def test_too_many_pixels(tmp_path):
    for i, frame in enumerate(_frames(4)):
        save_png(tmp_path / f"f_{i}.png", frame)
    with pytest.raises(VideoReadError, match="over the limit of 10,000; scale it down"):
        load_frames(tmp_path, max_pixels=10_000)  # 4 x 3072 pixels
    with pytest.raises(VideoReadError, match="over the limit of 3,000 per frame"):
        load_frames(tmp_path, max_pixels=3_000)


def test_long_video_is_refused_from_its_metadata_before_decoding(tmp_path):
    save_animation(tmp_path / "long.mp4", _rgba(_frames(1)) * 120, fps=24)
    with pytest.raises(VideoReadError, match="long.mp4 has about 120 frames, over the limit of 10"):
        load_frames(tmp_path / "long.mp4", max_frames=10)


def test_errors_are_one_line_toonmotion_errors(tmp_path):
    for path in (tmp_path / "x.mp4", tmp_path):
        with pytest.raises(ToonmotionError) as info:
            load_frames(path)
        assert "\n" not in str(info.value)


def test_bad_limits_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="max_frames"):
        load_frames(tmp_path, max_frames=0)
