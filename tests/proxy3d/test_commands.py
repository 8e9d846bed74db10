"""The 3D proxy commands: lift, proxy-export, proxy-preview (and a failed run overwrites nothing)."""

import numpy as np
import pytest

from tests.conftest import run_cli
from tests.proxy3d.conftest import clip_path
from toonmotion.capture.bvh_kinematics import forward_kinematics
from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.io.bvh import load_bvh
from toonmotion.io.markers_json import save_markers
from toonmotion.io.motion_json import save_motion
from toonmotion.io.proxy_json import load_proxy
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import view_direction
from toonmotion.proxy3d.prior import prior_from_bvh, prior_in_metres, resample_prior
from toonmotion.proxy3d.skeleton_bvh import limb_tree


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """The CMU walk's first 1.5 s at 12 fps seen from (30, 10): a markers file."""
    walk = clip_path("cmu_07_01_walk.bvh")
    truth = resample_prior(prior_in_metres(prior_from_bvh(load_bvh(walk), STANDARD_JOINTS, start=1))[0], 12)
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([30.0, 10.0, 0.0]), middle + 7 * view_direction(30, 10)])
    cam = PerspectiveCamera(900.0, 640, 480, np.tile(ext, (truth.frame_count, 1)))
    markers = Markers(truth.names, cam.project(truth.positions), fps=12)
    folder = tmp_path_factory.mktemp("lift")
    save_markers(folder / "markers.json", markers)
    return folder, walk, markers


def test_lift_writes_a_proxy_and_its_exports(drawn, capsys):
    folder, walk, markers = drawn
    code = run_cli("lift", folder / "markers.json", "--prior", walk, "--view", "30,10", "--focal", "900",
                   "--size", "640x480", "-o", folder / "proxy.json", "--glb", folder / "proxy.glb", "--bvh",
                   folder / "proxy.bvh", "--preview", folder / "preview.gif")
    out = capsys.readouterr().out
    assert code == 0, out
    assert "lifted 16 markers over" in out and "(given)" in out
    proxy = load_proxy(folder / "proxy.json")
    seen = proxy.camera.project(proxy.points)
    assert np.abs(seen - markers.positions).max() < 1e-6
    clip = load_bvh(folder / "proxy.bvh")
    tree = limb_tree(proxy)
    at = forward_kinematics(clip)[:, [clip.names.index(tree.names[j]) for j in tree.markers]]
    assert np.abs(at - proxy.skeleton).max() < 1e-6
    assert (folder / "proxy.glb").read_bytes()[:4] == b"glTF"
    assert (folder / "preview.gif").stat().st_size > 0
    # The exports again, from the proxy file.
    assert run_cli("proxy-export", folder / "proxy.json", "-o", folder / "again.bvh") == 0
    assert load_bvh(folder / "again.bvh").motion.shape == clip.motion.shape
    assert run_cli("proxy-preview", folder / "proxy.json", "-o", folder / "frames") == 0
    assert len(list((folder / "frames").glob("*.png"))) == proxy.frame_count


def test_a_motion_s_joints_are_matched_by_their_role(drawn, capsys, tmp_path):
    """A motion named like a toonmotion character (hip, torso, an extra root) lifts with a CMU clip."""
    from toonmotion.animate.motion import Motion
    from toonmotion.rig.skeleton import Skeleton

    _, walk, markers = drawn
    rename = {"hips": "hip", "spine": "torso"}
    names = ["root"] + [rename.get(n, n) for n in markers.names]
    parents = {"hip": "root", "torso": "hip", "neck": "torso", "head": "neck", "left_shoulder": "torso",
               "left_elbow": "left_shoulder", "left_hand": "left_elbow", "right_shoulder": "torso",
               "right_elbow": "right_shoulder", "right_hand": "right_elbow", "left_hip": "hip",
               "left_knee": "left_hip", "left_foot": "left_knee", "right_hip": "hip",
               "right_knee": "right_hip", "right_foot": "right_knee", "root": None}
    first = markers.positions[0]
    joints = [("root", None, tuple(first[0]))] + [
        (n, parents[n], tuple(first[i])) for i, n in enumerate(names[1:])]
    skeleton = Skeleton.from_joints(joints)
    positions = np.concatenate([markers.positions[:, :1], markers.positions], axis=1)
    order = [names.index(n) for n in skeleton.names]
    save_motion(tmp_path / "motion.json", Motion(skeleton, positions[:, order], fps=12))
    code = run_cli("lift", tmp_path / "motion.json", "--prior", walk, "--view", "30,10", "--focal", "900",
                   "--size", "640x480", "-o", tmp_path / "proxy.json")
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "left out root" in captured.err
    assert "torso" in load_proxy(tmp_path / "proxy.json").names


def test_bad_input_exits_2_in_one_line_and_overwrites_nothing(drawn, capsys, tmp_path):
    folder, walk, markers = drawn
    kept = tmp_path / "proxy.json"
    kept.write_text("precious")
    odd = Markers(("pelvis",) + markers.names[1:], markers.positions, fps=12)
    save_markers(tmp_path / "odd.json", odd)
    short = tmp_path / "short.bvh"
    clip = load_bvh(walk)
    from toonmotion.io.bvh import save_bvh

    save_bvh(short, type(clip)(clip.names, clip.parents, clip.offsets, clip.channels, clip.motion[:20],
                               clip.frame_time))
    hand = markers.names[-1]
    cases = [
        (["lift", tmp_path / "odd.json", "--prior", walk, "-o", kept], "pelvis"),
        (["lift", folder / "markers.json", "--prior", short, "-o", kept], "too short"),
        (["lift", folder / "markers.json", "--prior", walk, "--view", "30", "-o", kept], "--view"),
        (["lift", folder / "markers.json", "--prior", walk, "--segment", "x:y", "-o", kept], "--segment"),
        (["lift", folder / "markers.json", "--prior", walk, "--up", "level", "-o", kept],
         "--up takes an angle in degrees or 'free'"),
        (["lift", folder / "markers.json", "--prior", walk, "--width", "3=1,2", "-o", kept], "--width"),
        (["lift", folder / "markers.json", "--prior", walk, "--width", f"0:{hand}=1,2", "-o", kept],
         "give them with --frames"),
        (["lift", folder / "markers.json", "--prior", walk, "--frames", folder / "markers.json",
          "--width", f"0:{hand}=-5,3", "-o", kept], f"the limb to {hand} needs two"),
        (["lift", folder / "markers.json", "--prior", walk, "-o", tmp_path / "proxy.txt"], ".json"),
        (["proxy-export", kept, "-o", tmp_path / "out.glb"], "proxy"),
        (["proxy-export", folder / "markers.json", "-o", tmp_path / "out.fbx"], ".glb"),
    ]
    for argv, words in cases:
        assert run_cli(*argv) == 2, argv
        err = capsys.readouterr().err.strip()
        assert err.count("\n") == 0 and words in err and "Traceback" not in err, (argv, err)
        assert kept.read_text() == "precious"
