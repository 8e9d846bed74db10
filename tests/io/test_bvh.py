"""Tests for toonmotion.io.bvh: reading BVH files and forward kinematics."""

import re
import time

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.conftest import SHARED_DATA, _require
from toonmotion.errors import MotionError
from toonmotion.io.bvh import BvhClip, forward_kinematics, load_bvh

MOCAP_DIR = SHARED_DATA / "mocap"
CLIPS = sorted(p.name for p in MOCAP_DIR.glob("*.bvh")) or ["<missing>"]

# A root with position channels, a joint rotated Z-then-X and one rotated X-then-Z, and an End
# Site; tabs, a CRLF line end and a channel order that differs per joint. Frame 0 is worked
# out by hand in test_forward_kinematics_by_hand.
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


def test_bone_lengths_stay_constant_in_every_shared_clip(shared_clip):
    _, clip = shared_clip
    P = forward_kinematics(clip)
    assert P.shape == (clip.frame_count, len(clip.names), 3)
    child = np.flatnonzero(clip.parents >= 0)
    lengths = np.linalg.norm(P[:, child] - P[:, clip.parents[child]], axis=2)
    # Every bone is as long as its rest offset (no joint but the root has position channels).
    rest = np.linalg.norm(clip.offsets[child], axis=1)
    np.testing.assert_allclose(lengths, np.broadcast_to(rest, lengths.shape), rtol=1e-6, atol=1e-9)


def test_forward_kinematics_by_hand(tmp_path):
    clip = load_bvh(_write(tmp_path, TINY))
    assert clip.names == ("root", "a", "b", "b_end")
    assert clip.parents.tolist() == [-1, 0, 1, 2]
    assert clip.channels[2] == ("Xrotation", "Yrotation", "Zrotation") and clip.channels[3] == ()
    assert clip.frame_count == 2 and clip.frame_time == 0.04
    P = forward_kinematics(clip)[0]
    # root at its position channels, turned Rz(90): x -> y, y -> -x.
    # a = root + Rz90 (1, 0, 0) = (10, 21, 30); a turns Rx(90): y -> z, z -> -y.
    # b = a + Rz90 Rx90 (0, 2, 0) = a + Rz90 (0, 0, 2) = (10, 21, 32); b turns Rx(90) Rz(90).
    # end = b + Rz90 Rx90 Rx90 Rz90 (0, 0, 3) = b + Rz90 Rx180 (0, 0, 3) = b + (0, 0, -3).
    expected = [[10, 20, 30], [10, 21, 30], [10, 21, 32], [10, 21, 29]]
    np.testing.assert_allclose(P, expected, rtol=0, atol=1e-12)


def test_forward_kinematics_matches_scipy_intrinsic_rotations(tmp_path):
    clip = load_bvh(_write(tmp_path, TINY))
    row = clip.motion[1]
    R_root = Rotation.from_euler("ZYX", row[3:6], degrees=True)  # upper case: intrinsic
    R_a = R_root * Rotation.from_euler("ZYX", row[6:9], degrees=True)
    R_b = R_a * Rotation.from_euler("XYZ", row[9:12], degrees=True)
    a = row[:3] + R_root.apply([1, 0, 0])
    b = a + R_a.apply([0, 2, 0])
    end = b + R_b.apply([0, 0, 3])
    np.testing.assert_allclose(forward_kinematics(clip)[1], [row[:3], a, b, end], rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("order", "expected"),
    [
        # Rx90 Rz90 (0, 1, 0) = Rx90 (-1, 0, 0) = (-1, 0, 0)
        ("Xrotation Yrotation Zrotation", [-1, 0, 0]),
        # Rz90 Rx90 (0, 1, 0) = Rz90 (0, 0, 1) = (0, 0, 1)
        ("Zrotation Yrotation Xrotation", [0, 0, 1]),
    ],
)
def test_rotation_order_is_the_channel_order(tmp_path, order, expected):
    values = {"X": "90", "Y": "0", "Z": "90"}
    row = " ".join(values[c[0]] for c in order.split())
    text = (
        f"HIERARCHY\nROOT r\n{{\nOFFSET 0 0 0\nCHANNELS 3 {order}\n"
        f"End Site\n{{\nOFFSET 0 1 0\n}}\n}}\nMOTION\nFrames: 1\nFrame Time: 0.1\n{row}\n"
    )
    P = forward_kinematics(load_bvh(_write(tmp_path, text)))
    np.testing.assert_allclose(P[0, 1], expected, rtol=0, atol=1e-12)


def test_position_channels_on_a_child_replace_its_offset_and_roots_may_be_many(tmp_path):
    text = (
        "HIERARCHY\nROOT r\n{\nOFFSET 5 5 5\nCHANNELS 1 Yrotation\n"
        "JOINT slider\n{\nOFFSET 1 2 3\nCHANNELS 2 Yposition Zrotation\n}\n}\n"
        "ROOT hat {\nOFFSET 0 9 0\n}\n"
        "MOTION\nFrames: 1\nFrame Time: 0.5\n0 7 90\n"
    )
    clip = load_bvh(_write(tmp_path, text))
    assert clip.parents.tolist() == [-1, 0, -1] and clip.fps == 2
    np.testing.assert_allclose(forward_kinematics(clip)[0], [[5, 5, 5], [6, 12, 8], [0, 9, 0]], atol=1e-12)


def test_forward_kinematics_is_fast():
    # 800 frames of 30 joints in a chain, 3 rotations each.
    J, T = 30, 800
    rng = np.random.default_rng(0)
    clip = BvhClip(
        names=tuple(f"j{i}" for i in range(J)),
        parents=np.arange(J) - 1,
        offsets=rng.normal(size=(J, 3)),
        channels=(("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"),)
        + (("Zrotation", "Xrotation", "Yrotation"),) * (J - 1),
        motion=rng.uniform(-180, 180, size=(T, 3 + 3 * J)),
        frame_time=1 / 120,
    )
    best = np.inf
    for _ in range(5):
        start = time.perf_counter()
        P = forward_kinematics(clip)
        best = min(best, time.perf_counter() - start)
    assert P.shape == (T, J, 3)
    assert best < 0.05, f"forward kinematics of {T} x {J} took {best * 1e3:.1f} ms"


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
