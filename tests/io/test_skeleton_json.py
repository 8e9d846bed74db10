"""Tests for toonmotion.io.skeleton_json and load_skeleton_file."""

import json
import re

import numpy as np
import pytest

from toonmotion.errors import SkeletonError
from toonmotion.io.char_cfg import save_char_cfg
from toonmotion.io.skeleton_json import (
    FORMAT,
    VERSION,
    load_skeleton_file,
    load_skeleton_json,
    save_skeleton_json,
    skeleton_from_dict,
    skeleton_to_dict,
)
from toonmotion.rig.skeleton import Skeleton

AWKWARD = [
    ("root", None, (0.1 + 0.2, 1.0 / 3.0)),
    ("arm", "root", (-1e-300, 9876543.123456789)),
    ("hand", "arm", (5e-324, np.nextafter(1.0, 2.0))),
    ("ünïcode joint", "root", (-0.0, 2.0**23 + 2.0**-29)),  # every mantissa bit, within MAX_COORDINATE
    ("hat", None, (np.pi, -np.e)),
]


def _skeleton():
    return Skeleton.from_joints(AWKWARD)


def _same(a, b):
    assert a.names == b.names
    np.testing.assert_array_equal(a.parents, b.parents)
    # Bit-identical, not just close.
    assert a.positions.tobytes() == b.positions.tobytes()


@pytest.mark.parametrize("size", [None, (320, 200)])
def test_json_round_trip_is_exact(tmp_path, size):
    skeleton = _skeleton()
    path = tmp_path / "s.json"
    save_skeleton_json(path, skeleton, size)
    loaded, loaded_size = load_skeleton_json(path)
    _same(loaded, skeleton)
    assert loaded_size == size
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["format"] == FORMAT and data["version"] == VERSION
    assert [j["name"] for j in data["joints"]] == list(skeleton.names)
    # A second save writes the same bytes.
    save_skeleton_json(tmp_path / "t.json", loaded, size)
    assert (tmp_path / "t.json").read_bytes() == path.read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.json", "t.json"]


def test_dict_round_trip_is_exact():
    skeleton = _skeleton()
    _same(skeleton_from_dict(skeleton_to_dict(skeleton)), skeleton)


def test_load_skeleton_file_reads_both_formats(tmp_path, drawings_root):
    skeleton = _skeleton()
    save_skeleton_json(tmp_path / "s.JSON", skeleton, (320, 200))
    _same(load_skeleton_file(tmp_path / "s.JSON", image_size=(320, 200)), skeleton)
    save_char_cfg(tmp_path / "s.yml", skeleton, (320, 200))
    from_yaml = load_skeleton_file(tmp_path / "s.yml", image_size=(320, 200))
    assert from_yaml.names == skeleton.names
    np.testing.assert_allclose(from_yaml.positions, skeleton.positions, atol=5e-4)
    shared = load_skeleton_file(drawings_root / "char1" / "char_cfg.yaml", image_size=(508, 602))
    assert len(shared) == 16


def test_no_size_in_the_file_skips_the_size_check(tmp_path):
    save_skeleton_json(tmp_path / "s.json", _skeleton())
    assert len(load_skeleton_file(tmp_path / "s.json", image_size=(1, 1))) == 5


def _json(tmp_path, data, name="s.json"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data))
    return path


def _valid(**changes):
    data = {"format": FORMAT, "version": VERSION, "width": 10, "height": 20,
            "joints": [{"name": "root", "parent": None, "position": [1, 2]}]}
    data.update(changes)
    return data


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ("{not json", r"cannot read .*s.json as JSON: "),
        ([1, 2], r"s.json is not a toonmotion skeleton file \(format 'toonmotion.skeleton'\)"),
        (_valid(format="toonmotion.project"), r"is not a toonmotion skeleton file"),
        ({"joints": []}, r"is not a toonmotion skeleton file"),
        (_valid(version=2), r"is skeleton format version 2; this toonmotion reads version 1"),
        (_valid(version="1"), r"is skeleton format version '1'"),
        (_valid(joints={"root": [1, 2]}), r"s.json: 'joints' must be a list"),
        (_valid(joints=None), r"'joints' must be a list"),
        (_valid(joints=[]), r"the skeleton has no joints"),
        (_valid(joints=[{"name": "root"}]), r"joint 1 needs a 'name' and a 'position: \[x, y\]'"),
        (
            _valid(joints=[{"name": "a", "parent": "b", "position": [0, 0]},
                           {"name": "b", "parent": "a", "position": [1, 1]}]),
            r"the skeleton has a cycle through joints a, b",
        ),
        (_valid(width="wide"), r"width and height must be whole numbers"),
        ({k: v for k, v in _valid().items() if k != "height"}, r"width and height"),
    ],
    ids=[
        "garbage",
        "not-an-object",
        "wrong-format",
        "no-format",
        "newer-version",
        "string-version",
        "joints-not-a-list",
        "joints-missing",
        "no-joints",
        "joint-without-position",
        "cycle",
        "bad-width",
        "width-without-height",
    ],
)
def test_malformed_json_raises_skeleton_error(tmp_path, data, message):
    path = _json(tmp_path, data)
    with pytest.raises(SkeletonError, match=message) as info:
        load_skeleton_json(path)
    assert "\n" not in str(info.value)
    with pytest.raises(SkeletonError, match=message):
        load_skeleton_file(path)


def test_missing_json(tmp_path):
    with pytest.raises(SkeletonError, match="no such file"):
        load_skeleton_file(tmp_path / "gone.json")


@pytest.mark.parametrize("name", ["skeleton.txt", "skeleton", "skeleton.bvh"])
def test_unknown_suffix(tmp_path, name):
    path = _json(tmp_path, _valid(), name=name)
    with pytest.raises(SkeletonError, match=f"cannot tell the skeleton format of {name}: "
                                            "use a char_cfg .yaml or a .json file"):
        load_skeleton_file(path)


@pytest.mark.parametrize("suffix", [".json", ".yaml"])
def test_image_size_mismatch(tmp_path, suffix):
    path = tmp_path / f"s{suffix}"
    if suffix == ".json":
        save_skeleton_json(path, _skeleton(), (320, 200))
    else:
        save_char_cfg(path, _skeleton(), (320, 200))
    assert len(load_skeleton_file(path, image_size=(320, 200))) == 5
    with pytest.raises(SkeletonError, match=f"s{suffix} was made for a 320x200 drawing but "
                                            "this one is 200x320; use the skeleton made for"):
        load_skeleton_file(path, image_size=(200, 320))


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"joints": [{"name": 1, "parent": None, "position": [1, 2]}]},
         r"{path}: joints\[0\]\.name: Input should be a valid string"),
        ({"joints": [{"name": ["root"], "parent": None, "position": [1, 2]}]},
         r"{path}: joints\[0\]\.name: Input should be a valid string"),
        ({"joints": [{"name": "root", "parent": False, "position": [1, 2]}]},
         r"{path}: joints\[0\]\.parent: Input should be a valid string"),
        ({"joints": [{"name": "root", "parent": None, "position": [1, True]}]},
         r"{path}: joints\[0\]\.position\[1\]: Input should be a valid number"),
        ({"version": True}, r"{path} is skeleton format version True; this toonmotion reads version 1"),
        ({"version": 2}, r"{path} is skeleton format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.pose"},
         r"{path} is not a toonmotion skeleton file \(format 'toonmotion.skeleton'\)"),
        ({"width": True}, r"{path}: width and height must be whole numbers of pixels above 0"),
        ({"width": 0}, r"{path}: width and height must be whole numbers of pixels above 0"),
        ({"colour": "red"}, r"{path}: colour: Extra inputs are not permitted"),
    ],
    ids=["int-name", "list-name", "bool-parent", "bool-coordinate", "bool-version", "future-version",
         "wrong-format", "bool-width", "zero-width", "unknown-key"],
)
def test_a_bad_value_is_one_line_naming_the_file_and_field(tmp_path, changes, message):
    path = _json(tmp_path, _valid(**changes))
    with pytest.raises(SkeletonError) as info:
        load_skeleton_json(path)
    assert re.fullmatch(message.format(path=re.escape(str(path))), str(info.value)), str(info.value)


def test_skeleton_problems_name_the_file(tmp_path):
    path = _json(tmp_path, _valid(joints=[{"name": "a", "parent": "b", "position": [0, 0]},
                                          {"name": "b", "parent": "a", "position": [1, 1]}]))
    with pytest.raises(SkeletonError, match=rf"^{re.escape(str(path))}: the skeleton has a cycle"):
        load_skeleton_json(path)


def test_skeleton_from_dict_refuses_a_non_string_name():
    with pytest.raises(SkeletonError, match=r"^here: \[0\]\.name: Input should be a valid string$"):
        skeleton_from_dict([{"name": 1, "parent": None, "position": [0, 0]}], where="here")


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_a_skeleton_file_over_its_size_limit_is_refused_before_it_is_read(tmp_path, suffix):
    from toonmotion import limits
    from toonmotion.errors import LimitError

    path = tmp_path / f"huge{suffix}"
    path.write_text("#" * 3000 if suffix == ".yaml" else " " * 3000)
    with limits.using(skeleton_bytes=2000), pytest.raises(LimitError) as refused:
        load_skeleton_file(path)
    assert str(refused.value) == (f"huge{suffix}'s size in bytes is over the limit skeleton_bytes=2,000 "
                                  "(it is 3,000); raise the limit with --limit skeleton_bytes=N")
