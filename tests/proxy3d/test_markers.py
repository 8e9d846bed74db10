"""Markers (toonmotion.proxy3d.markers) and their files (toonmotion.io.markers_json)."""

import json

import numpy as np
import pytest

from toonmotion.animate.motion import Motion
from toonmotion.errors import ProxyError
from toonmotion.io.markers_json import load_markers, save_markers
from toonmotion.proxy3d.markers import Markers, markers_from_motion
from toonmotion.rig.skeleton import Skeleton


def _markers(T=5, N=3, seed=0):
    rng = np.random.default_rng(seed)
    positions = rng.normal(scale=300, size=(T, N, 2))
    positions[0, 0] = (1e-300, -0.1)  # awkward floats must survive the round trip
    positions[-1, -1] = (1 / 3, 1234567.123456789)
    return Markers(tuple(f"m{i}" for i in range(N)), positions, fps=23.976)


def test_markers_copy_and_freeze():
    mine = np.zeros((2, 1, 2))
    m = Markers(["a"], mine, fps=12)
    mine[0, 0, 0] = 5
    assert m.positions[0, 0, 0] == 0 and not m.positions.flags.writeable
    assert m.names == ("a",) and m.fps == 12.0


@pytest.mark.parametrize(
    "names, positions, fps, message",
    [
        (("a", "a"), np.zeros((2, 2, 2)), 12, "marker name 'a' is used twice"),
        (("a", ""), np.zeros((2, 2, 2)), 12, "every marker needs a name"),
        ((), np.zeros((2, 0, 2)), 12, "there are no markers"),
        (("a", "b"), np.zeros((0, 2, 2)), 12, "no frames"),
        (("a", "b"), np.zeros((2, 3, 2)), 12, r"shape \(frames, 2, 2\)"),
        (("a",), np.zeros((2, 1, 3)), 12, r"shape \(frames, 1, 2\)"),
        (("a", "b"), [[[0, 0], [np.nan, 1]]], 12, "marker 'b' at frame 0 is not a finite number"),
        (("a",), [[[np.inf, 0]]], 12, "not a finite number"),
        (("a",), [[[0, 0]]], 0, "fps must be a finite number > 0"),
        (("a",), [[[0, 0]]], float("nan"), "fps"),
        ("ab", [[[0, 0]]], 12, "not one string"),
    ],
)
def test_bad_markers_raise_one_line(names, positions, fps, message):
    with pytest.raises(ProxyError, match=message) as caught:
        Markers(names, positions, fps)
    assert "\n" not in str(caught.value)


def test_markers_from_motion_keeps_names_positions_fps():
    skeleton = Skeleton.from_joints([("hip", None, (0, 0)), ("knee", "hip", (0, 10)),
                                     ("foot", "knee", (0, 20))])
    P = np.arange(4 * 3 * 2, dtype=float).reshape(4, 3, 2)
    m = markers_from_motion(Motion(skeleton, P, fps=15.0))
    assert m.names == skeleton.names
    assert np.array_equal(m.positions, P) and m.fps == 15.0


@pytest.mark.parametrize("suffix", [".json", ".csv"])
def test_files_round_trip_exactly(tmp_path, suffix):
    m = _markers()
    save_markers(tmp_path / f"m{suffix}", m)
    back = load_markers(tmp_path / f"m{suffix}", fps=m.fps if suffix == ".csv" else None)
    assert back.names == m.names
    assert np.array_equal(back.positions, m.positions)  # bit for bit
    assert back.fps == m.fps


def test_json_layout_is_the_documented_one(tmp_path):
    save_markers(tmp_path / "m.json", Markers(("a", "b"), [[[1, 2], [3, 4]]], fps=12))
    data = json.loads((tmp_path / "m.json").read_text())
    assert data == {"format": "toonmotion.markers", "version": 1, "fps": 12.0, "names": ["a", "b"],
                    "frames": [[[1.0, 2.0], [3.0, 4.0]]]}


def test_csv_defaults_to_12_fps_and_keeps_first_seen_order(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("frame,marker,x,y\n1,b,5,6\n0,b,1,2\n0,a,3,4\n1,a,7,8\n")
    m = load_markers(path)
    assert m.names == ("b", "a") and m.fps == 12.0
    assert m.positions.tolist() == [[[1, 2], [3, 4]], [[5, 6], [7, 8]]]


def _json(path, **changes):
    data = {"format": "toonmotion.markers", "version": 1, "fps": 12, "names": ["a", "b"],
            "frames": [[[0, 0], [1, 1]], [[0, 1], [1, 2]]]}
    data.update(changes)
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"version": 2}, "markers format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.motion"}, "is not a markers file"),
        ({"names": ["a", "a"]}, "marker name 'a' is used twice"),
        ({"names": ["a", "b", "c"]}, "frame 0 has 2 points for the 3 names"),
        ({"frames": []}, "'frames' must list at least one frame"),
        ({"names": []}, "'names' must list at least one marker name"),
        ({"frames": [[[0, 0], [1, 1]], [[0, 1]]]}, "frame 1 has 1 points"),
        ({"fps": -1}, "fps must be a number"),
        ({"frames": [[[0, 0], [1, "x"]]]}, r"frames\[0\]\[1\]\[1\]"),
    ],
)
def test_bad_json_files_raise_one_line(tmp_path, changes, message):
    with pytest.raises(ProxyError, match=message) as caught:
        load_markers(_json(tmp_path / "m.json", **changes))
    assert "\n" not in str(caught.value) and "m.json" in str(caught.value)


@pytest.mark.parametrize(
    "text, message",
    [
        ("frame,point,x,y\n0,a,1,2\n", "the first row must be the header frame,marker,x,y"),
        ("frame,marker,x,y\n", "no rows of markers"),
        ("frame,marker,x,y\n0,a,1,2\n0,b,1,2\n1,a,1,2\n", "frame 1 has no row for marker 'b'"),
        ("frame,marker,x,y\n0,a,1,2\n2,a,1,2\n", "numbered 0, 1, 2"),
        ("frame,marker,x,y\n0,a,1,2\n0,a,1,2\n", "gives marker 'a' a second time"),
        ("frame,marker,x,y\n0,a,one,2\n", "row 2 must be frame"),
        ("frame,marker,x,y\n0.5,a,1,2\n", "row 2 must be frame"),
        ("frame,marker,x,y\n0,a,nan,2\n", "not a finite number"),
        ("frame,marker,x,y\n0,,1,2\n", "empty marker name"),
    ],
)
def test_bad_csv_files_raise_one_line(tmp_path, text, message):
    (tmp_path / "m.csv").write_text(text)
    with pytest.raises(ProxyError, match=message) as caught:
        load_markers(tmp_path / "m.csv")
    assert "\n" not in str(caught.value)


def test_missing_file_is_a_proxy_error(tmp_path):
    for name in ("none.json", "none.csv"):
        with pytest.raises(ProxyError, match="no such file"):
            load_markers(tmp_path / name)


def test_a_failed_save_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "m.json"
    save_markers(path, _markers())
    before = path.read_bytes()

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr("json.dumps", broken)
    with pytest.raises(OSError):
        save_markers(path, _markers(seed=1))
    assert path.read_bytes() == before
