"""Tests for toonmotion.io.motion_json: motion files."""

import json
import re

import numpy as np
import pytest

from toonmotion.animate.motion import Motion, motion_for
from toonmotion.errors import MotionError
from toonmotion.io.motion_json import is_motion_file, load_motion, save_motion
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def motion():
    skeleton = sample_character()[1]
    rng = np.random.default_rng(3)
    # Numbers that need every bit of a double.
    positions = skeleton.positions + rng.normal(scale=np.pi, size=(9, len(skeleton), 2))
    return Motion(skeleton, positions, fps=23.976)


def test_save_then_load_is_exact(motion, tmp_path):
    save_motion(tmp_path / "m.json", motion)
    loaded = load_motion(tmp_path / "m.json")
    assert loaded.skeleton.names == motion.skeleton.names
    np.testing.assert_array_equal(loaded.skeleton.parents, motion.skeleton.parents)
    np.testing.assert_array_equal(loaded.positions, motion.positions)
    assert loaded.fps == motion.fps
    assert is_motion_file(tmp_path / "m.json")
    # One line per frame, so diffs of a motion stay readable.
    assert len((tmp_path / "m.json").read_text().splitlines()) == 3 + len(motion.positions)


def test_joints_listed_children_first_still_line_up(motion, tmp_path):
    save_motion(tmp_path / "m.json", motion)
    data = json.loads((tmp_path / "m.json").read_text())
    data["joints"] = data["joints"][::-1]
    data["frames"] = [frame[::-1] for frame in data["frames"]]
    (tmp_path / "r.json").write_text(json.dumps(data))
    loaded = load_motion(tmp_path / "r.json")
    np.testing.assert_array_equal(motion_for(motion.skeleton, loaded), motion.positions)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.update(format="toonmotion.pose"), "is not a motion file"),
        (lambda d: d.update(version=2), "motion format version 2"),
        (lambda d: d.update(fps=-1), "fps must be a finite number > 0"),
        (lambda d: d.update(frames=[]), r"shape \(frames, 17, 2\)"),
        (lambda d: d["frames"][0].pop(), r"must be a list of frames|shape"),
        (lambda d: d["joints"][1].update(parent="nobody"), "unknown parent 'nobody'"),
    ],
)
def test_malformed_motion_files(motion, tmp_path, change, message):
    save_motion(tmp_path / "m.json", motion)
    data = json.loads((tmp_path / "m.json").read_text())
    change(data)
    (tmp_path / "m.json").write_text(json.dumps(data))
    with pytest.raises(MotionError, match=message):
        load_motion(tmp_path / "m.json")


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(MotionError, match="no such file"):
        load_motion(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(MotionError, match="as JSON"):
        load_motion(tmp_path / "bad.json")
    assert not is_motion_file(tmp_path / "none.json")


def test_confidence_round_trips_and_csv_has_every_number(motion, tmp_path):
    import csv

    from toonmotion.io.motion_json import save_motion_csv

    rng = np.random.default_rng(5)
    captured = Motion(motion.skeleton, motion.positions, fps=motion.fps,
                      confidence=rng.uniform(size=motion.positions.shape[:2]))
    save_motion(tmp_path / "m.json", captured)
    loaded = load_motion(tmp_path / "m.json")
    np.testing.assert_array_equal(loaded.confidence, captured.confidence)
    save_motion_csv(tmp_path / "m.csv", captured)
    rows = list(csv.reader((tmp_path / "m.csv").open()))
    names = motion.skeleton.names
    assert rows[0][:5] == ["frame", "time", f"{names[0]}_x", f"{names[0]}_y", f"{names[0]}_confidence"]
    assert len(rows) == 1 + len(motion.positions) and len(rows[1]) == 2 + 3 * len(names)
    table = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(table[:, 0], np.arange(len(motion.positions)))
    np.testing.assert_array_equal(table[:, 2::3], captured.positions[..., 0])
    np.testing.assert_array_equal(table[:, 3::3], captured.positions[..., 1])
    np.testing.assert_array_equal(table[:, 4::3], captured.confidence)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["joints"][2].update(name=7),
         r"{path}: joints\[2\]\.name: Input should be a valid string"),
        (lambda d: d["joints"][2].update(name=["neck"]),
         r"{path}: joints\[2\]\.name: Input should be a valid string"),
        (lambda d: d.update(version=True),
         r"{path} is motion format version True; this toonmotion reads version 1"),
        (lambda d: d.update(version=2),
         r"{path} is motion format version 2; this toonmotion reads version 1"),
        (lambda d: d.update(format="toonmotion.skeleton"),
         r"{path} is not a motion file \(format 'toonmotion.motion'\)"),
        (lambda d: d["frames"][3][1].__setitem__(0, True),
         r"{path}: frames\[3\]\[1\]\[0\]: Input should be a valid number"),
        (lambda d: d.update(fps=True), r"{path}: fps: Input should be a valid number"),
    ],
    ids=["int-name", "list-name", "bool-version", "future-version", "wrong-format", "bool-coordinate",
         "bool-fps"],
)
def test_a_bad_value_is_one_line_naming_the_file_and_field(motion, tmp_path, change, message):
    path = tmp_path / "m.json"
    save_motion(path, motion)
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))
    with pytest.raises(MotionError) as info:
        load_motion(path)
    assert re.fullmatch(message.format(path=re.escape(str(path))), str(info.value)), str(info.value)


def test_csv_bytes(tmp_path):
    """The table as spreadsheets read it: a header, a row per frame, numbers in full, \\n endings."""
    from toonmotion.io.motion_json import save_motion_csv
    from toonmotion.rig.skeleton import Skeleton

    skeleton = Skeleton.from_joints([("hip", None, (0.0, 0.0)), ("knee", "hip", (0.0, 10.0))])
    positions = [[[1.0, 2.5], [0.1, 1 / 3]], [[-0.0, 1e-300], [1234567.125, 2.0]]]
    save_motion_csv(tmp_path / "m.csv", Motion(skeleton, positions, fps=3))
    assert (tmp_path / "m.csv").read_bytes() == (
        b"frame,time,hip_x,hip_y,knee_x,knee_y\n"
        b"0,0.0,1.0,2.5,0.1,0.3333333333333333\n"
        b"1,0.3333333333333333,-0.0,1e-300,1234567.125,2.0\n"
    )
    save_motion_csv(tmp_path / "c.csv", Motion(skeleton, positions, fps=3, confidence=[[1, 0.5], [0, 0.25]]))
    assert (tmp_path / "c.csv").read_text().splitlines()[:2] == [
        "frame,time,hip_x,hip_y,hip_confidence,knee_x,knee_y,knee_confidence",
        "0,0.0,1.0,2.5,1.0,0.1,0.3333333333333333,0.5",
    ]
