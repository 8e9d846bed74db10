"""``toonmotion project-mocap`` and ``api.project_mocap`` (issue 45 item 5): a mocap clip seen from a
view as a drawn 2D motion that ``retarget`` plays on a drawing."""

import numpy as np
import pytest
from PIL import Image

from tests.conftest import run_cli
from tests.proxy3d.conftest import clip_path
from toonmotion import api
from toonmotion.capture.bvh_kinematics import forward_kinematics
from toonmotion.capture.mocap import STANDARD_JOINTS, pick_joints
from toonmotion.errors import ProxyError
from toonmotion.io.bvh import load_bvh
from toonmotion.io.motion_json import load_motion
from toonmotion.io.project import save_project
from toonmotion.proxy3d.orthographic import camera

WALK = "cmu_07_01_walk.bvh"
# The shared drawings' own names for the clip's joints: their root on the hips, their torso.
DRAWING_MAP = {"root": "Hips", "torso": "Spine1"}


@pytest.fixture(scope="module")
def walk():
    return load_bvh(clip_path(WALK))


def _one_line_error(capsys):
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("toonmotion: error: ") and "Traceback" not in err, err
    return err


def _fitted_residual(motion, clip, view, joint_map=None, start=0):
    """Largest distance, px, between the motion and the best ``s * camera(view) @ X + o`` of the clip's
    own joints (forward kinematics), one scale and one offset for the whole clip; and the scale."""
    picks = pick_joints(clip.names, clip.parents)
    joint_map = joint_map or {}
    index = [clip.names.index(joint_map[n]) if n in joint_map else picks[n] for n in motion.skeleton.names]
    seen = forward_kinematics(clip)[start:, index] @ camera(*view).T  # (T, J, 2)
    p, q = seen.reshape(-1, 2), motion.positions.reshape(-1, 2)
    A = np.zeros((2 * len(p), 3))
    A[0::2, 0], A[0::2, 1] = p[:, 0], 1.0
    A[1::2, 0], A[1::2, 2] = p[:, 1], 1.0
    (scale, ox, oy), *_ = np.linalg.lstsq(A, q.ravel(), rcond=None)
    return float(np.abs(scale * p + [ox, oy] - q).max()), float(scale)


def test_the_written_motion_has_the_clip_s_frames_and_standard_joints(walk, tmp_path, capsys):
    out = tmp_path / "walk.json"
    assert run_cli("project-mocap", clip_path(WALK), "--view", "90,0", "-o", out) == 0
    said = capsys.readouterr().out
    assert f"projected 16 joints of {WALK} seen from 90,0: {walk.frame_count} frames" in said
    motion = load_motion(out)
    assert motion.frame_count == walk.frame_count and motion.fps == pytest.approx(walk.fps)
    assert set(motion.skeleton.names) == set(STANDARD_JOINTS)
    assert motion.skeleton.names[int(np.flatnonzero(motion.skeleton.parents < 0)[0])] == "hips"
    # The rest pose is the first frame; the whole clip fits the default 640 x 480 with 10% clear.
    np.testing.assert_array_equal(motion.skeleton.positions, motion.positions[0])
    lo, hi = motion.positions.min(axis=(0, 1)), motion.positions.max(axis=(0, 1))
    assert np.all(lo >= [64 - 1e-9, 48 - 1e-9]) and np.all(hi <= [576 + 1e-9, 432 + 1e-9])
    assert np.isclose(lo, [64, 48]).any() or np.isclose(hi, [576, 432]).any()


def test_a_segment_a_frame_rate_and_a_size(walk, tmp_path):
    out = tmp_path / "part.json"
    assert run_cli("project-mocap", clip_path(WALK), "--view", "0,0", "--segment", "1:121", "-o", out,
                   "--size", "300x200") == 0
    motion = load_motion(out)
    assert motion.frame_count == 120
    assert motion.positions[..., 0].max() <= 270 + 1e-9 and motion.positions[..., 1].max() <= 180 + 1e-9
    assert run_cli("project-mocap", clip_path(WALK), "--view", "0,0", "--fps", "24", "-o", out) == 0
    slow = load_motion(out)
    assert slow.fps == 24 and slow.frame_count == int((walk.frame_count - 1) / walk.fps * 24 + 1e-9) + 1


@pytest.mark.parametrize("view", [(0.0, 0.0), (90.0, 0.0), (-35.0, 25.0), (150.0, -60.0)])
def test_each_joint_is_the_clip_s_joint_seen_through_the_camera(walk, view):
    motion = api.project_mocap(walk, view=view)
    residual, scale = _fitted_residual(motion, walk, view)
    assert residual < 1e-9 and scale > 0


def test_mapped_joints_carry_the_drawing_s_names_and_are_exact(walk, tmp_path):
    out = tmp_path / "mapped.json"
    assert run_cli("project-mocap", clip_path(WALK), "--view", "30,10", "--segment", "1:",
                   "--map", "root=Hips,torso=Spine1,front_left_foot=LeftHand", "-o", out) == 0
    motion = load_motion(out)
    names = motion.skeleton.names
    # Hips shows as root and LeftHand as front_left_foot, in place of hips and left_hand; Spine1
    # (above the standard spine, Spine) is added as torso, now the shoulders' and neck's parent.
    assert {"root", "torso", "front_left_foot", "spine"} <= set(names)
    assert not {"hips", "left_hand"} & set(names) and len(names) == 17
    parent = {n: None if p < 0 else names[p] for n, p in zip(names, motion.skeleton.parents, strict=True)}
    assert parent["spine"] == "root" and parent["torso"] == "spine"
    assert parent["neck"] == parent["left_shoulder"] == "torso" and parent["front_left_foot"] == "left_elbow"
    residual, _ = _fitted_residual(motion, walk, (30, 10), {**DRAWING_MAP, "front_left_foot": "LeftHand"},
                                   start=1)
    assert residual < 1e-9


def test_a_walk_along_z_crosses_the_picture_from_the_side_not_from_the_front(walk):
    side = api.project_mocap(walk, view=(90, 0), segment=(1, None))
    front = api.project_mocap(walk, view=(0, 0), segment=(1, None))
    hips_side = side.positions[:, side.skeleton.index("hips")]
    hips_front = front.positions[:, front.skeleton.index("hips")]
    # From +X the walk's +Z is the picture's left: the hips cross most of the 512 px the picture
    # leaves between its margins, right to left; from the front they stay within a few percent.
    assert hips_side[0, 0] - hips_side[-1, 0] > 0.6 * 512
    assert np.ptp(hips_front[:, 0]) < 0.05 * 512
    # Either way the head is above the feet (y down).
    for motion in (side, front):
        head, feet = (motion.positions[:, motion.skeleton.index(n), 1] for n in ("head", "left_foot"))
        assert np.all(head < feet)


def test_a_z_up_clip_is_turned_up_as_lift_does():
    zombie = load_bvh(clip_path("fair_zombie.bvh"))
    motion = api.project_mocap(zombie, view=(0, 0), segment=(0, 60))
    head, foot = (motion.positions[:, motion.skeleton.index(n), 1] for n in ("head", "right_foot"))
    assert np.all(head < foot) and np.ptp(motion.positions[..., 1]) > 200


def test_the_motion_retargets_onto_a_shared_drawing(walk, rigs, tmp_path, capsys):
    motion_file = tmp_path / "walk_side.json"
    assert run_cli("project-mocap", clip_path(WALK), "--view", "90,0", "--segment", "1:61", "--fps", "12",
                   "--map", "root=Hips,torso=Spine1", "-o", motion_file) == 0
    motion = load_motion(motion_file)
    character = rigs.character("char1")
    moved = api.retarget(motion, character.skeleton)
    # Every bone of the drawing but root -> hip -> torso follows the clip; the root walks left.
    root = moved.positions[:, moved.skeleton.index("root")]
    assert root[-1, 0] < root[0, 0] - 50
    project = tmp_path / "char1"
    save_project(project, character)
    capsys.readouterr()
    out = tmp_path / "walk_side.gif"
    assert run_cli("retarget", motion_file, project, "-o", out) == 0, capsys.readouterr().err
    with Image.open(out) as gif:
        assert gif.n_frames == motion.frame_count
    assert (project / "motions" / "walk_side.json").is_file()


def test_bad_view_and_map_are_one_line_errors_and_write_nothing(tmp_path, capsys):
    out = tmp_path / "motion.json"
    walk = clip_path(WALK)
    cases = [
        (["--view", "30", "-o", out], "--view takes 2 comma-separated numbers"),
        (["--view", "abc,1", "-o", out], "--view takes 2 comma-separated numbers"),
        (["--view", "0,100", "-o", out], "elevation must be between -90 and 90 degrees"),
        (["--view", "0,0", "--map", "root", "-o", out], "--map takes NAME=NAME pairs"),
        (["--view", "0,0", "--map", "front_left_foot=LeftHnd", "-o", out],
         "'LeftHnd', which the mocap clip does not have (did you mean 'LeftHand'?)"),
        (["--view", "0,0", "--map", "a=LeftHand,b=LeftHand", "-o", out],
         "names the clip's joint 'LeftHand' for both 'a' and 'b'"),
        (["--view", "0,0", "--segment", "500:", "-o", out], "the segment 500: holds none of the clip's 317"),
        (["--view", "0,0", "--fps", "0", "-o", out], "the motion's fps must be a finite number > 0"),
        (["--view", "0,0", "--size", "0x10", "-o", out], "--size"),
        (["--view", "0,0", "-o", tmp_path / "motion.txt"], ".json"),
    ]
    for argv, words in cases:
        assert run_cli("project-mocap", walk, *argv) == 2, argv
        err = _one_line_error(capsys)
        assert words in err, (argv, err)
    assert not out.exists()
    with pytest.raises(ProxyError, match="elevation"):
        api.project_mocap(load_bvh(walk), view=(0, -91))
    with pytest.raises(ProxyError, match="the view is two angles"):
        api.project_mocap(load_bvh(walk), view=(0,))  # type: ignore[arg-type]
