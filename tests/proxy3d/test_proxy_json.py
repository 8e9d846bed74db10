"""Proxy files (toonmotion.io.proxy_json): exact round trips and one-line errors."""

import json

import numpy as np
import pytest

from tests.proxy3d.synthetic_proxy import BRANCHING, FOREST, synthetic_proxy
from toonmotion.errors import ProxyError
from toonmotion.io.proxy_json import load_proxy, save_proxy
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.proxy import Proxy

FIELDS = ("points", "skeleton", "rest", "limb_rotations", "radii")


def _awkward(proxy):
    """``proxy`` with floats that only a full-precision writer keeps: tiny, negative zero, thirds."""
    points = proxy.points.copy()
    points[0, 0] = (1e-300, -0.0, 1 / 3)
    points[-1, -1] = (1234567.123456789, 5e-324, -2 / 3)
    extrinsics = proxy.camera.extrinsics.copy()
    extrinsics[0, 0] = 0.1 + 0.2
    camera = PerspectiveCamera(proxy.camera.focal + 1 / 7, proxy.camera.width, proxy.camera.height,
                               extrinsics)
    return Proxy(proxy.names, proxy.parents, 23.976, camera, points=points, radii=proxy.radii,
                 skeleton=proxy.skeleton, rest=proxy.rest, limb_rotations=proxy.limb_rotations)


def _assert_identical(back, proxy):
    assert back.names == proxy.names and np.array_equal(back.parents, proxy.parents)
    assert back.fps == proxy.fps
    assert (back.camera.focal, back.camera.width, back.camera.height) == (
        proxy.camera.focal, proxy.camera.width, proxy.camera.height)
    assert back.camera.extrinsics.tobytes() == proxy.camera.extrinsics.tobytes()
    for field in FIELDS:
        mine, theirs = getattr(back, field), getattr(proxy, field)
        if theirs is None:
            assert mine is None
        else:  # bit for bit, negative zeros and subnormals included
            assert mine.shape == theirs.shape and mine.tobytes() == theirs.tobytes(), field


@pytest.mark.parametrize("hierarchy", [BRANCHING, FOREST], ids=["branching", "forest"])
@pytest.mark.parametrize("radii", [True, False], ids=["radii", "no radii"])
def test_round_trip_is_exact(tmp_path, hierarchy, radii):
    proxy = _awkward(synthetic_proxy(hierarchy, radii=radii))
    save_proxy(tmp_path / "proxy.json", proxy)
    _assert_identical(load_proxy(tmp_path / "proxy.json"), proxy)


def test_one_frame_per_line_and_parents_by_name(tmp_path):
    proxy = synthetic_proxy(FOREST, frames=7)
    save_proxy(tmp_path / "proxy.json", proxy)
    text = (tmp_path / "proxy.json").read_text()
    data = json.loads(text)
    assert data["format"] == "toonmotion.proxy" and data["version"] == 1
    assert data["parents"][data["names"].index("hat_tip")] == "hat" and data["parents"][0] == "neck"
    # Header, names, parents, the camera and its 7 frames, rest, then 4 per-frame arrays of 7 lines
    # after their openers.
    assert len(text.splitlines()) == 4 + 7 + 1 + 4 * (1 + 7)


def _spoil(tmp_path, change):
    proxy = synthetic_proxy(BRANCHING, frames=3)
    save_proxy(tmp_path / "proxy.json", proxy)
    data = json.loads((tmp_path / "proxy.json").read_text())
    change(data)
    (tmp_path / "proxy.json").write_text(json.dumps(data).replace('"__nan__"', "NaN"))
    return tmp_path / "proxy.json"


def _set(key, value):
    def change(data):
        data[key] = value
    return change


def _nested(*path_and_value):
    *path, value = path_and_value

    def change(data):
        target = data
        for step in path[:-1]:
            target = target[step]
        target[path[-1]] = value
    return change


@pytest.mark.parametrize(
    "change, message",
    [
        (_set("format", "toonmotion.markers"), "is not a proxy file"),
        (_set("version", 2), "proxy format version 2"),
        (_set("radii", "none"), "'radii' must be null"),
        (_nested("points", 1, 0, "__nan__"), r"points\[1\]\[0\]"),
        (_nested("camera", "extrinsics", 0, 3, "__nan__"), "camera.extrinsics"),
        (_nested("skeleton", 2, [[0.0, 0.0, 0.0]]), "'skeleton' frame 2 has 1 entries for the 9 markers"),
        (_nested("limb_rotations", 0, 0, [2.0, 0.0, 0.0, 0.0]), "unit quaternions"),
        (_nested("limb_rotations", 0, 0, [1e308, 1e308, 0.0, 0.0]), "unit quaternions"),
        (_nested("limb_rotations", 0, 0, [0.5, 0.5, 0.0, 0.0]), "unit quaternions"),
        (_nested("radii", 1, 0, [-0.1, 0.1]), "must not be negative"),
        (_nested("parents", 1, "nobody"), "parent 'nobody' is not one of the marker names"),
        (_nested("parents", 1, "left_foot"), "the parents loop through marker 'left_foot'"),
        (_nested("parents", 2, "head"), "the parents loop through marker"),
        (lambda d: d["parents"].pop(), "'parents' has 8 entries for the 9 names"),
        (lambda d: d["rest"].pop(), "'rest' has 7 vectors for the 8 limbs"),
        (lambda d: d["points"].pop(), "'points' has 2 frames but the camera has 3"),
        (_set("fps", 0), "fps"),
        (_nested("camera", "focal", -5.0), "focal length"),
        (_nested("camera", "width", 1.5), "camera.width"),
        (_set("names", ["a"] * 9), "distinct"),
        (lambda d: d.pop("skeleton"), "skeleton"),
    ],
)
def test_bad_files_raise_one_line_naming_the_file(tmp_path, change, message):
    path = _spoil(tmp_path, change)
    with pytest.raises(ProxyError, match=message) as caught:
        load_proxy(path)
    assert "\n" not in str(caught.value)
    assert "proxy.json" in str(caught.value)


def test_missing_and_non_json_files(tmp_path):
    with pytest.raises(ProxyError, match="no such file"):
        load_proxy(tmp_path / "absent.json")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(ProxyError, match="as JSON"):
        load_proxy(tmp_path / "bad.json")


def test_save_is_atomic_and_leaves_no_temporary_file(tmp_path):
    proxy = synthetic_proxy(BRANCHING, frames=2)
    (tmp_path / "proxy.json").write_text("old")
    save_proxy(tmp_path / "proxy.json", proxy)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["proxy.json"]
    _assert_identical(load_proxy(tmp_path / "proxy.json"), proxy)
