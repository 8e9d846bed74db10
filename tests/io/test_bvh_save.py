"""Tests for toonmotion.io.bvh.save_bvh: what it writes, load_bvh reads back exactly."""

import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require
from tests.io.test_bvh import TINY
from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics
from toonmotion.errors import MotionError
from toonmotion.io.bvh import load_bvh, save_bvh

MOCAP_DIR = SHARED_DATA / "mocap"
CLIPS = sorted(p.name for p in MOCAP_DIR.glob("*.bvh")) or ["<missing>"]


def _assert_same(back, clip):
    assert back.names == clip.names
    assert np.array_equal(back.parents, clip.parents)
    assert back.channels == clip.channels
    # Bit for bit: every number is written by repr.
    assert back.offsets.tobytes() == clip.offsets.tobytes()
    assert back.motion.shape == clip.motion.shape and back.motion.tobytes() == clip.motion.tobytes()
    assert back.frame_time == clip.frame_time


@pytest.mark.parametrize("name", CLIPS)
def test_shared_clips_round_trip_exactly(name, tmp_path):
    clip = load_bvh(_require(MOCAP_DIR) / name)
    save_bvh(tmp_path / name, clip)
    back = load_bvh(tmp_path / name)
    _assert_same(back, clip)
    error = np.abs(forward_kinematics(back) - forward_kinematics(clip)).max()
    assert error <= 1e-6, f"{name}: forward kinematics differ by {error:.3g}"


def test_tabs_crlf_and_mixed_channel_orders_round_trip(tmp_path):
    (tmp_path / "tiny.bvh").write_bytes(TINY.encode())
    clip = load_bvh(tmp_path / "tiny.bvh")
    save_bvh(tmp_path / "out.bvh", clip)
    _assert_same(load_bvh(tmp_path / "out.bvh"), clip)


def _forest():
    """Two roots; a leaf joint with channels; a leaf without channels named as no End Site would be
    ("tip"); one named like an End Site ("b_end"); a name with spaces; awkward floats."""
    names = ("a", "b", "b_end", "left hand", "tip", "other root", "other root_end")
    parents = np.array([-1, 0, 1, 0, 3, -1, 5])
    channels = (("Zposition", "Xposition", "Yrotation", "Xrotation"), ("Yrotation", "Zrotation", "Xrotation"),
                (), ("Xrotation",), (), ("Xposition", "Yposition", "Zposition"), ())
    offsets = np.array([[0.0, 0, 0], [1e-300, -0.0, 1 / 3], [0, 2, 0], [-1, 0.1, 0], [0, 0, 1.5],
                        [5, 5, 5], [0.1, 0.2, 0.3]])
    rng = np.random.default_rng(1)
    motion = rng.normal(scale=40, size=(4, 4 + 3 + 1 + 3))
    motion[0, 0] = 1e-17
    return BvhClip(names=names, parents=parents, offsets=offsets, channels=channels, motion=motion,
                   frame_time=1 / 24)


def test_several_roots_end_sites_and_odd_names_round_trip(tmp_path):
    clip = _forest()
    save_bvh(tmp_path / "forest.bvh", clip)
    text = (tmp_path / "forest.bvh").read_text()
    assert text.count("ROOT ") == 2 and text.count("End Site") == 2  # b_end and other root_end
    assert "JOINT tip" in text and "CHANNELS 0" in text
    back = load_bvh(tmp_path / "forest.bvh")
    _assert_same(back, clip)
    assert np.abs(forward_kinematics(back) - forward_kinematics(clip)).max() == 0


def test_a_clip_not_in_depth_first_order_reads_back_depth_first(tmp_path):
    # root, then two children, then a grandchild of the first: the file lists the grandchild second.
    clip = BvhClip(names=("r", "a", "b", "a2"), parents=np.array([-1, 0, 0, 1]),
                   offsets=np.arange(12.0).reshape(4, 3), channels=(("Xposition",), ("Zrotation",),
                                                                    ("Xrotation",), ("Yrotation",)),
                   motion=np.array([[1.0, 2, 3, 4], [5, 6, 7, 8]]), frame_time=0.5)
    save_bvh(tmp_path / "clip.bvh", clip)
    back = load_bvh(tmp_path / "clip.bvh")
    order = [clip.names.index(n) for n in back.names]
    assert back.names == ("r", "a", "a2", "b")
    assert np.array_equal(back.offsets, clip.offsets[order])
    assert np.array_equal(back.motion, clip.motion[:, order])
    assert np.array_equal(forward_kinematics(back), forward_kinematics(clip)[:, order])


def _clip(**change):
    fields = dict(names=("r", "c"), parents=np.array([-1, 0]), offsets=np.zeros((2, 3)),
                  channels=(("Xposition",), ("Zrotation",)), motion=np.zeros((1, 2)), frame_time=0.1)
    fields.update(change)
    return BvhClip(**fields)


@pytest.mark.parametrize(
    "clip, message",
    [
        (_clip(names=("r", "r")), "'r' is used twice"),
        (_clip(names=("r", "two  spaces")), "cannot be written"),
        (_clip(names=("r", "")), "cannot be written"),
        (_clip(names=("r", "a {")), "cannot be written"),
        (_clip(names=("r", "tab\there")), "cannot be written"),
        (_clip(channels=(("Xposition",), ("Wrotation",))), "BVH channels are"),
        (_clip(channels=(("Xposition",), ("Zrotation",)), motion=np.array([[0.0, np.nan]])), "not finite"),
        (_clip(offsets=np.array([[0.0, 0, 0], [np.inf, 0, 0]])), "not finite"),
        (_clip(frame_time=0.0), "frame time"),
        (_clip(names=(), parents=np.zeros(0), offsets=np.zeros((0, 3)), channels=(), motion=np.zeros((1, 0))),
         "no joints"),
    ],
)
def test_clips_bvh_cannot_hold_raise_one_line_and_write_nothing(clip, message, tmp_path):
    path = tmp_path / "clip.bvh"
    path.write_text("before")
    with pytest.raises(MotionError, match=message) as caught:
        save_bvh(path, clip)
    assert "\n" not in str(caught.value)
    assert path.read_text() == "before"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["clip.bvh"]
