"""Tests for toonmotion.io.pose_json: pose and key-frame files."""

import json
import re

import numpy as np
import pytest

from toonmotion.animate.timeline import Keyframe, make_timeline
from toonmotion.errors import EditError, KeyframeError, PoseError
from toonmotion.io.pose_json import load_keyframes, load_pose, save_keyframes, save_pose
from toonmotion.io.skeleton_json import save_skeleton_json
from toonmotion.rig.pose import Pose, rest_pose, rotate_about
from toonmotion.rig.skeleton import Skeleton
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def _awkward_pose(skeleton):
    """A pose whose coordinates need every bit of a double: turned by an irrational angle."""
    P = rotate_about(skeleton, skeleton.positions, "right_shoulder", np.sqrt(2))
    P = rotate_about(skeleton, P, "left_knee", -1 / 3)
    return Pose(P + np.array([1e-7, -np.pi]))


def _write(path, data):
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


def _joints(skeleton, positions=None):
    positions = skeleton.positions if positions is None else positions
    return {n: [float(x), float(y)] for n, (x, y) in zip(skeleton.names, positions, strict=True)}


# --- poses --------------------------------------------------------------------------------------


def test_pose_round_trips_exactly(tmp_path, skeleton):
    pose = _awkward_pose(skeleton)
    path = tmp_path / "pose.json"
    save_pose(path, skeleton, pose)
    data = json.loads(path.read_text())
    assert data["format"] == "toonmotion.pose" and data["version"] == 1
    assert list(data["joints"]) == list(skeleton.names)
    loaded = load_pose(path, skeleton)
    assert np.array_equal(loaded.positions, pose.positions)
    save_pose(path, skeleton, loaded)  # and again: the file does not drift
    assert np.array_equal(load_pose(str(path), skeleton).positions, pose.positions)


def test_a_skeleton_file_reads_as_its_pose(tmp_path, skeleton):
    posed = Skeleton.from_joints(
        (name, parent, (x + 0.125, 2 * y)) for name, parent, (x, y) in skeleton.joints()
    )
    path = tmp_path / "posed.json"
    save_skeleton_json(path, posed, size=(420, 600))
    pose = load_pose(path, skeleton)
    np.testing.assert_array_equal(pose.positions, posed.positions)
    # Joints listed in another order still land on the right joints.
    data = json.loads(path.read_text())
    data["joints"].reverse()
    np.testing.assert_array_equal(load_pose(_write(path, data), skeleton).positions, posed.positions)


def test_a_skeleton_file_with_other_joints_is_refused(tmp_path, skeleton):
    other = Skeleton.from_joints([("arm", None, (0, 0)), ("hand", "arm", (10, 0))])
    path = tmp_path / "other.json"
    save_skeleton_json(path, other)
    with pytest.raises(PoseError, match=rf"{re.escape(str(path))}: unknown joint 'arm'"):
        load_pose(path, skeleton)
    _write(path, {"format": "toonmotion.skeleton", "version": 1, "joints": {"arm": [0, 0]}})
    with pytest.raises(PoseError, match=rf"{re.escape(str(path))}: 'joints' must be a list"):
        load_pose(path, skeleton)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (None, r"cannot read {path}: no such file"),
        ("{not json", r"cannot read {path} as JSON"),
        ([1, 2], r"{path} is not a pose file \(format 'toonmotion.pose' or 'toonmotion.skeleton'\)"),
        ({"format": "toonmotion.keyframes", "version": 1}, r"{path} is not a pose file"),
        ({"format": "toonmotion.pose", "version": 2, "joints": {}},
         r"{path} is format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.pose", "joints": {}}, r"{path} is format version None"),
        ({"format": "toonmotion.pose", "version": 1, "joints": {"tail": [0, 0]}},
         r"{path}: unknown joint 'tail'"),
        ({"format": "toonmotion.pose", "version": 1, "joints": {"root": [0, 0]}},
         r"{path}: joint 'hip' has no position.* \(16 are missing\)"),
        ({"format": "toonmotion.pose", "version": 1, "joints": [[0, 0]]},
         r"{path}: joints must be a mapping"),
    ],
)
def test_bad_pose_files_are_refused_naming_the_file(tmp_path, skeleton, content, message):
    path = tmp_path / "pose.json"
    if isinstance(content, str):
        path.write_text(content)
    elif content is not None:
        _write(path, content)
    with pytest.raises(PoseError, match=message.format(path=re.escape(str(path)))):
        load_pose(path, skeleton)


def test_bad_positions_in_a_pose_file_name_the_file_and_joint(tmp_path, skeleton):
    joints = _joints(skeleton) | {"neck": ["a", 1]}
    path = _write(tmp_path / "pose.json", {"format": "toonmotion.pose", "version": 1, "joints": joints})
    where = re.escape(str(path))
    with pytest.raises(PoseError, match=rf"{where}: joint 'neck' has position \['a', 1\]; give two numbers"):
        load_pose(path, skeleton)
    joints["neck"] = joints["torso"]  # the neck bone squashed to nothing
    _write(path, {"format": "toonmotion.pose", "version": 1, "joints": joints})
    with pytest.raises(PoseError, match=rf"{where}: bone 'neck' is squashed to 0 px"):
        load_pose(path, skeleton)


def test_a_skeleton_file_of_another_version_is_refused(tmp_path, skeleton):
    path = tmp_path / "future.json"
    save_skeleton_json(path, skeleton)
    data = json.loads(path.read_text())
    _write(path, data | {"version": 2})
    with pytest.raises(PoseError, match="version 2"):
        load_pose(path, skeleton)


# --- key-frames ------------------------------------------------------------------------------------


def test_keyframes_round_trip_exactly(tmp_path, skeleton):
    keys = [Keyframe(0, rest_pose(skeleton)), Keyframe(9, _awkward_pose(skeleton)),
            Keyframe(4, Pose(rotate_about(skeleton, skeleton.positions, "neck", 0.2)))]
    timeline = make_timeline(skeleton, keys, fps=23.976, ease="out")
    path = tmp_path / "keys.json"
    save_keyframes(path, skeleton, timeline)
    loaded = load_keyframes(path, skeleton)
    assert [k.frame for k in loaded.keys] == [0, 4, 9]
    assert loaded.fps == 23.976 and loaded.ease == "out" and loaded.frame_count == 10
    for a, b in zip(timeline.keys, loaded.keys, strict=True):
        assert np.array_equal(a.pose.positions, b.pose.positions)
    assert load_keyframes(path, skeleton, fps=6).fps == 6.0  # fps given by the caller wins


def test_sample_keyframes_round_trip(tmp_path, skeleton):
    timeline = sample_keyframes(skeleton)
    path = tmp_path / "sample-keys.json"
    save_keyframes(path, skeleton, timeline)
    loaded = load_keyframes(path, skeleton)
    assert (loaded.fps, loaded.ease) == (12.0, "in-out")
    assert [k.frame for k in loaded.keys] == [0, 6, 12, 18, 24, 30, 36]
    for a, b in zip(timeline.keys, loaded.keys, strict=True):
        assert np.array_equal(a.pose.positions, b.pose.positions)


def test_rest_keys_and_defaults(tmp_path, skeleton):
    bent = rotate_about(skeleton, skeleton.positions, "left_elbow", 1.0)
    path = _write(tmp_path / "keys.json", {
        "format": "toonmotion.keyframes", "version": 1,
        "keys": [{"frame": 8, "rest": True}, {"frame": 0, "joints": _joints(skeleton, bent)},
                 {"frame": 3, "rest": True, "joints": {"ignored": [0, 0]}}],
    })
    timeline = load_keyframes(path, skeleton)
    assert timeline.fps == 24.0 and timeline.ease == "linear"
    assert [k.frame for k in timeline.keys] == [0, 3, 8]
    np.testing.assert_array_equal(timeline.keys[0].pose.positions, bent)
    for key in timeline.keys[1:]:  # "rest": true wins over any joints given
        np.testing.assert_array_equal(key.pose.positions, skeleton.positions)


def _keys_file(**extra):
    data = {"format": "toonmotion.keyframes", "version": 1, "fps": 12, "keys": [{"frame": 0, "rest": True}]}
    return data | extra


@pytest.mark.parametrize(
    ("content", "error", "message"),
    [
        (None, KeyframeError, r"cannot read {path}: no such file"),
        ("[1, 2", KeyframeError, r"cannot read {path} as JSON"),
        ({"format": "toonmotion.pose", "version": 1}, KeyframeError,
         r"{path} is not a key-frames file \(format 'toonmotion.keyframes'\)"),
        (_keys_file(version=7), KeyframeError,
         r"{path} is format version 7; this toonmotion reads version 1"),
        (_keys_file(keys={"frame": 0}), KeyframeError, r"{path}: 'keys' must be a list"),
        (_keys_file(keys=[{"frame": 0, "rest": True}, {"joints": {}}]), KeyframeError,
         r"{path}: key 2 needs a 'frame' number"),
        (_keys_file(keys=[{"frame": 5}]), KeyframeError,
         r"{path}: key at frame 5 needs 'joints' \(or 'rest': true\)"),
        (_keys_file(keys=[{"frame": 2, "joints": {"tail": [1, 2]}}]), PoseError,
         r"{path}: key at frame 2: unknown joint 'tail'"),
    ],
)
def test_bad_keyframe_files_are_refused_naming_the_file(tmp_path, skeleton, content, error, message):
    path = tmp_path / "keys.json"
    if isinstance(content, str):
        path.write_text(content)
    elif content is not None:
        _write(path, content)
    with pytest.raises(error, match=message.format(path=re.escape(str(path)))):
        load_keyframes(path, skeleton)


@pytest.mark.parametrize(
    "content",
    [
        _keys_file(keys=[{"frame": 0, "rest": True}, {"frame": 0, "rest": True}]),
        _keys_file(keys=[{"frame": -3, "rest": True}]),
        _keys_file(keys=[{"frame": 1.5, "rest": True}]),
        _keys_file(fps=0),
        _keys_file(ease="bounce"),
    ],
    ids=["repeated-frame", "negative-frame", "fractional-frame", "zero-fps", "unknown-ease"],
)
def test_bad_timelines_in_a_file_name_the_file(tmp_path, skeleton, content):
    path = _write(tmp_path / "keys.json", content)
    with pytest.raises(KeyframeError) as error:
        load_keyframes(path, skeleton)
    assert str(path) in str(error.value)


def test_fine_tuning_edits_round_trip_in_pose_and_key_files(skeleton, tmp_path):
    from toonmotion.deform.tuning import CurveEdit, DragEdit
    from toonmotion.io.pose_json import load_pose_edits

    edits = (CurveEdit(points=[[1.5, 2.25], [3, 4], [5, np.pi]]),
             DragEdit(start=[[10, 20], [30, 40]], end=[[11, 19], [30, 45]]))
    save_pose(tmp_path / "p.json", skeleton, rest_pose(skeleton), edits)
    loaded = load_pose_edits(tmp_path / "p.json")
    assert [type(e) for e in loaded] == [CurveEdit, DragEdit]
    np.testing.assert_array_equal(loaded[0].points, edits[0].points)
    np.testing.assert_array_equal(loaded[1].end, edits[1].end)
    timeline = make_timeline(skeleton, [Keyframe(0, rest_pose(skeleton)),
                                        Keyframe(6, rest_pose(skeleton), edits)], fps=12)
    save_keyframes(tmp_path / "k.json", skeleton, timeline)
    keys = load_keyframes(tmp_path / "k.json", skeleton).keys
    assert keys[0].edits == () and len(keys[1].edits) == 2
    np.testing.assert_array_equal(keys[1].edits[1].start, edits[1].start)
    save_skeleton_json(tmp_path / "s.json", skeleton)
    assert load_pose_edits(tmp_path / "s.json") == ()


@pytest.mark.parametrize(
    ("edits", "message"),
    [
        ([{"kind": "curve", "points": [[1, 2]]}], "edit 1 a sketch curve needs at least 2 points"),
        ([{"kind": "curve", "points": [[1, 2], [3, None]]}], "list of \\[x, y\\] points|non-finite"),
        ([{"kind": "drag", "from": [[1, 2]], "to": []}], "drag's end points needs at least 1"),
        ([{"kind": "drag", "from": [[1, 2]], "to": [[1, 2], [3, 4]]}], "1 start points but 2 end"),
        ([{"kind": "blur"}], "kind 'blur'; use 'curve' or 'drag'"),
        ({"kind": "curve"}, "'edits' must be a list"),
    ],
)
def test_malformed_edits_in_a_key_file(skeleton, tmp_path, edits, message):
    from toonmotion.errors import EditError

    data = {"format": "toonmotion.keyframes", "version": 1,
            "keys": [{"frame": 0, "rest": True, "edits": edits}]}
    with pytest.raises(EditError, match=message):
        load_keyframes(_write(tmp_path / "k.json", data), skeleton)


def _pose_file(skeleton, **changes):
    return {"format": "toonmotion.pose", "version": 1, "joints": _joints(skeleton)} | changes


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"version": True}, r"{path} is format version True; this toonmotion reads version 1"),
        ({"version": 2}, r"{path} is format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.motion"},
         r"{path} is not a pose file \(format 'toonmotion.pose' or 'toonmotion.skeleton'\)"),
        ({"format": "toonmotion.skeleton", "joints": [{"name": 1, "parent": None, "position": [0, 0]}]},
         r"{path}: joints\[0\]\.name: Input should be a valid string"),
        ({"joints": "neck"}, r"{path}: joints must be a mapping of joint name to \[x, y\]"),
        ({"extra": 1}, r"{path}: extra: Extra inputs are not permitted"),
    ],
    ids=["bool-version", "future-version", "wrong-format", "skeleton-file-int-name", "joints-not-a-mapping",
         "unknown-key"],
)
def test_a_bad_pose_file_is_one_line_naming_file_and_field(tmp_path, skeleton, changes, message):
    path = _write(tmp_path / "pose.json", _pose_file(skeleton, **changes))
    with pytest.raises(PoseError) as info:
        load_pose(path, skeleton)
    assert re.fullmatch(message.format(path=re.escape(str(path))), str(info.value)), str(info.value)


@pytest.mark.parametrize(
    ("changes", "error", "message"),
    [
        ({"version": True}, KeyframeError, r"{path} is format version True; this toonmotion reads version 1"),
        ({"version": 2}, KeyframeError, r"{path} is format version 2; this toonmotion reads version 1"),
        ({"format": "toonmotion.pose"}, KeyframeError,
         r"{path} is not a key-frames file \(format 'toonmotion.keyframes'\)"),
        ({"keys": [{"frame": True, "rest": True}]}, KeyframeError,
         r"{path}: keys\[0\]\.frame: Input should be a valid integer"),
        ({"keys": [{"frame": 0, "rest": 1}]}, KeyframeError,
         r"{path}: keys\[0\]\.rest: Input should be a valid boolean"),
        ({"ease": 1}, KeyframeError, r"{path}: ease: Input should be a valid string"),
        ({"fps": "12"}, KeyframeError, r"{path}: fps: Input should be a valid number"),
        ({"keys": [{"frame": 0, "rest": True}, {"frame": 1, "joints": {"neck": [1, "a"]}}]}, PoseError,
         r"{path}: keys\[1\]: joint 'neck' has position \[1, 'a'\]; give two numbers \[x, y\]"),
        ({"keys": [{"frame": 0, "rest": True, "edits": [{"kind": "curve", "points": [[0, 0], [1, 1]]},
                                                        {"kind": "blur"}]}]}, EditError,
         r"{path}: keys\[0\]: edit 2 has kind 'blur'; use 'curve' or 'drag'"),
    ],
    ids=["bool-version", "future-version", "wrong-format", "bool-frame", "int-rest", "int-ease",
         "string-fps", "bad-position", "bad-edit-kind"],
)
def test_a_bad_keyframes_file_is_one_line_naming_file_and_field(tmp_path, skeleton, changes, error, message):
    path = _write(tmp_path / "keys.json", _keys_file(**changes))
    with pytest.raises(error) as info:
        load_keyframes(path, skeleton)
    assert type(info.value) is error
    assert re.fullmatch(message.format(path=re.escape(str(path))), str(info.value)), str(info.value)
