"""Tests for toonmotion.io.bvh: reading BVH files (their kinematics: tests/capture/test_bvh_kinematics.py)."""

import re

import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require
from toonmotion.errors import MotionError
from toonmotion.io.bvh import load_bvh

MOCAP_DIR = SHARED_DATA / "mocap"
CLIPS = sorted(p.name for p in MOCAP_DIR.glob("*.bvh")) or ["<missing>"]

# A root with position channels, a joint rotated Z-then-X and one rotated X-then-Z, and an End
# Site; tabs, a CRLF line end and a channel order that differs per joint. Frame 0 is worked
# out by hand in tests/capture/test_bvh_kinematics.py.
TINY = (
    "HIERARCHY\n"
    "ROOT root\n"
    "{\n"
    "\tOFFSET 0 0 0\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\r\n"
    "\tJOINT a\n"
    "\t{\n"
    "\t\tOFFSET 1 0 0\n"
    "\t\tCHANNELS 3 Zrotation Yrotation Xrotation\n"
    "\t\tJOINT b\n"
    "\t\t{\n"
    "\t\t\tOFFSET 0 2 0\n"
    "\t\t\tCHANNELS 3 Xrotation Yrotation Zrotation\n"
    "\t\t\tEnd Site\n"
    "\t\t\t{\n"
    "\t\t\t\tOFFSET 0 0 3\n"
    "\t\t\t}\n"
    "\t\t}\n"
    "\t}\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time:\t0.04\n"
    "10 20 30 90 0 0 0 0 90 90 0 0\n"
    "1 2 3 12.5 -40 7 30 60 -90 45 10 -20\n"
)
TINY_FIRST_ROW = 24  # the line number of frame 0


def _write(tmp_path, text, name="clip.bvh"):
    path = tmp_path / name
    path.write_bytes(text.encode())
    return path


def _header(path):
    text = path.read_text()
    frames = int(re.search(r"Frames:\s*(\d+)", text).group(1))
    frame_time = float(re.search(r"Frame Time:\s*(\S+)", text).group(1))
    return frames, frame_time


@pytest.fixture(scope="module", params=CLIPS)
def shared_clip(request):
    path = _require(MOCAP_DIR) / request.param
    return path, load_bvh(path)


def test_every_shared_clip_loads_as_its_header_says(shared_clip):
    path, clip = shared_clip
    frames, frame_time = _header(path)
    assert clip.frame_count == frames > 0
    assert clip.frame_time == frame_time
    assert clip.fps == pytest.approx(1 / frame_time)
    J = len(clip.names)
    assert len(set(clip.names)) == J and clip.names[0] == "Hips"
    assert clip.parents.shape == (J,) and clip.offsets.shape == (J, 3) and len(clip.channels) == J
    assert all(p < i for i, p in enumerate(clip.parents)), "parents come first"
    assert clip.motion.shape == (frames, sum(len(c) for c in clip.channels))
    assert clip.channels[0][:3] == ("Xposition", "Yposition", "Zposition")
    ends = [name for name, c in zip(clip.names, clip.channels, strict=True) if not c]
    assert len(ends) >= 5 and all(name.endswith("_end") for name in ends)


def test_the_tiny_clip_reads_as_written(tmp_path):
    clip = load_bvh(_write(tmp_path, TINY))
    assert clip.names == ("root", "a", "b", "b_end")
    assert clip.parents.tolist() == [-1, 0, 1, 2]
    assert clip.channels[2] == ("Xrotation", "Yrotation", "Zrotation") and clip.channels[3] == ()
    assert clip.frame_count == 2 and clip.frame_time == 0.04
    np.testing.assert_array_equal(clip.offsets, [[0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]])
    np.testing.assert_array_equal(clip.motion[0], [10, 20, 30, 90, 0, 0, 0, 0, 90, 90, 0, 0])


def _broken(change):
    return change(TINY)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", r"clip\.bvh is not a BVH file: it is empty"),
        ("Hello, world\n", r"clip\.bvh is not a BVH file: it does not start with HIERARCHY"),
        (TINY.replace("\t\t}\n\t}\n}\n", "\t\t}\n\t}\n"), r"unbalanced braces: the '\{' of root \(line 3\)"),
        (TINY.replace("\t}\n}\n", "\t}\n}\n}\n"), r"line 21: unbalanced braces: a '\}' closes nothing"),
        (TINY.replace("Yrotation Zrotation", "Wrotation Zrotation"), r"line 13: unknown channel 'Wrotation'"),
        (TINY.replace("CHANNELS 3 Xrotation", "CHANNELS 3 Xrotation Xrotation"), r"line 13: .*listed twice"),
        (TINY.replace("OFFSET 1 0 0", "OFFSET 1 zero 0"), r"line 8: OFFSET Y must be a number, got 'zero'"),
        (TINY.replace("Frames: 2", "Frames: 3"), r"Frames: 3 but 2 rows of values follow"),
        (TINY.replace("Frames: 2", "Frames: two"), r"line 22: Frames: must be followed by a number"),
        (TINY.replace("Frames: 2\n", ""), r"line 21: MOTION is not followed by a 'Frames: N' line"),
        (TINY.replace(" -20\n", "\n"), rf"line {TINY_FIRST_ROW + 1}: 11 values in a frame, .* 12 channels"),
        (TINY.replace("10 20 30", "10 2O 30"), rf"line {TINY_FIRST_ROW}: '2O' is not a number"),
        (TINY.replace("10 20 30", "10 nan 30"), rf"line {TINY_FIRST_ROW}: a value is not finite"),
        (TINY.replace("0.04", "0"), r"Frame Time: 0 must be a number of seconds > 0"),
        (TINY.replace("0.04", "-0.04"), r"Frame Time: -0.04 must be a number of seconds > 0"),
        (TINY.replace("Frame Time:\t0.04\n", ""), r"line 21: MOTION has no 'Frame Time: seconds' line"),
        (TINY.split("MOTION")[0], r"has no MOTION section"),
        (TINY.replace("JOINT b", "JOINT a"), r"line 10: joint name 'a' is used twice"),
        (TINY.replace("OFFSET 0 0 3", "OFFSET 0 0 3\nCHANNELS 1 Xrotation"), r"CHANNELS outside a joint"),
    ],
)
def test_malformed_files_raise_one_line_errors_naming_file_and_line(tmp_path, text, message):
    path = _write(tmp_path, text)
    with pytest.raises(MotionError, match=message) as caught:
        load_bvh(path)
    assert "\n" not in str(caught.value)
    assert str(path) in str(caught.value)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(MotionError, match=r"cannot read .*nope\.bvh: no such file"):
        load_bvh(tmp_path / "nope.bvh")
    with pytest.raises(MotionError, match="it is a folder"):
        load_bvh(tmp_path)
