"""Tests for toonmotion.capture.bvh_kinematics: a BVH clip's joints in every frame."""

import time

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.conftest import SHARED_DATA, _require
from tests.io.test_bvh import TINY, _write
from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics
from toonmotion.io.bvh import load_bvh

MOCAP_DIR = SHARED_DATA / "mocap"
CLIPS = sorted(p.name for p in MOCAP_DIR.glob("*.bvh")) or ["<missing>"]


@pytest.fixture(scope="module", params=CLIPS)
def shared_clip(request):
    return load_bvh(_require(MOCAP_DIR) / request.param)


def test_bone_lengths_stay_constant_in_every_shared_clip(shared_clip):
    clip = shared_clip
    P = forward_kinematics(clip)
    assert P.shape == (clip.frame_count, len(clip.names), 3)
    child = np.flatnonzero(clip.parents >= 0)
    lengths = np.linalg.norm(P[:, child] - P[:, clip.parents[child]], axis=2)
    # Every bone is as long as its rest offset (no joint but the root has position channels).
    rest = np.linalg.norm(clip.offsets[child], axis=1)
    np.testing.assert_allclose(lengths, np.broadcast_to(rest, lengths.shape), rtol=0, atol=1e-12)


def test_forward_kinematics_by_hand(tmp_path):
    P = forward_kinematics(load_bvh(_write(tmp_path, TINY)))[0]
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


def test_forward_kinematics_matches_axis_matrices_composed_in_channel_order():
    # Issue 10 moved forward kinematics here, onto scipy's Euler angles: the same numbers as
    # hand-written axis rotations multiplied in the order the channels are listed.
    rng = np.random.default_rng(3)
    orders = [("Xposition", "Zrotation", "Yposition", "Xrotation", "Yrotation", "Zposition"),
              ("Yrotation", "Xrotation", "Zrotation"), ("Xrotation",), (), ("Zrotation", "Yrotation"),
              ("Xposition", "Zrotation"), ("Zrotation", "Xrotation", "Yrotation"), ()]
    parents = np.array([-1, 0, 1, 2, 1, 4, 5, -1])
    T = 17
    clip = BvhClip(names=tuple(f"j{i}" for i in range(len(orders))), parents=parents,
                   offsets=rng.normal(size=(len(orders), 3)), channels=tuple(orders),
                   motion=rng.uniform(-180, 180, size=(T, sum(map(len, orders)))), frame_time=0.1)
    expected = np.empty((T, len(orders), 3))
    for t in range(T):
        values = iter(clip.motion[t])
        world = []
        for j, channels in enumerate(orders):
            R, offset = np.eye(3), clip.offsets[j].copy()
            for name in channels:
                value, axis = next(values), "XYZ".index(name[0])
                if name.endswith("position"):
                    offset[axis] = value
                else:
                    R = R @ _axis_matrix(axis, np.radians(value))
            p = parents[j]
            if p >= 0:
                R, offset = world[p][0] @ R, expected[t, p] + world[p][0] @ offset
            world.append((R, offset))
            expected[t, j] = offset
    np.testing.assert_allclose(forward_kinematics(clip), expected, rtol=0, atol=1e-12)


def _axis_matrix(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.eye(3)
    R[i, i] = R[j, j] = c
    R[i, j], R[j, i] = -s, s
    return R


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


def test_a_clip_of_no_frames_has_no_positions():
    clip = BvhClip(names=("r", "r_end"), parents=[-1, 0], offsets=np.ones((2, 3)),
                   channels=(("Zrotation",), ()), motion=np.zeros((0, 1)), frame_time=0.1)
    assert forward_kinematics(clip).shape == (0, 2, 3)


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
