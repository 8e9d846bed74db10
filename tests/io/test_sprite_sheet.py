"""Tests for toonmotion.io.exchange.sprite_sheet: TexturePacker JSON (Hash) atlases and their packed
sheets."""

import json
from itertools import combinations

import numpy as np
import pytest
from PIL import Image

import toonmotion
from toonmotion.errors import ExportError, ToonmotionError
from toonmotion.io.exchange.sprite_sheet import SheetLayout, save_sprite_sheet

FPS = 12.0


@pytest.fixture(scope="module")
def rendered(sample_frames):
    return sample_frames


@pytest.fixture(scope="module")
def on_twos(rendered):
    """Animation on twos: every drawing held for two frames."""
    return [f for f in rendered[:6] for _ in range(2)]


def _read(path):
    atlas = json.loads(path.read_text())
    sheet = np.asarray(Image.open(path.with_suffix(".png")).convert("RGBA"))
    return atlas, sheet


def _rebuilt(atlas, sheet):
    """Every frame, rebuilt as a game engine would: its rectangle cut out of the sheet and placed
    at spriteSourceSize in a clear canvas of sourceSize."""
    frames = []
    for entry in atlas["frames"].values():
        f, s, size = entry["frame"], entry["spriteSourceSize"], entry["sourceSize"]
        assert (f["w"], f["h"]) == (s["w"], s["h"]) and entry["rotated"] is False
        canvas = np.zeros((size["h"], size["w"], 4), np.uint8)
        drawing = sheet[f["y"]:f["y"] + f["h"], f["x"]:f["x"] + f["w"]]
        canvas[s["y"]:s["y"] + s["h"], s["x"]:s["x"] + s["w"]] = drawing
        frames.append(canvas)
    return frames


def _rects(atlas):
    return {tuple(e["frame"][k] for k in "xywh") for e in atlas["frames"].values()}


def _clear_outside(rgba):
    """``rgba`` with its clear pixels set to (0, 0, 0, 0), as trimming leaves them."""
    rgba = rgba.copy()
    rgba[rgba[..., 3] == 0] = 0
    return rgba


def _failing(frames, after, error):
    yield from frames[:after]
    raise error


def _leftovers(folder):
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp")]


# --- the sheet rebuilds every frame --------------------------------------------------------------


@pytest.mark.parametrize("trim", [True, False])
@pytest.mark.parametrize("padding", [0, 2, 5])
def test_every_frame_is_rebuilt_exactly_from_the_sheet(tmp_path, rendered, trim, padding):
    path = tmp_path / "walk.json"
    layout = save_sprite_sheet(path, iter(rendered), fps=FPS, padding=padding, trim=trim)
    atlas, sheet = _read(path)
    assert sheet.shape[:2] == (layout.size[1], layout.size[0])
    # The renderer leaves clear pixels (0, 0, 0, 0), so even trimmed frames come back exactly.
    assert all(np.array_equal(f, _clear_outside(f)) for f in rendered)
    for rebuilt, frame in zip(_rebuilt(atlas, sheet), rendered, strict=True):
        assert np.array_equal(rebuilt, frame)
    entries = list(atlas["frames"].values())
    assert all(e["trimmed"] is trim for e in entries)  # every rendered frame has a clear border
    if trim:
        assert sum(e["frame"]["w"] * e["frame"]["h"] for e in entries) < 0.6 * len(rendered) * 96 * 120


def test_untrimmed_frames_keep_the_colour_under_clear_pixels(tmp_path, rendered):
    frame = rendered[0].copy()
    frame[frame[..., 3] == 0, :3] = (12, 34, 56)
    save_sprite_sheet(tmp_path / "a.json", [frame], fps=FPS, trim=False)
    assert np.array_equal(_rebuilt(*_read(tmp_path / "a.json"))[0], frame)
    save_sprite_sheet(tmp_path / "b.json", [frame], fps=FPS, trim=True)
    # Trimmed, the colour is kept inside the box round the visible pixels, not outside it.
    rows, cols = np.flatnonzero(frame[..., 3].any(axis=1)), np.flatnonzero(frame[..., 3].any(axis=0))
    inside = np.zeros(frame.shape[:2], bool)
    inside[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1] = True
    assert (~inside).any() and (inside & (frame[..., 3] == 0)).any()
    assert np.array_equal(_rebuilt(*_read(tmp_path / "b.json"))[0], np.where(inside[..., None], frame, 0))


@pytest.mark.parametrize("padding", [0, 1, 3])
def test_rectangles_never_overlap_and_keep_the_padding(tmp_path, rendered, padding):
    path = tmp_path / "walk.json"
    layout = save_sprite_sheet(path, rendered, fps=FPS, padding=padding)
    atlas, sheet = _read(path)
    W, H = layout.size
    rects = _rects(atlas)
    assert len(rects) == len(rendered)
    for x, y, w, h in rects:
        assert x >= padding and y >= padding and x + w + padding <= W and y + h + padding <= H
    for (ax, ay, aw, ah), (bx, by, bw, bh) in combinations(rects, 2):
        apart_x = ax + aw + padding <= bx or bx + bw + padding <= ax
        apart_y = ay + ah + padding <= by or by + bh + padding <= ay
        assert apart_x or apart_y
    # Nothing but the frames is drawn: the sheet is clear outside every rectangle.
    covered = np.zeros((H, W), bool)
    for x, y, w, h in rects:
        covered[y:y + h, x:x + w] = True
    assert not sheet[~covered].any()
    # Roughly square, and tight: the frames fill a good part of it.
    assert max(W, H) <= 1.6 * min(W, H)
    assert sum(w * h for _, _, w, h in rects) >= 0.5 * W * H


def test_held_drawings_share_one_rectangle(tmp_path, on_twos):
    path = tmp_path / "twos.json"
    layout = save_sprite_sheet(path, on_twos, fps=FPS)
    atlas, sheet = _read(path)
    rects = [f.rect for f in layout.frames]
    assert len(set(rects)) == 6
    assert all(rects[2 * i] == rects[2 * i + 1] for i in range(6))
    assert all(np.array_equal(a, b) for a, b in zip(_rebuilt(atlas, sheet), on_twos, strict=True))


def test_a_drawing_that_moves_shares_its_rectangle_at_another_offset(tmp_path):
    frame = np.zeros((20, 30, 4), np.uint8)
    frame[4:9, 3:10] = (200, 100, 0, 255)
    moved = np.roll(frame, (6, 11), axis=(0, 1))
    layout = save_sprite_sheet(tmp_path / "slide.json", [frame, moved], fps=FPS)
    assert layout.frames[0].rect == layout.frames[1].rect
    assert (layout.frames[0].offset, layout.frames[1].offset) == ((3, 4), (14, 10))
    rebuilt = _rebuilt(*_read(tmp_path / "slide.json"))
    assert np.array_equal(rebuilt[0], frame) and np.array_equal(rebuilt[1], moved)


def test_a_fully_clear_frame_is_one_clear_pixel(tmp_path, rendered):
    clear = np.zeros_like(rendered[0])
    layout = save_sprite_sheet(tmp_path / "fade.json", [rendered[0], clear], fps=FPS)
    atlas, sheet = _read(tmp_path / "fade.json")
    entry = atlas["frames"]["frame_0001"]
    assert entry["trimmed"] is True
    assert entry["spriteSourceSize"] == {"x": 0, "y": 0, "w": 1, "h": 1}
    assert (entry["frame"]["w"], entry["frame"]["h"]) == (1, 1)
    assert layout.frames[1].rect[2:] == (1, 1)
    assert np.array_equal(_rebuilt(atlas, sheet)[1], clear)


def test_an_opaque_frame_is_not_trimmed(tmp_path):
    frame = np.full((6, 9, 4), 255, np.uint8)
    layout = save_sprite_sheet(tmp_path / "a.json", [frame], fps=FPS, padding=0)
    assert layout.frames[0].trimmed is False and layout.frames[0].rect == (0, 0, 9, 6)
    assert layout.size == (9, 6)


# --- the atlas ------------------------------------------------------------------------------------


def test_the_atlas_is_texturepacker_json_hash(tmp_path, on_twos):
    path = tmp_path / "hop.json"
    layout = save_sprite_sheet(path, on_twos, fps=FPS, name="hop", padding=2)
    assert isinstance(layout, SheetLayout)
    atlas = json.loads(path.read_text())
    assert list(atlas) == ["frames", "animations", "meta"]
    names = [f"hop_{i:04d}" for i in range(len(on_twos))]
    assert list(atlas["frames"]) == names  # in frame order
    assert atlas["animations"] == {"hop": names}
    assert atlas["meta"] == {
        "app": "toonmotion", "version": toonmotion.__version__, "image": "hop.png", "format": "RGBA8888",
        "size": {"w": layout.size[0], "h": layout.size[1]}, "scale": "1",
    }
    for entry, frame in zip(atlas["frames"].values(), layout.frames, strict=True):
        assert set(entry) == {"frame", "rotated", "trimmed", "spriteSourceSize", "sourceSize", "duration"}
        assert entry["frame"] == dict(zip("xywh", frame.rect, strict=True))
        assert entry["spriteSourceSize"] == {"x": frame.offset[0], "y": frame.offset[1],
                                             "w": frame.rect[2], "h": frame.rect[3]}
        assert entry["sourceSize"] == {"w": 96, "h": 120}
        assert entry["rotated"] is False and entry["trimmed"] is frame.trimmed
        assert isinstance(entry["duration"], int) and entry["duration"] == frame.duration
    durations = [e["duration"] for e in atlas["frames"].values()]
    assert set(durations) <= {83, 84}  # 1000 / 12 in whole ms
    assert abs(sum(durations) - len(on_twos) / FPS * 1000) <= 1


def test_durations_keep_the_total_on_time(tmp_path):
    frames = [np.full((2, 2, 4), 255, np.uint8)] * 7
    layout = save_sprite_sheet(tmp_path / "a.json", frames, fps=24)
    assert [f.duration for f in layout.frames] == [42, 41, 42, 42, 41, 42, 42]
    assert sum(f.duration for f in layout.frames) == round(7 / 24 * 1000)


def test_frame_keys_get_more_digits_for_many_frames(tmp_path):
    frames = (np.full((1, 1, 4), 255, np.uint8) for _ in range(10001))
    layout = save_sprite_sheet(tmp_path / "long.json", frames, fps=100)
    assert (layout.frames[0].name, layout.frames[-1].name) == ("frame_00000", "frame_10000")
    assert len({f.rect for f in layout.frames}) == 1


# --- max_size --------------------------------------------------------------------------------------


def test_a_sheet_too_big_is_refused_and_the_old_pair_kept(tmp_path, rendered):
    path = tmp_path / "walk.json"
    layout = save_sprite_sheet(path, rendered, fps=FPS)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    side = max(layout.size)
    with pytest.raises(ExportError, match=r"need a sheet of .* but max_size is 150, which holds") as caught:
        save_sprite_sheet(path, rendered, fps=FPS, max_size=150)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    # The numbers in the message are true: that many frames fit, one more does not, and the size
    # it asks for holds them all.
    message = str(caught.value)
    fit = int(message.split("holds the first ")[1].split(":")[0])
    asked = int(message.split("raise max_size to ")[1].split(",")[0])
    assert 0 < fit < len(rendered) and asked == side
    save_sprite_sheet(tmp_path / "some.json", rendered[:fit], fps=FPS, max_size=150)
    with pytest.raises(ExportError, match="max_size"):
        save_sprite_sheet(tmp_path / "more.json", rendered[:fit + 1], fps=FPS, max_size=150)
    save_sprite_sheet(tmp_path / "all.json", rendered, fps=FPS, max_size=asked)


def test_a_frame_bigger_than_max_size_is_named(tmp_path, rendered):
    with pytest.raises(ExportError, match=r"frame 0 is \d+x\d+ pixels .* more than max_size 60"):
        save_sprite_sheet(tmp_path / "walk.json", rendered, fps=FPS, max_size=60)
    assert list(tmp_path.iterdir()) == []


# --- bad input and atomicity --------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["walk.png", "walk.txt", "walk"])
def test_the_atlas_must_be_json(tmp_path, rendered, name):
    with pytest.raises(ExportError, match=r"give a \.json file"):
        save_sprite_sheet(tmp_path / name, rendered[:1], fps=FPS)


def test_no_frames_is_an_export_error_and_writes_nothing(tmp_path):
    with pytest.raises(ExportError, match="no frames to write to walk.json"):
        save_sprite_sheet(tmp_path / "walk.json", iter([]), fps=FPS)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("padding", [-1, 1.5, True, "2", None])
def test_bad_padding_is_an_export_error(tmp_path, rendered, padding):
    with pytest.raises(ExportError, match="padding must be a whole number"):
        save_sprite_sheet(tmp_path / "walk.json", rendered[:1], fps=FPS, padding=padding)


@pytest.mark.parametrize(
    "options, match",
    [({"max_size": 0}, "max_size must be"), ({"name": ""}, "name must be"), ({"fps": 0}, "fps")],
)
def test_other_bad_options_are_export_errors(tmp_path, rendered, options, match):
    with pytest.raises(ExportError, match=match):
        save_sprite_sheet(tmp_path / "walk.json", rendered[:1], **{"fps": FPS, **options})


@pytest.mark.parametrize(
    "frames, match",
    [([np.zeros((4, 4, 3), np.uint8)], "RGBA"),
     ([np.zeros((4, 4, 4), np.uint8), np.zeros((5, 4, 4), np.uint8)], "frame 1 is 4x5")],
)
def test_frames_are_checked(tmp_path, frames, match):
    with pytest.raises(ExportError, match=match):
        save_sprite_sheet(tmp_path / "walk.json", frames, fps=FPS)


@pytest.mark.parametrize("error", [KeyboardInterrupt(), ToonmotionError("pose broke")])
def test_a_failure_midway_leaves_the_old_pair_and_no_temporary(tmp_path, rendered, error):
    path = tmp_path / "walk.json"
    save_sprite_sheet(path, rendered[:4], fps=FPS)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    assert sorted(before) == ["walk.json", "walk.png"]
    with pytest.raises(type(error)):
        save_sprite_sheet(path, _failing(rendered[::-1], 5, error), fps=FPS)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    with pytest.raises(type(error)):
        save_sprite_sheet(tmp_path / "new" / "hop.json", _failing(rendered, 2, error), fps=FPS)
    assert not (tmp_path / "new").exists() or list((tmp_path / "new").iterdir()) == []
    assert _leftovers(tmp_path) == []


def test_a_failure_writing_leaves_no_half_pair(tmp_path, rendered, monkeypatch):
    path = tmp_path / "walk.json"
    save_sprite_sheet(path, rendered[:4], fps=FPS)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("pathlib.Path.write_text", broken)  # the sheet is written, the atlas fails
    with pytest.raises(OSError, match="disk full"):
        save_sprite_sheet(path, rendered, fps=FPS)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    assert _leftovers(tmp_path) == []
