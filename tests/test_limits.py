"""Tests for toonmotion.limits and the limits at each boundary (each root cause of issue 11)."""

import json
import struct
import zlib

import numpy as np
import pytest

from toonmotion import limits
from toonmotion.animate.cartoon_filter import FilterSettings, cartoon_filter
from toonmotion.errors import ImageTooLargeError, LimitError, ProjectError, SkeletonError, ToonmotionError
from toonmotion.io.frames import load_frames
from toonmotion.io.image import load_image
from toonmotion.io.skeleton_json import load_skeleton_json
from toonmotion.render.raster import check_canvas
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.segment import clean_mask


def _bomb(path, width, height):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\0" * 64))
                     + chunk(b"IEND", b""))
    return path


def test_the_defaults_are_in_force_and_using_restores_them():
    assert limits.current() == limits.Limits()
    with limits.using(joints=5, canvas_side=100) as raised:
        assert (raised.joints, raised.canvas_side) == (5, 100)
        assert limits.current() is raised
    assert limits.current() == limits.Limits()


@pytest.mark.parametrize(("changes", "message"), [
    ({"nope": 1}, "no limit named 'nope'"),
    ({"joints": 0}, "takes a positive whole number"),
    ({"joints": 2.5}, "takes a positive whole number"),
    ({"frames": float("inf")}, "takes a finite number"),
    ({"frames": True}, "takes a finite number"),
])
def test_a_bad_limit_is_refused_in_one_line(changes, message):
    with pytest.raises(LimitError, match=message), limits.using(**changes):
        pass


def test_check_names_the_limit_and_how_to_raise_it():
    with pytest.raises(LimitError, match=r"the thing is over the limit joints=1,000 \(it is 1,001\); "
                                          r"trim it, or raise the limit with --limit joints=N"):
        limits.check("joints", 1001, "the thing", hint="trim it")
    with pytest.raises(LimitError):
        limits.check("joints", float("nan"), "a NaN")
    with pytest.raises(LimitError, match=r"\(it is 150,672,000\)"):  # a size worked out, not 1.50672e+08
        limits.check("canvas_pixels", 150_671_999.9, "the picture")
    assert issubclass(LimitError, ToonmotionError) and issubclass(ImageTooLargeError, LimitError)


@pytest.mark.parametrize("side", [10_000, 20_000, 100_000])
def test_a_decompression_bomb_is_refused_from_its_header_without_a_warning(tmp_path, side, recwarn):
    bomb = _bomb(tmp_path / "bomb.png", side, side)
    with pytest.raises(ImageTooLargeError, match=f"{side}x{side}"):
        load_image(bomb)
    with pytest.raises(ImageTooLargeError), limits.using(image_pixels=side * side - 1):
        load_image(bomb)
    assert not [w for w in recwarn if "DecompressionBomb" in type(w.message).__name__]


def test_a_bomb_among_frames_is_refused(tmp_path):
    folder = tmp_path / "frames"
    folder.mkdir()
    _bomb(folder / "f_0.png", 30_000, 30_000)
    with pytest.raises(ToonmotionError, match="30000x30000"):
        load_frames(folder)


def test_a_bomb_under_a_raised_limit_is_a_damaged_file_not_a_crash(tmp_path):
    bomb = _bomb(tmp_path / "bomb.png", 20_000, 20_000)
    with limits.using(image_pixels=10**12), pytest.raises(ToonmotionError, match="damaged or truncated"):
        load_image(bomb, max_pixels=10**12)


def test_the_canvas_limit_names_the_picture_size():
    check_canvas(16_384, 3_000)
    with pytest.raises(LimitError, match="20000x10 pixels, has a side that is over the limit canvas_side"):
        check_canvas(20_000, 10)
    with pytest.raises(LimitError, match="canvas_pixels"):
        check_canvas(10_000, 10_000)
    with pytest.raises(LimitError):
        check_canvas(float("inf"), 1)


def test_a_skeleton_over_the_joint_limit_is_refused_before_any_work():
    star = [("hub", None, (0.0, 0.0))] + [(f"j{i}", "hub", (float(i), 1.0)) for i in range(1000)]
    with pytest.raises(LimitError, match="joint count is over the limit joints=1,000 \\(it is 1,001\\)"):
        Skeleton.from_joints(star)
    with limits.using(joints=1001):
        assert len(Skeleton.from_joints(star)) == 1001


def test_a_speckled_mask_is_refused_with_a_hint():
    specks = np.zeros((100, 100), bool)
    specks[::4, ::4] = True
    with pytest.raises(LimitError, match="separate parts in the figure .* --largest-only"):
        clean_mask(specks)
    assert clean_mask(specks, largest_only=True).sum() == 1


def test_a_filter_wider_than_the_clip_costs_nothing_more_and_gives_the_same_result():
    x = np.cumsum(np.random.default_rng(1).normal(size=(30, 2)), axis=0)
    wide = cartoon_filter(x, FilterSettings(strength=1.0, sigma=1e9))
    wider = cartoon_filter(x, FilterSettings(strength=1.0, sigma=1e300, shift=0.0))
    np.testing.assert_allclose(wide, wider, atol=1e-9)
    far = cartoon_filter(x, FilterSettings(strength=1.0, sigma=3.0, shift=1e12))
    np.testing.assert_array_equal(far, x)  # a kernel a trillion frames away touches nothing
    just = cartoon_filter(x, FilterSettings(strength=1.0, sigma=40.0))
    exact = cartoon_filter(x, FilterSettings(strength=1.0, sigma=40.0 + 1e-12))
    np.testing.assert_allclose(just, exact, atol=1e-9)


def test_an_overflowing_filter_strength_is_a_filter_error():
    x = np.array([[0.0], [0.0], [10.0], [10.0]])
    with pytest.raises(ToonmotionError, match="beyond any finite position"):
        cartoon_filter(x, FilterSettings(strength=1e308))


@pytest.mark.parametrize("name", [1, [1], {"a": 1}, True])
def test_a_non_string_joint_name_is_refused_with_its_place(tmp_path, name):
    joints = [{"name": "root", "parent": None, "position": [1, 1]}, {"name": name, "parent": "root",
                                                                     "position": [2, 2]}]
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"format": "toonmotion.skeleton", "version": 1, "joints": joints}))
    with pytest.raises(SkeletonError, match=r"joints\[1\]\.name: Input should be a valid string"):
        load_skeleton_json(path)


def test_deeply_nested_json_is_refused(tmp_path):
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(SkeletonError, match="nested too deeply"):
        load_skeleton_json(path)


def test_integers_beyond_32_bits_in_a_project_are_refused(tmp_path):
    from toonmotion.io.project import load_project, save_project
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    drawing, skeleton = sample_character(scale=0.3)
    save_project(tmp_path / "P", rig_drawing(drawing, skeleton=skeleton))
    data = json.loads((tmp_path / "P" / "project.json").read_text())
    data["mesh"]["triangles"][0][0] = 2**70
    (tmp_path / "P" / "project.json").write_text(json.dumps(data))
    with pytest.raises(ProjectError, match="less than or equal to 2147483647"):
        load_project(tmp_path / "P")


def test_a_bvh_claiming_a_trillion_frames_is_refused_before_any_work(tmp_path):
    from toonmotion.io.bvh import load_bvh

    path = tmp_path / "huge.bvh"
    header = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 0\n End Site\n {\n  OFFSET 0 1 0\n }\n}\n"
    path.write_text(header + "MOTION\nFrames: 1000000000000\nFrame Time: 0.04\n")
    with pytest.raises(LimitError, match="frame count is over the limit frames=100,000"):
        load_bvh(path)


def test_the_overview_limit_is_on_the_picture_written():
    from toonmotion.render.overview import render_overview
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    drawing, skeleton = sample_character(scale=0.3)
    hero = rig_drawing(drawing, skeleton=skeleton)
    with pytest.raises(LimitError, match=r"the picture to draw, \d+x99000 pixels"):
        render_overview(hero, height=90_000)
    with limits.using(canvas_side=800):  # its panels are drawn at twice the size: no matter
        picture = render_overview(hero, height=510)
    assert max(picture.size) <= 800
