"""The 3D panel's requests without a browser: the key-frames' animation lifted with a prior from the
library or sent to the project, elements simulated and composited into its frames, exports; each
checked against the same library calls, kept in the project across a restart, and refused in one
line when wrong."""

import json
import shutil

import numpy as np
import pytest
from fastapi.testclient import TestClient

from tests.conftest import SHARED_DATA, _require
from toonmotion import api
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.io.bvh import load_bvh
from toonmotion.io.image import load_image
from toonmotion.io.pose_json import load_keyframes, save_keyframes
from toonmotion.io.proxy_json import load_proxy
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character
from toonmotion.scene.elements import Balloon
from toonmotion.web.server import create_app

TOKEN = "secret-token"
ORIGINS = ("http://testserver",)
PRIOR = "cmu_16_07_jump.bvh"


@pytest.fixture(scope="module")
def library():
    return _require(SHARED_DATA / "mocap")


@pytest.fixture(scope="module")
def keyed(tmp_path_factory):
    """The half-size sample character with the sample key-frames, as a project folder."""
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("proxy") / "hero"
    character = rig_drawing(drawing, skeleton=skeleton)
    api.save_project(folder, character)
    save_keyframes(folder / "keys.json", character.skeleton, sample_keyframes(character.skeleton, fps=6.0))
    return folder


@pytest.fixture
def editable(tmp_path, keyed, library):
    folder = tmp_path / "hero"
    shutil.copytree(keyed, folder)
    return folder, TestClient(create_app(folder, token=TOKEN, origins=ORIGINS, library=library))


def _ask(socket, message):
    """The reply to ``message``, and the progress messages before it."""
    socket.send_text(json.dumps(message))
    said = [socket.receive_json()]
    while said[-1]["type"] == "progress":
        said.append(socket.receive_json())
    return said[-1], said[:-1]


def _library_animation(folder):
    """The project's animation as the editor solves it (its deformer runs the compiled loop)."""
    character = api.load_project(folder)
    timeline = load_keyframes(folder / "keys.json", character.skeleton)
    return character, api.animate_character(Deformer(character, DeformSettings(compiled=True)), timeline)


@pytest.fixture
def lifted(editable, library):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply, progress = _ask(socket, {"id": 4, "type": "lift", "prior": f"library/{PRIOR}", "view": [0, 0]})
    assert reply["type"] == "proxy", reply
    return folder, client, reply, progress


def test_the_animation_lifted_in_the_editor_is_the_library_s_lift(lifted, library):
    folder, client, reply, progress = lifted
    assert progress and all(p["id"] == 4 and 0 <= p["index"] <= p["count"] for p in progress)
    character, animation = _library_animation(folder)
    expected, report = api.lift_animation(character, animation, load_bvh(library / PRIOR), view=(0.0, 0.0))
    saved = load_proxy(folder / "proxy3d" / "proxy.json")
    assert np.allclose(saved.points, expected.points, atol=1e-9)
    assert np.abs(np.array(reply["proxy"]["points"]) - expected.points).max() <= 5e-5  # sent to 4 places
    assert reply["proxy"]["names"] == list(expected.names)
    assert np.array(reply["proxy"]["radii"]).shape == expected.radii.shape
    assert np.allclose(reply["proxy"]["camera"]["centres"], expected.camera.centres, atol=5e-5)
    assert reply["lift"]["found"] == [round(report.azimuth, 2), round(report.elevation, 2)]
    assert reply["lift"]["searched"] is False and reply["lift"]["stale"] is False
    assert f"library/{PRIOR}" in reply["priors"] and reply["scene"] is None
    # A restart shows it again, from the project folder alone.
    again = TestClient(create_app(folder, token=TOKEN, origins=ORIGINS, library=library))
    with again.websocket_connect(f"/ws?token={TOKEN}") as socket:
        shown, _ = _ask(socket, {"type": "proxy"})
    assert shown["proxy"] == reply["proxy"] and shown["lift"] == reply["lift"]


def test_a_balloon_is_simulated_and_composited_as_the_scene_command_does(lifted):
    folder, client, _, _ = lifted
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply, progress = _ask(socket, {"id": 5, "type": "scene",
                                        "elements": [{"kind": "balloon", "markers": ["right_hand"]}]})
    assert reply["type"] == "scene", reply
    assert progress and reply["elements"] == [{"kind": "balloon", "markers": ["right_hand"], "count": 3}]
    character, animation = _library_animation(folder)
    proxy = load_proxy(folder / "proxy3d" / "proxy.json")
    pictures, limbs = api.animation_frames(character, animation, proxy)
    motion = api.simulate_scene(proxy, [Balloon("right_hand")])
    expected = list(api.composite_scene(proxy, pictures, motion, background=(255, 255, 255), limbs=limbs))
    assert reply["frames"] == len(expected) == proxy.frame_count
    for t in (0, len(expected) // 2, len(expected) - 1):
        assert np.array_equal(load_image(folder / "proxy3d" / "scene" / f"{t:04d}.png")[..., :3], expected[t])
    served = client.get("/api/scene/1.png", headers={"X-Toonmotion-Token": TOKEN})
    assert served.status_code == 200 and served.content == (folder / "proxy3d/scene/0001.png").read_bytes()
    assert client.get("/api/scene/999.png", headers={"X-Toonmotion-Token": TOKEN}).status_code == 404


@pytest.mark.parametrize(("kind", "files"), [("glb", ["wave.glb"]), ("bvh", ["wave.bvh"]),
                                             ("mp4", ["wave.mp4"])])
def test_the_proxy_and_the_scene_export_and_download(lifted, kind, files):
    folder, client, _, _ = lifted
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        if kind == "mp4":
            balls = {"kind": "balls", "markers": ["left_foot"], "count": 2}
            _ask(socket, {"type": "scene", "elements": [balls]})
        reply, _ = _ask(socket, {"type": "proxy_export", "format": kind, "name": "wave"})
    assert reply["files"] == [f"exports/{name}" for name in files], reply
    for name in files:
        download = client.get(f"/api/exports/{name}", headers={"X-Toonmotion-Token": TOKEN})
        assert download.status_code == 200 and download.content == (folder / "exports" / name).read_bytes()
    if kind == "bvh":
        clip = load_bvh(folder / "exports" / "wave.bvh")
        assert len(clip.motion) == load_proxy(folder / "proxy3d" / "proxy.json").frame_count


@pytest.mark.parametrize(("message", "said"), [
    ({"type": "lift", "prior": "library/nothing.bvh"}, "no prior 'library/nothing.bvh'; the priors are: "),
    ({"type": "lift", "prior": "library/../../secret.bvh"}, "no prior 'library/../../secret.bvh'"),
    ({"type": "lift", "prior": f"library/{PRIOR}", "ground": "sky"}, "'ground' must be 'prior' or 'feet'"),
    ({"type": "lift", "prior": f"library/{PRIOR}", "view": [0]}, "'view' must be null (searched) or"),
    ({"type": "scene", "elements": [{"kind": "balloon", "markers": ["right_hand"]}]},
     "there is no 3D proxy yet: lift the animation first"),
    ({"type": "proxy_export", "format": "glb", "name": "../x"}, "'name' must be 1 to 64 letters"),
])
def test_bad_requests_are_refused_in_one_line_and_nothing_is_written(editable, message, said):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply, _ = _ask(socket, message)
    assert reply["type"] == "error" and said in reply["message"] and "\n" not in reply["message"], reply
    assert not (folder / "proxy3d").exists() and not (folder / "exports").exists()


def test_a_scene_is_refused_in_one_line_when_its_elements_or_the_keys_do_not_fit(lifted):
    folder, client, _, _ = lifted
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        cape, _ = _ask(socket, {"type": "scene", "elements": [{"kind": "cape", "markers": ["neck"]}]})
        stray, _ = _ask(socket, {"type": "scene", "elements": [{"kind": "scarf", "markers": ["tail"]}]})
        character = api.load_project(folder)
        _ask(socket, {"type": "set_key", "frame": 40, "positions": character.skeleton.positions.tolist()})
        stale, _ = _ask(socket, {"type": "scene", "elements": [{"kind": "balloon", "markers": ["neck"]}]})
        state, _ = _ask(socket, {"type": "proxy"})
    assert cape["message"] == "a cape takes two markers, the figure's own left and right shoulders, got 1"
    assert stray["type"] == "error" and "tail" in stray["message"]
    assert stale["message"] == "the key-frames changed since the proxy was lifted: lift the animation again"
    assert state["lift"]["stale"] is True
    assert not (folder / "proxy3d" / "scene").exists()


def test_a_clip_sent_to_the_project_becomes_a_prior_and_a_bad_one_is_not_kept(editable, library):
    folder, client = editable
    headers = {"X-Toonmotion-Token": TOKEN}
    clip = (library / PRIOR).read_bytes()
    sent = client.put("/api/priors?name=my walk!.bvh", content=clip, headers=headers)
    assert sent.status_code == 200 and sent.json()["sent"] == "project/my_walk.bvh"
    assert sent.json()["priors"][0] == "project/my_walk.bvh"
    bad = client.put("/api/priors?name=notes.bvh", content=b"HIERARCHY\nnonsense", headers=headers)
    said = bad.json()["error"]
    assert bad.status_code == 400 and said.startswith("notes.bvh") and "\n" not in said
    assert sorted(p.name for p in (folder / "proxy3d" / "priors").iterdir()) == ["my_walk.bvh"]
