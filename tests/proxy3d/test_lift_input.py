"""``lift`` refuses input that does not belong (issue 45 item 4): a ``--map`` key that names no marker,
and drawn frames the markers do not lie on."""

import numpy as np
import pytest

from tests.conftest import run_cli
from tests.proxy3d.conftest import clip_path
from toonmotion import api
from toonmotion.animate.motion import Motion
from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.errors import ProxyError
from toonmotion.io.bvh import load_bvh
from toonmotion.io.image import save_png
from toonmotion.io.markers_json import save_markers
from toonmotion.io.proxy_json import load_proxy
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.lift import OFF_FRAMES, OFF_MARGIN, lift
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import view_direction
from toonmotion.proxy3d.prior import prior_from_bvh, prior_in_metres, resample_prior
from toonmotion.rig.skeleton import Skeleton

FOCAL, IMAGE = 900.0, (640, 480)


@pytest.fixture(scope="module")
def walk():
    return load_bvh(clip_path("cmu_07_01_walk.bvh"))


@pytest.fixture(scope="module")
def truth(walk):
    """The CMU walk's first second at 12 fps, in metres."""
    return resample_prior(prior_in_metres(prior_from_bvh(walk, STANDARD_JOINTS, start=1, stop=121))[0], 12)


@pytest.fixture(scope="module")
def drawn(truth):
    """The walk seen from (30, 10) on a 640 x 480 picture."""
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([30.0, 10.0, 0.0]), middle + 7 * view_direction(30, 10)])
    cam = PerspectiveCamera(FOCAL, *IMAGE, np.tile(ext, (truth.frame_count, 1)))
    return Markers(truth.names, cam.project(truth.positions), fps=12)


@pytest.fixture(scope="module")
def files(drawn, tmp_path_factory):
    folder = tmp_path_factory.mktemp("lift_input")
    save_markers(folder / "markers.json", drawn)
    return folder


def _one_line_error(capsys):
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and err.startswith("toonmotion: error: ") and "Traceback" not in err, err
    return err


# --- --map keys -------------------------------------------------------------------------------


def test_a_map_key_that_names_no_marker_is_refused_with_the_markers(walk, drawn):
    with pytest.raises(ProxyError) as caught:
        api.lift_proxy(drawn, walk, joint_map={"ghost": "Hips"}, view=(30, 10))
    message = str(caught.value)
    assert "'ghost'" in message and "not one of the markers" in message and "\n" not in message
    assert ", ".join(drawn.names) in message  # every marker listed
    assert "did you mean" not in message  # nothing is close to "ghost"


def test_a_misspelt_map_key_suggests_the_marker_meant(walk, drawn):
    with pytest.raises(ProxyError, match=r"'left_hnd', .* \(did you mean 'left_hand'\?\)"):
        api.lift_proxy(drawn, walk, joint_map={"left_hnd": "LeftHand"}, view=(30, 10))


def test_a_misspelt_clip_joint_suggests_the_joint_meant(walk, drawn):
    with pytest.raises(ProxyError, match=r"'LeftHnd', which the mocap clip does not have \(did you mean "
                                         r"'LeftHand'\?\)"):
        api.lift_proxy(drawn, walk, joint_map={"left_hand": "LeftHnd"}, view=(30, 10))


def test_the_command_refuses_an_unknown_map_key_in_one_line(walk, files, capsys):
    out = files / "ghost.json"
    code = run_cli("lift", files / "markers.json", "--prior", clip_path("cmu_07_01_walk.bvh"), "--map",
                   "ghost=Hips", "--view", "30,10", "-o", out)
    assert code == 2
    err = _one_line_error(capsys)
    assert "'ghost'" in err and "left_hand" in err
    assert not out.exists()
    assert run_cli("lift", files / "markers.json", "--prior", clip_path("cmu_07_01_walk.bvh"), "--map",
                   "left_hnd=LeftHand", "--view", "30,10", "-o", out) == 2
    assert "did you mean 'left_hand'?" in _one_line_error(capsys)


def test_with_a_motion_only_the_user_s_keys_are_checked(walk, drawn, truth):
    """A motion named like the shared drawings (root, hip, torso) is matched by role; those entries
    are not the user's and pass, a stray key of the user's is refused by name."""
    rename = {"hips": "hip", "spine": "torso"}
    parent = dict(zip(truth.names, [None if p < 0 else truth.names[p] for p in truth.parents], strict=True))
    joints = [("root", None, tuple(drawn.positions[0, 0]))] + [
        (rename.get(n, n), "root" if parent[n] is None else rename.get(parent[n], parent[n]),
         tuple(drawn.positions[0, i])) for i, n in enumerate(drawn.names)]
    skeleton = Skeleton.from_joints(joints)
    columns = {rename.get(n, n): i for i, n in enumerate(drawn.names)} | {"root": 0}
    motion = Motion(skeleton, drawn.positions[:, [columns[n] for n in skeleton.names]], fps=12)
    with pytest.raises(ProxyError, match="names the marker 'ghost', which is not one of the markers"):
        api.lift_proxy(motion, walk, joint_map={"ghost": "Hips"}, view=(30, 10))
    proxy, report = api.lift_proxy(motion, walk, joint_map={"left_hand": "LeftHand"}, segment=(1, 121),
                                   view=(30, 10), focal=FOCAL, size=IMAGE)
    assert {"hip", "torso", "left_hand"} <= set(proxy.names) and report.left_out == ("root",)


# --- frames -----------------------------------------------------------------------------------


def test_frames_of_another_picture_are_refused(drawn, truth):
    """Issue 45: markers spread over 1669 px on 562 x 379 px frames."""
    lo, hi = drawn.positions.min(axis=(0, 1)), drawn.positions.max(axis=(0, 1))
    wide = Markers(drawn.names, (drawn.positions - lo) * [1669 / (hi - lo)[0], 1.0] + [0, 10], fps=12)
    frames = np.full((truth.frame_count, 379, 562, 3), 255, np.uint8)
    with pytest.raises(ProxyError) as caught:
        lift(wide, truth, view=(30, 10), frames=frames)
    assert str(caught.value) == ("the markers reach x = 1669 px but the frames are 562×379 px: are these "
                                 "frames of this motion? (--frames)")


def test_the_command_refuses_frames_of_another_size_in_one_line(files, truth, capsys):
    small = files / "small"
    small.mkdir()
    for t in range(truth.frame_count):
        save_png(small / f"f_{t:03d}.png", np.full((100, 120, 4), 255, np.uint8))
    out = files / "small.json"
    code = run_cli("lift", files / "markers.json", "--prior", clip_path("cmu_07_01_walk.bvh"), "--segment",
                   "1:121", "--view", "30,10", "--frames", small, "-o", out)
    assert code == 2
    err = _one_line_error(capsys)
    assert "but the frames are 120×100 px: are these frames of this motion? (--frames)" in err
    assert not out.exists()


def test_the_right_frames_are_accepted(drawn, truth, files, capsys):
    frames = np.full((truth.frame_count, IMAGE[1], IMAGE[0], 3), 255, np.uint8)
    proxy, _ = lift(drawn, truth, view=(30, 10), focal=FOCAL, frames=frames)
    assert proxy.radii is not None and proxy.camera.width == IMAGE[0]
    folder = files / "frames"
    folder.mkdir()
    for t, picture in enumerate(frames):
        save_png(folder / f"f_{t:03d}.png", np.concatenate([picture, picture[..., :1]], axis=2))
    code = run_cli("lift", files / "markers.json", "--prior", clip_path("cmu_07_01_walk.bvh"), "--segment",
                   "1:121", "--view", "30,10", "--focal", FOCAL, "--frames", folder, "-o", files / "ok.json")
    assert code == 0, capsys.readouterr().err
    assert load_proxy(files / "ok.json").radii is not None


def test_a_few_markers_off_the_frames_are_accepted_many_are_not(drawn, truth):
    """The rule: at most OFF_FRAMES of the positions beyond the frame enlarged by OFF_MARGIN."""
    x = drawn.positions[..., 0].ravel()

    def frames_leaving_off(share):
        width = int(np.ceil(np.quantile(x, 1 - share) / (1 + OFF_MARGIN)))
        return np.full((truth.frame_count, IMAGE[1], width, 3), 255, np.uint8)

    few = frames_leaving_off(OFF_FRAMES / 2)
    assert 0 < np.mean(x > (1 + OFF_MARGIN) * few.shape[2]) <= OFF_FRAMES
    proxy, _ = lift(drawn, truth, view=(30, 10), focal=FOCAL, frames=few)
    assert proxy.radii is not None
    many = frames_leaving_off(2 * OFF_FRAMES)
    with pytest.raises(ProxyError, match=rf"the markers reach x = {x.max():.0f} px but the frames are "
                                         rf"{many.shape[2]}×{IMAGE[1]} px"):
        lift(drawn, truth, view=(30, 10), focal=FOCAL, frames=many)
