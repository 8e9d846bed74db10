"""Tests for toonmotion.io.track_json."""

import json
import re

import numpy as np
import pytest

from toonmotion.errors import SkeletonError, TrackingError
from toonmotion.io.track_json import DEFAULT_SIZE, FORMAT, VERSION, load_joints, save_joints
from toonmotion.rig.skeleton import Skeleton


def _skeleton():
    return Skeleton.from_joints([
        ("head", None, (0.1 + 0.2, 1.0 / 3.0)),
        ("hand", "arm", (5e-324, np.nextafter(1.0, 2.0))),
        ("arm", "head", (-0.0, 9876543.123456789)),
    ])


def _write(path, data):
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


def test_round_trip_is_exact(tmp_path):
    skeleton = _skeleton()
    sizes = np.array([[16.5, 1.0 / 3.0], [8.0, 9.0], [np.pi, 48.0]])
    save_joints(tmp_path / "joints.json", skeleton, sizes, frame=7)
    loaded, loaded_sizes, frame = load_joints(tmp_path / "joints.json")
    assert loaded.names == skeleton.names
    np.testing.assert_array_equal(loaded.parents, skeleton.parents)
    assert loaded.positions.tobytes() == skeleton.positions.tobytes()
    assert loaded_sizes.tobytes() == sizes.tobytes()
    assert frame == 7
    data = json.loads((tmp_path / "joints.json").read_text())
    assert data["format"] == FORMAT and data["version"] == VERSION


def test_defaults_and_sizes_follow_joint_order_not_file_order(tmp_path):
    path = _write(tmp_path / "j.json", {
        "format": FORMAT, "version": VERSION, "size": [20, 10],
        "joints": [
            {"name": "hand", "parent": "elbow", "position": [9, 0], "size": [6, 7]},
            {"name": "elbow", "parent": None, "position": [0, 0]},
        ],
    })
    skeleton, sizes, frame = load_joints(path)
    assert skeleton.names == ("elbow", "hand") and frame == 0
    np.testing.assert_array_equal(sizes, [[20, 10], [6, 7]])
    data = json.loads(path.read_text())
    del data["size"]
    _, sizes, _ = load_joints(_write(path, data))
    np.testing.assert_array_equal(sizes[0], DEFAULT_SIZE)


def test_missing_file_and_bad_json(tmp_path):
    with pytest.raises(TrackingError, match="nope.json: no such file"):
        load_joints(tmp_path / "nope.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(TrackingError, match="bad.json as JSON"):
        load_joints(tmp_path / "bad.json")


def test_wrong_format_and_version(tmp_path):
    with pytest.raises(TrackingError, match="skel.json is not a toonmotion joints file"):
        skeleton_file = {"format": "toonmotion.skeleton", "version": 1, "joints": []}
        load_joints(_write(tmp_path / "skel.json", skeleton_file))
    with pytest.raises(TrackingError, match="v9.json is joints format version 9"):
        load_joints(_write(tmp_path / "v9.json", {"format": FORMAT, "version": 9, "joints": []}))


@pytest.mark.parametrize("size", [[0, 4], [4], [-1, 4], ["8", 8], [True, 8], 8, [1e400, 8]])
def test_bad_sizes_name_the_file_and_joint(tmp_path, size):
    joint = {"name": "hip", "parent": None, "position": [1, 2], "size": size}
    path = _write(tmp_path / "j.json", {"format": FORMAT, "version": VERSION, "joints": [joint]})
    with pytest.raises(TrackingError, match=r"j\.json: the 'size' of joint 'hip'"):
        load_joints(path)
    del joint["size"]
    path = _write(path, {"format": FORMAT, "version": VERSION, "size": size, "joints": [joint]})
    with pytest.raises(TrackingError, match=r"j\.json: the file's 'size'"):
        load_joints(path)


@pytest.mark.parametrize("frame", [-1, 1.5, "0", True])
def test_bad_frame(tmp_path, frame):
    path = _write(tmp_path / "j.json", {"format": FORMAT, "version": VERSION, "frame": frame, "joints": [
        {"name": "hip", "parent": None, "position": [1, 2]}]})
    with pytest.raises(TrackingError, match="'frame' must be a whole number"):
        load_joints(path)


def test_bad_joints_are_skeleton_errors_naming_the_file(tmp_path):
    path = _write(tmp_path / "j.json", {"format": FORMAT, "version": VERSION, "joints": [
        {"name": "hip", "parent": "nobody", "position": [1, 2]}]})
    with pytest.raises(SkeletonError, match=r"j\.json: joint 'hip' names an unknown parent"):
        load_joints(path)
    path = _write(path, {"format": FORMAT, "version": VERSION, "joints": [{"name": "hip"}]})
    with pytest.raises(SkeletonError, match=r"j\.json: joint 1 needs"):
        load_joints(path)


def test_save_rejects_bad_sizes_and_frames(tmp_path):
    skeleton = _skeleton()
    with pytest.raises(TrackingError, match="each of the 3 joints"):
        save_joints(tmp_path / "j.json", skeleton, np.ones((2, 2)))
    with pytest.raises(TrackingError, match="the size of joint 'arm'"):
        save_joints(tmp_path / "j.json", skeleton, [[1, 1], [0, 1], [1, 1]])
    with pytest.raises(TrackingError, match="frame"):
        save_joints(tmp_path / "j.json", skeleton, np.ones((3, 2)), frame=-1)
    assert not (tmp_path / "j.json").exists()


@pytest.mark.parametrize(
    ("changes", "error", "message"),
    [
        ({"joints": [{"name": 3, "parent": None, "position": [1, 2]}]}, TrackingError,
         r"{path}: joints\[0\]\.name: Input should be a valid string"),
        ({"joints": [{"name": {"a": 1}, "parent": None, "position": [1, 2]}]}, TrackingError,
         r"{path}: joints\[0\]\.name: Input should be a valid string"),
        ({"version": True}, TrackingError,
         r"{path} is joints format version True; this toonmotion reads version 1"),
        ({"version": 2}, TrackingError,
         r"{path} is joints format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.skeleton"}, TrackingError,
         r"{path} is not a toonmotion joints file \(format 'toonmotion.joints'\)"),
        ({"joints": {"hip": [1, 2]}}, SkeletonError,
         r"{path}: 'joints' must be a list of \{{name, parent, position, size\}} objects"),
        ({"extra": 1}, TrackingError, r"{path}: extra: Extra inputs are not permitted"),
    ],
    ids=["int-name", "dict-name", "bool-version", "future-version", "wrong-format", "joints-not-a-list",
         "unknown-key"],
)
def test_a_bad_value_is_one_line_naming_the_file_and_field(tmp_path, changes, error, message):
    data = {"format": FORMAT, "version": VERSION,
            "joints": [{"name": "hip", "parent": None, "position": [1, 2]}]}
    path = _write(tmp_path / "j.json", data | changes)
    with pytest.raises(error) as info:
        load_joints(path)
    assert type(info.value) is error
    assert re.fullmatch(message.format(path=re.escape(str(path))), str(info.value)), str(info.value)
