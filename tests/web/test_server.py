"""Tests for toonmotion.web.server without a browser: security, the project's data, live posing
and one-line errors."""

import io
import json
import time

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image
from starlette.websockets import WebSocketDisconnect

from tests.web.slow_work import slow_work
from toonmotion import api
from toonmotion.errors import MeshError, ProjectError
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character
from toonmotion.web import editing as editing_module
from toonmotion.web import session
from toonmotion.web.editing import Editing
from toonmotion.web.server import MAX_MESSAGE_BYTES, create_app
from toonmotion.web.wire import decode_vertices

TOKEN = "secret-token"
ORIGIN = "http://127.0.0.1:8000"
# The editor's origins in these tests: the test client names the host "testserver" (its WebSocket
# always does), so that name is the editor's own here.
ORIGINS = (ORIGIN, "http://testserver")


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("web") / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    return folder


@pytest.fixture(scope="module")
def client(project):
    return TestClient(create_app(project, token=TOKEN, origins=ORIGINS))


def _get(client, path, **headers):
    return client.get(path, headers={"X-Toonmotion-Token": TOKEN, **headers})


def test_the_page_and_its_code_are_served_without_the_token(client):
    page = client.get("/")
    assert page.status_code == 200 and "toonmotion editor" in page.text
    for name in ("app.js", "mesh_view.js", "pose_panel.js", "editor.css"):
        assert client.get(f"/static/{name}").status_code == 200
    assert client.get("/favicon.ico").status_code == 204


@pytest.mark.parametrize("headers", [{}, {"X-Toonmotion-Token": "wrong"}, {"X-Toonmotion-Token": ""}])
def test_the_project_needs_the_token(client, headers):
    reply = client.get("/api/project", headers=headers)
    assert reply.status_code == 403
    assert reply.json() == {"error": "missing or wrong token: open the address 'toonmotion edit' printed"}


def test_a_page_from_another_origin_is_refused(client):
    reply = _get(client, "/api/project", Origin="http://evil.example")
    assert (reply.status_code, reply.json()) == (
        403,
        {"error": "requests from http://evil.example are not allowed"},
    )
    assert _get(client, "/api/project", Origin=ORIGIN).status_code == 200
    assert client.get("/", headers={"Origin": "http://evil.example"}).status_code == 403


@pytest.mark.parametrize(
    "path",
    [
        "/static/../server.py",
        "/static/..%2Fserver.py",
        "/static/%2e%2e/server.py",
        "/static/__init__.py",
        "/static/../../../../etc/passwd",
        "/static/%2Fetc%2Fpasswd",
        "/static/index.html%00.js",
        "/api/../server.py",
        "/api/texture.png/../../project.json",
        "/hero/project.json",
        "/project.json",
    ],
)
def test_no_request_reaches_a_file_the_server_does_not_name(client, path):
    reply = _get(client, path)
    assert reply.status_code in (403, 404)
    assert "def create_app" not in reply.text and "root:" not in reply.text and '"format"' not in reply.text
    assert list(reply.json()) == ["error"]


def test_the_project_data_is_the_saved_character(client, project):
    character = api.load_project(project)
    data = _get(client, "/api/project").json()
    assert (data["width"], data["height"]) == character.size
    np.testing.assert_array_equal(np.reshape(data["vertices"], (-1, 2)), character.mesh.V)
    triangles = np.sort(np.reshape(data["triangles"], (-1, 3)), axis=1)
    expected = np.sort(character.mesh.F, axis=1)
    assert sorted(map(tuple, triangles)) == sorted(map(tuple, expected))  # all of them, in draw order
    assert [j["name"] for j in data["joints"]] == list(character.skeleton.names)
    texture = np.asarray(Image.open(io.BytesIO(_get(client, "/api/texture.png").content)))
    np.testing.assert_array_equal(texture, character.texture)


def _pose(character, joint, angle):
    return api.rotate_joint(character, joint, angle).positions.tolist()


def test_a_pose_comes_back_as_the_deformed_mesh_the_library_computes(client, project):
    character = api.load_project(project)
    positions = _pose(character, "right_elbow", 0.9)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(json.dumps({"id": 7, "type": "pose", "positions": positions}))
        reply = socket.receive_json()
    assert (reply["id"], reply["type"]) == (7, "mesh")
    expected = api.pose_character(character, api.rotate_joint(character, "right_elbow", 0.9))
    np.testing.assert_allclose(decode_vertices(reply["U"]), expected.deformation.U, atol=1e-3)
    assert np.abs(decode_vertices(reply["U"]) - character.mesh.V).max() > 5  # the arm moved


def test_a_sketched_forearm_poses_the_arm_and_the_mesh_follows(client, project):
    character = api.load_project(project)
    bent = np.array(_pose(character, "right_elbow", 0.9))
    elbow, hand = (character.skeleton.index(n) for n in ("right_elbow", "right_hand"))
    stroke = np.linspace(bent[elbow], bent[hand], 12).tolist()
    rest = character.skeleton.positions.tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(json.dumps({"id": 4, "type": "sketch", "strokes": [stroke], "positions": rest}))
        reply = socket.receive_json()
    assert (reply["id"], reply["type"], reply["elsewhere"]) == (4, "sketched", False)
    assert reply["bones"] == ["right_hand"]
    np.testing.assert_allclose(reply["positions"], bent, atol=1e-6)
    posed = api.pose_character(character, api.rotate_joint(character, "right_elbow", 0.9))
    np.testing.assert_allclose(decode_vertices(reply["U"]), posed.deformation.U, atol=1e-3)


@pytest.mark.parametrize(
    ("message", "said"),
    [
        ('{"type": "sketch", "positions": []}', "'strokes' must be a list of strokes"),
        ('{"type": "sketch", "strokes": [[[1, "a"]]]}', "a stroke's point must be [x, y]"),
        ('{"type": "sketch", "strokes": [[[1, 1], [1, 1]]], "positions": ' + json.dumps([[0, 0]] * 17) + "}",
         "is squashed"),
        ("not json", "a message must be a JSON object"),
        ("[1, 2]", "a message must be a JSON object"),
        ("[" * 100_000, "a message must be a JSON object"),
        ('{"type": "dance"}', "unknown message type 'dance'"),
        ('{"id": 3, "type": "pose"}', "'positions' must list [x, y] for each of the 17 joints"),
        ('{"type": "pose", "positions": [[1, 2]]}', "for each of the 17 joints"),
        ('{"type": "pose", "positions": ' + json.dumps([["a", "b"]] * 17) + "}", "[x, y] pairs of numbers"),
        ('{"type": "pose", "positions": ' + json.dumps([[1, 2, 3]] * 17) + "}", "[x, y] pairs of numbers"),
        ('{"type": "pose", "positions": ' + json.dumps([[1e300, 1]] * 17) + "}", "pixels from the origin"),
        ('{"type": "pose", "positions": ' + json.dumps([[0, 0]] * 17) + "}", "is squashed"),
        ("x" * (MAX_MESSAGE_BYTES + 1), "1,000,000 bytes at most"),
    ],
)
def test_a_bad_message_gets_a_one_line_error_and_the_connection_lives_on(client, project, message, said):
    character = api.load_project(project)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(message)
        reply = socket.receive_json()
        assert reply["type"] == "error" and said in reply["message"] and "\n" not in reply["message"]
        socket.send_text(json.dumps({"id": 1, "type": "pose", "positions": _pose(character, "head", 0.1)}))
        assert socket.receive_json()["type"] == "mesh"


@pytest.mark.parametrize("query", ["", "?token=wrong"])
def test_the_live_connection_needs_the_token(client, query):
    with pytest.raises(WebSocketDisconnect) as closed, client.websocket_connect(f"/ws{query}") as socket:
        socket.receive_text()
    assert closed.value.code == 1008


def test_a_live_connection_from_another_origin_is_refused(client):
    with (
        pytest.raises(WebSocketDisconnect),
        client.websocket_connect(f"/ws?token={TOKEN}", headers={"Origin": "http://evil.example"}) as socket,
    ):
        socket.receive_text()


def test_a_bad_project_fails_before_the_server_starts(tmp_path):
    with pytest.raises(ProjectError, match="no project at"):
        create_app(tmp_path / "nothing", token=TOKEN)


@pytest.fixture
def editable(tmp_path, project):
    """A fresh copy of the project, edited by its own server."""
    import shutil

    folder = tmp_path / "hero"
    shutil.copytree(project, folder)
    return folder, TestClient(create_app(folder, token=TOKEN, origins=ORIGINS))


def _send(socket, message):
    socket.send_text(json.dumps(message))
    return socket.receive_json()


def test_region_edits_are_saved_at_once_and_undo_and_redo_survive_a_reload(editable):
    folder, client = editable
    character = api.load_project(folder)
    hand = character.skeleton.positions[character.skeleton.index("right_hand")].tolist()
    head = character.skeleton.positions[character.skeleton.index("head")]
    lasso = [(head + d).tolist() for d in ([-9, -9], [9, -9], [9, 9], [-9, 9])]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        up = _send(socket, {"id": 1, "type": "depth", "at": hand, "by": 1})
        assert (up["type"], up["edits"], up["undone"]) == ("regions", 1, 0)
        assert api.load_project(folder).depth.max() == 1  # saved before the reply
        fixed = _send(socket, {"type": "correct", "bone": "neck", "curve": lasso})
        saved = api.load_project(folder)
        assert fixed["edits"] == len(saved.edits) == 2
        assert fixed["vertex_bone"] == saved.binding.bone.tolist() != character.binding.bone.tolist()
        assert _send(socket, {"type": "undo"})["edits"] == 1
    # a new server on the saved project
    reloaded = TestClient(create_app(folder, token=TOKEN, origins=ORIGINS))
    with reloaded.websocket_connect(f"/ws?token={TOKEN}") as socket:
        again = _send(socket, {"type": "redo"})
    assert (again["edits"], again["undone"]) == (2, 0)
    np.testing.assert_array_equal(api.load_project(folder).binding.bone, saved.binding.bone)
    # The triangles come back in draw order: the raised region's triangles last.
    front = np.reshape(again["triangles"], (-1, 3))[-1]
    assert saved.depth[saved.binding.bone[front[0]]] == 1


def test_undo_and_redo_take_back_every_kind_of_edit_newest_first_and_survive_a_restart(editable):
    folder, client = editable
    character = api.load_project(folder)
    rest = character.skeleton.positions.tolist()
    bent = _pose(character, "right_elbow", 0.9)
    hand = rest[character.skeleton.index("right_hand")]
    joints = [{"name": n, "parent": p, "position": list(xy)} for n, p, xy in character.skeleton.joints()]
    joints[character.skeleton.index("head")]["position"][1] -= 6
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        assert _send(socket, {"type": "rig", "joints": joints})["type"] == "rigged"
        _send(socket, {"type": "depth", "at": hand, "by": 1})
        _send(socket, {"type": "set_key", "frame": 0, "positions": rest})
        keyed = _send(socket, {"type": "set_key", "frame": 8, "positions": bent})
        assert keyed["history"] == {"undo": 4, "redo": 0}
        one_key = _send(socket, {"type": "undo"})
        assert (one_key["kind"], [k["frame"] for k in one_key["keys"]["keys"]]) == ("keys", [0])
        assert json.loads((folder / "keys.json").read_text())["keys"][0]["frame"] == 0
        assert len(json.loads((folder / "keys.json").read_text())["keys"]) == 1  # saved as it happened
    # a new server: the history is on disk
    restarted = TestClient(create_app(folder, token=TOKEN, origins=ORIGINS))
    with restarted.websocket_connect(f"/ws?token={TOKEN}") as socket:
        assert _send(socket, {"type": "undo"})["keys"] is None and not (folder / "keys.json").exists()
        region = _send(socket, {"type": "undo"})
        assert (region["kind"], region["edits"], region["history"]) == ("regions", 0, {"undo": 1, "redo": 3})
        rig = _send(socket, {"type": "undo"})
        assert rig["kind"] == "rig"
        np.testing.assert_allclose(api.load_project(folder).skeleton.positions, character.skeleton.positions)
        assert _send(socket, {"type": "undo"})["message"] == "there are no edits to undo"
        for kind in ("rig", "regions", "keys", "keys"):
            redone = _send(socket, {"type": "redo"})
            assert redone.get("kind") == kind, redone
    final = api.load_project(folder)
    assert (len(final.edits), final.skeleton.positions[final.skeleton.index("head")][1]) == (
        1, character.skeleton.positions[character.skeleton.index("head")][1] - 6)
    assert [k["frame"] for k in json.loads((folder / "keys.json").read_text())["keys"]] == [0, 8]


def test_fine_tuning_is_applied_to_the_pose_and_keyed_with_it(editable):
    from toonmotion.deform.tuning import DragEdit
    from toonmotion.io.pose_json import load_keyframes

    folder, client = editable
    character = api.load_project(folder)
    rest = character.skeleton.positions.tolist()
    start = character.mesh.V[0].tolist()
    drag = {"kind": "drag", "from": [start], "to": [[start[0], start[1] - 12]]}
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        mesh = _send(socket, {"type": "pose", "positions": rest, "edits": [drag]})
        expected = api.pose_character(character, api.rotate_joint(character, "head", 0.0),
                                      edits=[DragEdit([start], [[start[0], start[1] - 12]])])
        np.testing.assert_allclose(decode_vertices(mesh["U"]), expected.deformation.U, atol=1e-3)
        keyed = _send(socket, {"type": "set_key", "frame": 0, "positions": rest, "edits": [drag]})
        assert keyed["keys"]["keys"][0]["edits"] == [drag]
        again = _send(socket, {"type": "set_key", "frame": 0, "positions": rest})  # keeps its edits
        assert again["keys"]["keys"][0]["edits"] == [drag]
        bad = _send(socket, {"type": "pose", "positions": rest, "edits": [{"kind": "smudge"}]})
        assert bad["type"] == "error" and "'edits'" in bad["message"]
    assert len(load_keyframes(folder / "keys.json", character.skeleton).keys[0].edits) == 1


def test_undo_refuses_a_history_the_project_no_longer_matches(editable):
    folder, client = editable
    rest = api.load_project(folder).skeleton.positions.tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "set_key", "frame": 0, "positions": rest})
        edited = (folder / "keys.json").read_text().replace('"fps": 12', '"fps": 24')
        (folder / "keys.json").write_text(edited)  # changed outside the editor
        reply = _send(socket, {"type": "undo"})
        assert reply["type"] == "error" and "no longer matches the project" in reply["message"]
        assert (folder / "keys.json").read_text() == edited  # nothing lost
        assert _send(socket, {"type": "undo"})["message"] == "there are no edits to undo"


@pytest.mark.parametrize(
    ("message", "said"),
    [
        ({"type": "depth", "at": [10, 10], "by": 5}, "'by' must be 1"),
        ({"type": "depth", "at": "here", "by": 1}, "'at' must be [x, y]"),
        ({"type": "depth", "at": [1e300, 1], "by": 1}, "over 10,000,000 px from the origin"),
        ({"type": "correct", "bone": 3, "curve": [[0, 0], [1, 0], [0, 1]]}, "'bone' must name"),
        ({"type": "correct", "bone": "neck", "curve": [[0, 0]]}, "3 to 10,000"),
        ({"type": "correct", "bone": "nobody", "curve": [[0, 0], [50, 0], [0, 50]]}, "nobody"),
        ({"type": "undo"}, "no edits to undo"),
        ({"type": "redo"}, "nothing to redo"),
    ],
)
def test_a_bad_region_edit_changes_nothing(editable, message, said):
    folder, client = editable
    before = (folder / "project.json").read_bytes()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply = _send(socket, message)
    assert reply["type"] == "error" and said in reply["message"], reply
    assert (folder / "project.json").read_bytes() == before


def test_the_overlaps_of_a_pose_name_the_regions_at_one_depth(client, project):
    character = api.load_project(project)
    raised = api.rotate_joint(character, "right_shoulder", 1.6).positions.tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        rest = _send(socket, {"type": "overlaps", "positions": character.skeleton.positions.tolist()})
        found = _send(socket, {"type": "overlaps", "positions": raised})
    assert rest == {"id": None, "type": "overlaps", "pairs": []}
    expected = api.same_depth_overlaps(
        character,
        [
            (
                0,
                api.pose_character(
                    character, api.rotate_joint(character, "right_shoulder", 1.6)
                ).deformation.U,
            )
        ],
    )
    assert [(p["a"], p["b"]) for p in found["pairs"]] == [(o.bone_a, o.bone_b) for o in expected] != []


def test_keys_are_saved_in_the_project_folder_and_frames_are_the_librarys_animation(editable):
    from toonmotion.io.pose_json import load_keyframes

    folder, client = editable
    character = api.load_project(folder)
    rest = character.skeleton.positions.tolist()
    bent = _pose(character, "right_elbow", 1.0)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        assert "no key-frames yet" in _send(socket, {"type": "frame", "frame": 3})["message"]
        _send(socket, {"type": "set_key", "frame": 0, "positions": rest})
        reply = _send(socket, {"type": "set_key", "frame": 8, "positions": bent})
        assert [k["frame"] for k in reply["keys"]["keys"]] == [0, 8]
        timeline = load_keyframes(folder / "keys.json", character.skeleton)  # saved before the reply
        assert [k.frame for k in timeline.keys] == [0, 8]
        middle = _send(socket, {"type": "frame", "frame": 4})
        beyond = _send(socket, {"type": "frame", "frame": 99})
        moved = _send(socket, {"type": "move_key", "frame": 8, "to": 10})
        assert [k["frame"] for k in moved["keys"]["keys"]] == [0, 10]
        clash = _send(socket, {"type": "move_key", "frame": 0, "to": 10})
        assert clash["type"] == "error" and "has a key already" in clash["message"]
        _send(socket, {"type": "delete_key", "frame": 10})
        last = _send(socket, {"type": "delete_key", "frame": 0})
    expected = api.animate_character(character, timeline)
    np.testing.assert_allclose(decode_vertices(middle["U"]), expected.meshes[4][1], atol=1e-3)
    np.testing.assert_allclose(middle["positions"], expected.motion.positions[4], atol=1e-9)
    assert beyond["frame"] == 8  # clamped to the keys' span
    assert last == {"id": None, "type": "keys", "keys": None, "history": {"undo": 5, "redo": 0},
                    "says": "the key at frame 0 deleted"}
    assert not (folder / "keys.json").exists()


def test_the_editor_opens_with_the_projects_keys(editable):
    folder, client = editable
    character = api.load_project(folder)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "set_key", "frame": 5, "positions": character.skeleton.positions.tolist()})
    again = TestClient(create_app(folder, token=TOKEN, origins=ORIGINS))
    data = again.get("/api/project", headers={"X-Toonmotion-Token": TOKEN}).json()
    assert [k["frame"] for k in data["keys"]["keys"]] == [5]


@pytest.mark.parametrize(
    ("message", "said"),
    [
        ({"type": "set_key", "frame": -1, "positions": []}, "a frame number"),
        ({"type": "set_key", "frame": 1.5, "positions": []}, "a frame number"),
        ({"type": "set_key", "frame": True, "positions": []}, "a frame number"),
        ({"type": "set_key", "frame": 200_000, "positions": None}, "'positions' must list"),
        ({"type": "delete_key", "frame": 3}, "no key-frames yet"),
        ({"type": "move_key", "frame": 3, "to": 4}, "no key-frames yet"),
    ],
)
def test_a_bad_key_edit_changes_nothing(editable, message, said):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply = _send(socket, message)
    assert reply["type"] == "error" and said in reply["message"], reply
    assert not (folder / "keys.json").exists()


def test_a_key_beyond_the_frames_limit_is_refused(editable):
    folder, client = editable
    rest = api.load_project(folder).skeleton.positions.tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply = _send(socket, {"type": "set_key", "frame": 100_000, "positions": rest})
    assert reply["type"] == "error" and "over the limit frames=100,000" in reply["message"]
    assert not (folder / "keys.json").exists()


def _keyed(folder, socket):
    character = api.load_project(folder)
    _send(socket, {"type": "set_key", "frame": 0, "positions": character.skeleton.positions.tolist()})
    _send(socket, {"type": "set_key", "frame": 6, "positions": _pose(character, "right_elbow", 1.0)})


def test_an_export_reports_progress_and_writes_the_animation_into_the_project(editable):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        socket.send_text(json.dumps({"id": 9, "type": "export", "format": "gif", "name": "wave"}))
        said = [socket.receive_json()]
        while said[-1]["type"] == "progress":
            said.append(socket.receive_json())
    progress, done = said[:-1], said[-1]
    assert [(p["id"], p["index"], p["count"]) for p in progress] == [(9, i, 7) for i in range(1, 8)]
    assert done == {
        "id": 9,
        "type": "exported",
        "file": "exports/wave.gif",
        "files": ["exports/wave.gif"],
        "frames": 7,
        "size": done["size"],
    }
    with Image.open(folder / "exports" / "wave.gif") as gif:
        assert (gif.n_frames, list(gif.size)) == (7, done["size"])
    download = _get(client, "/api/exports/wave.gif")
    assert download.status_code == 200 and download.content == (folder / "exports" / "wave.gif").read_bytes()


@pytest.mark.parametrize(("kind", "files", "media"), [
    ("glb", ["wave.glb"], ["model/gltf-binary"]),
    ("spine", ["wave.spine.json", "wave.spine.atlas", "wave.spine.png"],
     ["application/json", "text/plain", "image/png"]),
    ("sheet", ["wave.sheet.json", "wave.sheet.png"], ["application/json", "image/png"]),
    ("webp", ["wave.webp"], ["image/webp"]),
])
def test_rigs_sheets_and_transparent_pictures_export_and_download_every_file(editable, kind, files, media):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        socket.send_text(json.dumps({"type": "export", "format": kind, "name": "wave"}))
        done = socket.receive_json()
        while done["type"] == "progress":
            done = socket.receive_json()
    assert done["type"] == "exported" and done["files"] == [f"exports/{f}" for f in files], done
    assert done["frames"] == 7 and (done["size"] is None) == (kind in ("glb", "spine"))
    for name, kind_of in zip(files, media, strict=True):
        download = _get(client, f"/api/exports/{name}")
        assert download.status_code == 200 and download.headers["content-type"].startswith(kind_of)
        assert download.content == (folder / "exports" / name).read_bytes()
    assert _get(client, "/api/exports/wave.spine.exe").status_code == 404
    assert _get(client, "/api/exports/..%2Fkeys.json").status_code == 404


def test_an_export_takes_the_size_background_and_overlays_the_cli_takes(editable):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        socket.send_text(json.dumps({"type": "export", "format": "png", "name": "framed", "size": [64, 80],
                                     "background": [0, 128, 255], "overlays": ["skeleton"]}))
        done = socket.receive_json()
        while done["type"] == "progress":
            done = socket.receive_json()
    assert done["size"] == [64, 80] and done["file"] == "exports/framed", done
    frames = sorted((folder / "exports" / "framed").glob("*.png"))
    assert len(frames) == 7
    first = np.asarray(Image.open(frames[0]).convert("RGBA"))
    assert first.shape == (80, 64, 4)
    assert tuple(first[0, 0]) == (0, 128, 255, 255)  # the background, opaque


@pytest.mark.parametrize(
    ("message", "said"),
    [
        ({"format": "gif", "name": "ok", "size": [0, 10]}, "'size' must be [width, height]"),
        ({"format": "gif", "name": "ok", "size": [20_000, 10]}, "from 1 to 16,384"),
        ({"format": "gif", "name": "ok", "size": "big"}, "'size' must be"),
        ({"format": "gif", "name": "ok", "background": [0, 0, 300]}, "'background' must be"),
        ({"format": "gif", "name": "ok", "background": "red"}, "'background' must be"),
        ({"format": "gif", "name": "ok", "overlays": ["x-ray"]}, "unknown overlay 'x-ray'"),
        ({"format": "gif", "name": "ok", "overlays": "skeleton"}, "'overlays' must list"),
        ({"format": "gif", "name": "../../evil"}, "'name' must be"),
        ({"format": "gif", "name": ""}, "'name' must be"),
        ({"format": "gif", "name": ".hidden"}, "'name' must be"),
        ({"format": "gif", "name": "a/b"}, "'name' must be"),
        ({"format": "gif", "name": "x" * 65}, "'name' must be"),
        ({"format": "gif", "name": 7}, "'name' must be"),
        ({"format": "exe", "name": "ok"}, "'format' must be gif, mp4, png"),
        ({"format": "gif", "name": "ok", "keys": False}, "no key-frames yet"),
        ({"format": "glb", "name": "ok", "overlays": ["mesh"]}, "overlays are drawn on GIF, MP4 and PNG"),
    ],
)
def test_a_bad_export_writes_nothing(editable, message, said):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        if message.pop("keys", True):
            _keyed(folder, socket)
        reply = _send(socket, {"type": "export", **message})
    assert reply["type"] == "error" and said in reply["message"], reply
    assert not (folder / "exports").exists() or list((folder / "exports").iterdir()) == []


@pytest.mark.parametrize(
    "name", ["..%2Fproject.json", "missing.gif", "wave.json", "wave", "%2e%2e%2fkeys.json"]
)
def test_only_an_export_can_be_downloaded(client, name):
    assert _get(client, f"/api/exports/{name}").status_code == 404


def test_a_pose_with_an_acceleration_is_the_single_frame_filters(client, project):
    character = api.load_project(project)
    rest = character.skeleton.positions.tolist()
    fixed = ["right_foot", "left_foot"]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply = _send(socket, {"type": "pose", "positions": rest, "accel": [0, -30], "fixed": fixed})
        bad = _send(socket, {"type": "pose", "positions": rest, "accel": [0, -30], "fixed": "feet"})
        none = _send(socket, {"type": "pose", "positions": rest, "accel": [0, -30], "fixed": []})
    expected = api.pose_character(
        character, api.rotate_joint(character, "head", 0.0), accel=(0, -30), fixed=fixed
    )
    np.testing.assert_allclose(reply["positions"], expected.pose.positions, atol=1e-9)
    np.testing.assert_allclose(decode_vertices(reply["U"]), expected.deformation.U, atol=1e-3)
    feet = [character.skeleton.index(f) for f in fixed]
    np.testing.assert_array_equal(np.asarray(reply["positions"])[feet], character.skeleton.positions[feet])
    assert bad["type"] == "error" and "'fixed' must list" in bad["message"]
    assert none["type"] == "error" and "fix at least one joint" in none["message"]


def test_frames_and_exports_can_be_exaggerated(editable):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        plain = _send(socket, {"type": "frame", "frame": 5})
        lively = _send(socket, {"type": "frame", "frame": 5, "strength": 2.0, "sigma": 2.0})
        bad = _send(socket, {"type": "frame", "frame": 5, "strength": "lots"})
    from toonmotion.io.pose_json import load_keyframes

    timeline = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    expected = api.animate_character(
        api.load_project(folder), timeline, exaggeration=api.FilterSettings(strength=2.0, sigma=2.0)
    )
    np.testing.assert_allclose(lively["positions"], expected.motion.positions[5], atol=1e-9)
    assert np.abs(np.subtract(lively["positions"], plain["positions"])).max() > 0.5
    assert bad["type"] == "error" and "strength" in bad["message"]


def _joints(character):
    s = character.skeleton
    return [
        {"name": n, "parent": None if p < 0 else s.names[p], "position": s.positions[i].tolist()}
        for i, (n, p) in enumerate(zip(s.names, s.parents, strict=True))
    ]


def test_rig_again_with_an_edited_skeleton_replays_the_region_edits(editable):
    folder, client = editable
    character = api.load_project(folder)
    joints = _joints(character)
    joints[character.skeleton.index("head")]["position"][1] -= 6  # the head joint a little higher
    joints.append({"name": "hat", "parent": "head", "position": [joints[4]["position"][0], 8.0]})
    hand = character.skeleton.positions[character.skeleton.index("right_hand")].tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "depth", "at": hand, "by": 1})
        reply = _send(socket, {"type": "rig", "joints": joints})
        data = _get(client, "/api/project").json()
    saved = api.load_project(folder)
    assert reply == {"id": None, "type": "rigged", "skipped": 0, "says": "the drawing rigged again"}
    assert "hat" in saved.skeleton.names and len(saved.edits) == 1 and saved.depth.max() == 1
    assert [j["name"] for j in data["joints"]] == list(saved.skeleton.names)  # the server serves the new rig
    assert data["suggestions"] and data["curve_skeleton"]


@pytest.mark.parametrize(
    ("joints", "said"),
    [
        ([], "'joints' must list"),
        ([{"name": 1, "parent": None, "position": [1, 1]}], "joint 1 needs a 'name'"),
        ([{"name": "a", "parent": "nobody", "position": [50, 50]}], "nobody"),
        ([{"name": "a", "parent": None, "position": "here"}], "position must be [x, y]"),
        ([{"name": "a", "parent": None, "position": [5000, 5000]}], "px from the figure"),
    ],
)
def test_a_bad_skeleton_changes_nothing(editable, joints, said):
    folder, client = editable
    before = (folder / "project.json").read_bytes()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply = _send(socket, {"type": "rig", "joints": joints})
    assert reply["type"] == "error" and said in reply["message"], reply
    assert (folder / "project.json").read_bytes() == before


def test_while_there_are_keys_a_rig_keeps_the_joint_names(editable):
    folder, client = editable
    character = api.load_project(folder)
    joints = _joints(character)
    joints[-1]["name"] = "left_toe"
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        reply = _send(socket, {"type": "rig", "joints": joints})
    assert reply["type"] == "error" and "keep their names" in reply["message"]



def test_joints_moved_in_a_rig_carry_the_keys_with_them_and_undo_takes_both_back(editable):
    from toonmotion.io.pose_json import load_keyframes

    folder, client = editable
    character = api.load_project(folder)
    skeleton = character.skeleton
    joints = _joints(character)
    head, hand, elbow = (skeleton.index(n) for n in ("head", "right_hand", "right_elbow"))
    joints[head]["position"][1] -= 6
    forearm = skeleton.positions[hand] - skeleton.positions[elbow]
    joints[hand]["position"] = (skeleton.positions[hand] + 4 * forearm / np.linalg.norm(forearm)).tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)  # the rest pose at 0, the forearm turned 1 radian at 6
        keys_before = (folder / "keys.json").read_text()
        assert _send(socket, {"type": "rig", "joints": joints})["type"] == "rigged"
        moved = api.load_project(folder).skeleton
        rest, turned = (k.pose.positions for k in load_keyframes(folder / "keys.json", moved).keys)
        # A key of the rest pose is the new rest pose; a joint not moved keeps its keyed place.
        np.testing.assert_allclose(rest, moved.positions, atol=1e-9)
        bent = np.array(_pose(character, "right_elbow", 1.0))
        still = [j for j in range(len(skeleton)) if j not in (head, hand)]
        np.testing.assert_array_equal(turned[still], bent[still])
        # The hand, moved 4 px along its forearm, is 4 px farther along the turned forearm.
        before, after = bent[hand] - bent[elbow], turned[hand] - turned[elbow]
        assert np.linalg.norm(after) == pytest.approx(np.linalg.norm(before) + 4, abs=1e-6)
        assert before[0] * after[1] - before[1] * after[0] == pytest.approx(0.0, abs=1e-6)
        undone = _send(socket, {"type": "undo"})
        assert undone["kind"] == "rig" and (folder / "keys.json").read_text() == keys_before
        np.testing.assert_array_equal(api.load_project(folder).skeleton.positions, skeleton.positions)
        assert _send(socket, {"type": "redo"})["kind"] == "rig"
    again = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton).keys[0].pose.positions
    np.testing.assert_allclose(again, moved.positions, atol=1e-9)

def test_timing_changes_the_keys_rate_and_easing(editable):
    from toonmotion.io.pose_json import load_keyframes

    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        reply = _send(socket, {"type": "timing", "fps": 24, "ease": "linear"})
        bad_fps = _send(socket, {"type": "timing", "fps": 0})
        bad_ease = _send(socket, {"type": "timing", "ease": "bouncy"})
    assert (reply["keys"]["fps"], reply["keys"]["ease"]) == (24.0, "linear")
    saved = load_keyframes(folder / "keys.json", api.load_project(folder).skeleton)
    assert (saved.fps, saved.ease, [k.frame for k in saved.keys]) == (24.0, "linear", [0, 6])
    assert bad_fps["type"] == "error" and "fps" in bad_fps["message"]
    assert bad_ease["type"] == "error" and "ease must be one of" in bad_ease["message"]


def test_the_regions_name_the_vertices_that_fell_back(client, project):
    character = api.load_project(project)
    data = _get(client, "/api/project").json()
    assert data["fallback"] == np.flatnonzero(character.binding.fallback).tolist()


def test_an_exaggerated_export_is_the_filtered_animation(editable):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _keyed(folder, socket)
        for message in ({"name": "plain"}, {"name": "lively", "strength": 3.0, "sigma": 2.0}):
            reply = _send(socket, {"type": "export", "format": "png", **message})
            while reply["type"] == "progress":
                reply = socket.receive_json()
            assert reply["type"] == "exported", reply
    plain = sorted((folder / "exports" / "plain").glob("*.png"))
    lively = sorted((folder / "exports" / "lively").glob("*.png"))
    assert len(plain) == len(lively) == 7
    differ = [
        not np.array_equal(np.asarray(Image.open(a)), np.asarray(Image.open(b)))
        for a, b in zip(plain, lively, strict=True)
    ]
    assert any(differ)


def _walking_gif():
    """Four frames of the sample walking right on white, as GIF bytes."""
    from toonmotion.samples import sample_character_on

    picture = sample_character_on("white", scale=0.5)[0]
    frames = [Image.fromarray(np.roll(picture, 2 * t, axis=1)) for t in range(4)]
    buffer = io.BytesIO()
    frames[0].save(buffer, format="GIF", save_all=True, append_images=frames[1:], duration=80)
    return buffer.getvalue()


def test_footage_is_tracked_saved_and_retargeted(editable):
    from toonmotion.io.motion_json import load_motion

    folder, client = editable
    sent = client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif())
    assert sent.status_code == 200, sent.text
    footage = sent.json()
    assert (footage["frames"], footage["width"], footage["height"]) == (4, 210, 300)
    assert footage["joints"] and all(len(j["size"]) == 2 for j in footage["joints"])
    assert footage["border"] == [255, 255, 255]  # drawn on white: the figure is told from it
    frame = Image.open(io.BytesIO(_get(client, "/api/footage/3.png").content))
    assert frame.size == (210, 300)
    # The character's own joints, placed on the figure (here it is the figure, at its size), so
    # that the motion retargets by name.
    joints = [{**j, "size": [16, 16]} for j in _joints(api.load_project(folder))]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(json.dumps({"id": 4, "type": "track", "joints": joints}))
        reply = socket.receive_json()
        while reply["type"] == "progress":
            reply = socket.receive_json()
        assert reply["type"] == "tracked", reply
        # 16 px rectangles on a figure whose limbs ask for 48: said with the tracking.
        small = "the rectangles are small for this figure (median 16 px,"
        assert [note[:len(small)] for note in reply["notes"]] == [small]
        retargeted = _send(socket, {"type": "retarget"})
        shown = _send(socket, {"type": "frame", "frame": 3, "source": "capture"})
    motion = load_motion(folder / "motions" / "captured.json")  # saved in the project
    assert motion.positions.shape == (4, len(joints), 2)
    moved = np.asarray(reply["positions"])[-1] - np.asarray(reply["positions"])[0]
    assert np.median(moved[:, 0]) == pytest.approx(6, abs=1)  # the figure walked 6 px right
    assert retargeted["type"] == "retargeted", retargeted
    assert (retargeted["first"], retargeted["last"]) == (0, 3)
    assert shown["type"] == "frame"
    assert len(decode_vertices(shown["U"])) == len(api.load_project(folder).mesh.V)


@pytest.mark.parametrize(
    ("url", "body", "status", "said"),
    [
        ("/api/footage?suffix=exe", b"x", 400, "send footage as"),
        ("/api/footage", b"x", 400, "suffix"),
        ("/api/footage?suffix=gif", b"not a gif at all", 400, "cannot read"),
        ("/api/footage?suffix=mp4", b"\x00" * 2000, 400, "could not be decoded as a video"),
        ("/api/footage?suffix=mp4&name=holiday.mp4", b"\x00" * 2000, 400, "cannot read holiday.mp4:"),
    ],
)
def test_bad_footage_is_refused_in_one_line(editable, url, body, status, said):
    folder, client = editable
    reply = client.put(url, content=body, headers={"X-Toonmotion-Token": TOKEN})
    assert reply.status_code == status and said in reply.json()["error"], reply.text
    assert str(folder) not in reply.json()["error"]  # the file sent, not where the server keeps it
    assert not list((folder / "footage").glob("*")) if (folder / "footage").exists() else True


def test_footage_over_the_upload_limit_is_refused_as_it_arrives(editable):
    from toonmotion import limits

    folder, client = editable
    with limits.using(upload_bytes=1000):
        reply = client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif())
    assert reply.status_code == 413 and "upload_bytes=1,000" in reply.json()["error"]
    assert not (folder / "footage").exists() or list((folder / "footage").iterdir()) == []


def test_a_folder_of_frames_is_sent_one_by_one_and_read_in_order(editable):
    from toonmotion.samples import sample_character_on

    folder, client = editable
    picture = sample_character_on("white", scale=0.5)[0]
    url = "/api/footage/frames/{}?count=3&suffix=png&token=" + TOKEN
    replies = [client.put(url.format(i), content=_png(np.roll(picture, 3 * i, axis=1))) for i in range(3)]
    assert [r.status_code for r in replies] == [200, 200, 200]
    assert replies[0].json() == {"received": 1, "count": 3}
    footage = replies[-1].json()
    assert (footage["frames"], footage["width"], footage["height"]) == (3, 210, 300)
    third = np.asarray(Image.open(io.BytesIO(_get(client, "/api/footage/2.png").content)).convert("RGB"))
    np.testing.assert_array_equal(third, np.roll(picture, 6, axis=1)[..., :3])  # in the order sent
    again = client.put(url.format(0).replace("count=3", "count=1"), content=_png(picture))
    assert again.json()["frames"] == 1  # a new folder replaces the last one


@pytest.mark.parametrize(
    ("url", "said"),
    [
        ("/api/footage/frames/0?count=2&suffix=exe", "send frames as png"),
        ("/api/footage/frames/2?count=2&suffix=png", "numbered 0 to count - 1"),
        ("/api/footage/frames/0?count=999999&suffix=png", "footage_frames"),
        ("/api/footage/frames/-1?count=2&suffix=png", "numbered"),
    ],
)
def test_bad_frames_are_refused_in_one_line(editable, url, said):
    folder, client = editable
    reply = client.put(url, content=b"x", headers={"X-Toonmotion-Token": TOKEN})
    assert reply.status_code == 400 and said in reply.json()["error"], reply.text


def test_a_tracking_can_be_cancelled_and_the_earlier_one_is_kept(editable, monkeypatch):
    folder, client = editable
    assert client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif()).status_code == 200
    joints = [{**j, "size": [16, 16]} for j in _joints(api.load_project(folder))]
    saved = folder / "motions" / "captured.json"
    stopped: list[str] = []
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        first = _send(socket, {"type": "track", "joints": joints})
        while first["type"] == "progress":
            first = socket.receive_json()
        assert first["type"] == "tracked", first
        before = saved.read_bytes()
        monkeypatch.setattr(api, "track_footage", slow_work(stopped))
        socket.send_text(json.dumps({"id": 7, "type": "track", "joints": joints}))
        assert socket.receive_json() == {"id": 7, "type": "progress", "index": 0, "count": 3000}
        # A message sent while it runs is answered after it; a cancel for another id is not its own.
        socket.send_text(json.dumps({"id": 8, "type": "retarget"}))
        socket.send_text(json.dumps({"id": 6, "type": "cancel"}))
        socket.send_text(json.dumps({"id": 7, "type": "cancel"}))
        replies = [socket.receive_json()]
        while replies[-1]["type"] == "progress":
            replies.append(socket.receive_json())
        after = socket.receive_json()
        late = _send(socket, {"id": 9, "type": "retarget"})
        socket.send_text(json.dumps({"id": 7, "type": "cancel"}))  # after its reply: let be
        last = _send(socket, {"id": 10, "type": "retarget"})
    cancelled = replies[-1]
    assert cancelled == {"id": 7, "type": "error", "cancelled": True,
                         "message": "cancelled: did not track the footage; nothing saved before was changed"}
    assert stopped == ["Cancelled"]
    assert saved.read_bytes() == before  # the earlier tracking is as it was
    assert (after["id"], after["type"]) == (8, "retargeted")  # the earlier tracking's
    assert (late["id"], late["type"], last["id"], last["type"]) == (9, "retargeted", 10, "retargeted")


def test_leaving_the_page_stops_a_slow_request(editable, monkeypatch):
    folder, client = editable
    assert client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif()).status_code == 200
    joints = [{**j, "size": [16, 16]} for j in _joints(api.load_project(folder))]
    stopped: list[str] = []
    monkeypatch.setattr(api, "track_footage", slow_work(stopped))
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(json.dumps({"id": 3, "type": "track", "joints": joints}))
        assert socket.receive_json()["type"] == "progress"
    deadline = time.monotonic() + 10
    while not stopped and time.monotonic() < deadline:
        time.sleep(0.02)
    assert stopped == ["Cancelled"]
    assert not (folder / "motions" / "captured.json").exists()


def test_a_binary_frame_ends_the_live_session_with_a_close_that_says_why(client, caplog):
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_bytes(b"\x00\x01")
        with pytest.raises(WebSocketDisconnect) as closed:
            socket.receive_json()
    assert closed.value.code == 1003 and "text messages" in closed.value.reason
    assert "the live connection broke: KeyError" in caplog.text


def test_tracking_and_retargeting_need_their_inputs(client):
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        joint = {"name": "a", "position": [1, 2], "size": [8, 8]}
        track = _send(socket, {"type": "track", "joints": [joint]})
        retarget = _send(socket, {"type": "retarget"})
        frame = _send(socket, {"type": "frame", "frame": 0, "source": "capture"})
    assert "no footage yet" in track["message"]
    assert "no tracked motion yet" in retarget["message"]
    assert "nothing is retargeted yet" in frame["message"]


def test_a_correction_tracks_again_from_its_frame_and_keeps_the_frames_before(editable):
    folder, client = editable
    assert client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif()).status_code == 200
    joints = [{**j, "size": [16, 16]} for j in _joints(api.load_project(folder))]

    def track(socket, message):
        socket.send_text(json.dumps(message))
        reply = socket.receive_json()
        while reply["type"] == "progress":
            reply = socket.receive_json()
        return reply

    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        first = track(socket, {"type": "track", "joints": joints})
        head = first["names"].index("head")
        x, y = first["positions"][2][head]
        again = track(socket, {"type": "track", "joints": joints, "at": 2, "set": {"head": [x + 3, y]}})
        bad = track(socket, {"type": "track", "joints": joints, "at": 2, "set": {}})
    assert again["type"] == "tracked", again
    np.testing.assert_allclose(again["positions"][:2], first["positions"][:2])  # kept before the correction
    assert again["positions"][2][head] == pytest.approx([x + 3, y])
    assert bad["type"] == "error" and "'set' must give" in bad["message"]


def test_tracking_holds_joints_to_the_figure_chooses_paths_and_halves_large_footage_unless_told_not_to(
        editable, monkeypatch):
    folder, client = editable
    assert client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=_walking_gif()).status_code == 200
    joints = [{**j, "size": [16, 16]} for j in _joints(api.load_project(folder))]
    held, colours, original = [], [], api.track_footage

    def tracking(*args, **kwargs):
        settings = kwargs["settings"]
        held.append((settings.figure, settings.best_path, settings.both_ways, settings.working_side))
        colours.append(kwargs["background"])
        return original(*args, **kwargs)

    monkeypatch.setattr(api, "track_footage", tracking)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        replies = []
        for how in ({}, {"free": True}, {"frame_by_frame": True},
                    {"both_ways": True, "background": [250, 240, 220]}, {"full_resolution": True},
                    {"free": "yes"}, {"frame_by_frame": 1}, {"both_ways": True, "frame_by_frame": True},
                    {"background": "white"}, {"full_resolution": "no"}):
            socket.send_text(json.dumps({"type": "track", "joints": joints, **how}))
            reply = socket.receive_json()
            while reply["type"] == "progress":
                reply = socket.receive_json()
            replies.append(reply)
    assert [r["type"] for r in replies] == ["tracked"] * 5 + ["error"] * 5
    assert held == [(True, True, False, 1000), (False, True, False, 1000), (True, False, False, 1000),
                    (True, True, True, 1000), (True, True, False, None)]
    assert "'free' must be true or false, got 'yes'" in replies[5]["message"]
    assert "'frame_by_frame' must be true or false, got 1" in replies[6]["message"]
    assert "both_ways needs best_path" in replies[7]["message"]
    assert "'background' must be null or [r, g, b]" in replies[8]["message"]
    assert "'full_resolution' must be true or false, got 'no'" in replies[9]["message"]
    assert colours == [None, None, None, (250, 240, 220), None]


def test_joints_are_suggested_again_on_the_colour_the_footage_is_drawn_on(editable):
    """Footage drawn on white inside a black frame: the border says the paper is black, and the
    joints suggested when it is sent run round the frame. Told it is drawn on white, the page gets
    joints on the character."""
    from toonmotion.samples import sample_character_on

    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        socket.send_text(json.dumps({"type": "suggest", "background": [255, 255, 255]}))
        early = socket.receive_json()
    assert early["type"] == "error" and "there is no footage yet" in early["message"]
    picture = sample_character_on("white", scale=0.5)[0].copy()
    figure = np.argwhere(picture.min(axis=2) < 200)  # the character's pixels, (row, column)
    picture[:3] = picture[-3:] = picture[:, :3] = picture[:, -3:] = 0
    buffer = io.BytesIO()
    frames = [Image.fromarray(np.roll(picture, t, axis=1)) for t in range(3)]
    frames[0].save(buffer, format="GIF", save_all=True, append_images=frames[1:], duration=80)
    sent = client.put(f"/api/footage?suffix=gif&token={TOKEN}", content=buffer.getvalue())
    assert sent.status_code == 200, sent.text
    (top, left), (bottom, right) = figure.min(axis=0), figure.max(axis=0)

    def on_character(joints):
        xy = np.array([j["position"] for j in joints])
        return bool(((xy >= (left, top)) & (xy <= (right, bottom))).all())

    assert not on_character(sent.json()["joints"]) and sent.json()["border"] == [0, 0, 0]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        replies = []
        for background in ([255, 255, 255], None, "white"):
            socket.send_text(json.dumps({"type": "suggest", "background": background}))
            replies.append(socket.receive_json())
    white, border, bad = replies
    assert white["type"] == "suggested" and len(white["joints"]) > 2 and on_character(white["joints"])
    assert all(set(j) == {"name", "parent", "position", "size"} for j in white["joints"])
    assert border["joints"] == sent.json()["joints"]  # null: the border's colour, as when sent
    assert bad["type"] == "error" and "'background' must be null or [r, g, b]" in bad["message"]


def _png(array) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(array).save(buffer, format="PNG")
    return buffer.getvalue()


def _opened(socket, message):
    socket.send_text(json.dumps(message))
    reply = socket.receive_json()
    steps = 0
    while reply["type"] == "progress":
        steps += 1
        reply = socket.receive_json()
    return reply, steps


def test_a_new_drawing_is_rigged_into_the_project_and_undo_brings_the_old_one_back(editable, drawings_root):
    folder, client = editable
    old = api.load_project(folder)
    drawing = np.asarray(Image.open(drawings_root / "char4" / "texture.png").convert("RGB"))
    mask = np.asarray(Image.open(drawings_root / "char4" / "mask.png").convert("L"))
    headers = {"X-Toonmotion-Token": TOKEN}
    sent = client.put("/api/uploads/drawing", content=_png(drawing), headers=headers)
    assert sent.json() == {"width": drawing.shape[1], "height": drawing.shape[0]}
    assert client.put("/api/uploads/mask", content=_png(mask), headers=headers).status_code == 200
    skeleton = client.put("/api/uploads/skeleton?format=yaml", headers=headers,
                          content=(drawings_root / "char4" / "char_cfg.yaml").read_bytes()).json()
    assert [j["name"] for j in skeleton["joints"]][:2] == ["root", "hip"]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        refused, _ = _opened(socket, {"type": "open_drawing", "skeleton": "keep", "mask": True})
        # The sample's joints: off the new figure, or a bone wholly outside it (the rig says first).
        assert "lie off the new figure" in refused["message"] or \
            "the kept skeleton does not fit the new figure" in refused["message"], refused
        opened, steps = _opened(socket, {"type": "open_drawing", "skeleton": "new", "mask": True})
        assert opened["type"] == "opened" and steps > 0, opened
        new = api.load_project(folder)  # saved
        assert new.size == (drawing.shape[1], drawing.shape[0])
        np.testing.assert_array_equal(new.mask, mask >= 128)
        assert _get(client, "/api/project").json()["width"] == drawing.shape[1]
        back = _send(socket, {"type": "undo"})
        assert back["kind"] == "drawing"
        again = api.load_project(folder)
        assert again.size == old.size
        np.testing.assert_array_equal(again.texture, old.texture)
        assert _send(socket, {"type": "redo"})["kind"] == "drawing"
        assert api.load_project(folder).size == new.size


@pytest.mark.parametrize(
    ("url", "body", "status", "said"),
    [
        ("/api/uploads/drawing", b"not an image", 400, "image"),
        ("/api/uploads/drawing?name=me.png", b"not an image", 400, "cannot read me.png:"),
        ("/api/uploads/passwd", b"x", 404, "uploads are drawing, mask, skeleton"),
        ("/api/uploads/..%2Fproject.json", b"x", 404, ""),
        ("/api/uploads/skeleton", b"x: 1", 400, "format"),
        ("/api/uploads/skeleton?format=yaml", b"- [unclosed", 400, "skeleton"),
        ("/api/uploads/skeleton?format=json", b"{}", 400, "skeleton"),
    ],
)
def test_bad_uploads_are_refused_in_one_line_and_change_nothing(editable, url, body, status, said):
    folder, client = editable
    before = (folder / "project.json").read_bytes()
    reply = client.put(url, content=body, headers={"X-Toonmotion-Token": TOKEN})
    assert reply.status_code == status and said in reply.json()["error"], reply.text
    assert "\n" not in reply.json()["error"] and str(folder) not in reply.json()["error"]
    assert (folder / "project.json").read_bytes() == before
    assert not (folder / "uploads").exists() or list((folder / "uploads").iterdir()) == []



def test_an_upload_over_the_pixel_limit_names_the_file_sent_and_how_the_editor_raises_it(editable):
    from toonmotion import limits

    folder, client = editable
    with limits.using(image_pixels=100):
        picture = _png(np.zeros((20, 20, 3), np.uint8))
        reply = client.put(f"/api/uploads/drawing?name=big.png&token={TOKEN}", content=picture)
    said = reply.json()["error"]
    assert reply.status_code == 400 and said.startswith("big.png is 20x20"), said
    assert "toonmotion --limit image_pixels=N edit" in said and "--max-pixels" not in said

def test_opening_a_drawing_needs_one_sent_first(editable):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply, _ = _opened(socket, {"type": "open_drawing", "skeleton": "new"})
    assert "no drawing to open yet" in reply["message"]


def test_the_editor_prepares_its_compiled_deformer_before_the_first_drag(project):
    editing = Editing.open(project)
    editing.prepare_deformer()
    prepared = editing._deformer
    assert prepared is not None and prepared.settings.compiled
    assert editing.deformer is prepared


def test_a_deformer_prepared_for_a_character_replaced_meanwhile_is_not_kept(project, monkeypatch):
    editing = Editing.open(project)
    build = editing_module._deformer_for

    def rigged_again_meanwhile(character):
        editing.character = api.load_project(project)
        return build(character)

    monkeypatch.setattr(editing_module, "_deformer_for", rigged_again_meanwhile)
    editing.prepare_deformer()
    assert editing._deformer is None


def test_a_deformer_that_cannot_be_prepared_is_left_to_the_first_drag(project, monkeypatch):
    editing = Editing.open(project)

    def broken(character):
        raise MeshError("the mesh is degenerate")

    monkeypatch.setattr(editing_module, "_deformer_for", broken)
    editing.prepare_deformer()  # nothing raised, nothing printed: the drag reports it
    assert editing._deformer is None
    with pytest.raises(MeshError, match="degenerate"):
        editing.deformer  # noqa: B018


# Links and hosts (issue 44): nothing is read, written or deleted through a symbolic link under
# the project, and a request must name the editor's own host.


def _outside(tmp_path):
    """A folder outside the project with a file in it, and the file's text."""
    secret = tmp_path / "elsewhere"
    secret.mkdir()
    (secret / "private.txt").write_text("not the project's")
    return secret


def test_an_export_that_is_a_link_is_not_served(editable, tmp_path):
    folder, client = editable
    secret = _outside(tmp_path)
    (folder / "exports").mkdir(exist_ok=True)
    (folder / "exports" / "leak.gif").symlink_to(secret / "private.txt")
    reply = _get(client, "/api/exports/leak.gif")
    assert reply.status_code == 403 and "not the project's" not in reply.text
    assert reply.json()["error"].startswith("exports/leak.gif in the project is a symbolic link")


def test_a_folder_of_frames_that_is_a_link_is_not_emptied(editable, tmp_path):
    folder, client = editable
    secret = _outside(tmp_path)
    (folder / "footage").mkdir(exist_ok=True)
    (folder / "footage" / "frames").symlink_to(secret, target_is_directory=True)
    reply = client.put(f"/api/footage/frames/0?count=2&suffix=png&token={TOKEN}",
                       content=_png(np.zeros((8, 8, 3), np.uint8)))
    assert reply.status_code == 403
    assert "footage/frames in the project is a symbolic link" in reply.json()["error"]
    assert sorted(p.name for p in secret.iterdir()) == ["private.txt"]  # nothing deleted or written there


@pytest.mark.parametrize("link", ["uploads/skeleton.json", "uploads"])
def test_an_upload_is_not_written_through_a_link(editable, tmp_path, link):
    folder, client = editable
    secret = _outside(tmp_path)
    target = secret / "private.txt" if link.endswith(".json") else secret
    (folder / link).parent.mkdir(exist_ok=True)
    (folder / link).symlink_to(target, target_is_directory=target.is_dir())
    reply = client.put(f"/api/uploads/skeleton?format=json&token={TOKEN}", content=b'{"joints": []}')
    assert reply.status_code == 403 and f"{link} in the project is a symbolic link" in reply.json()["error"]
    assert (secret / "private.txt").read_text() == "not the project's"
    assert sorted(p.name for p in secret.iterdir()) == ["private.txt"]


def test_a_link_made_while_the_editor_runs_stops_what_touches_files_but_not_a_drag(editable, tmp_path):
    """A key is saved in keys.json: with a link anywhere in the project the message is refused in
    one line and nothing is written; a drag, answered from memory, still is."""
    folder, client = editable
    secret = _outside(tmp_path)
    character = api.load_project(folder)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        (folder / "keys.json").symlink_to(secret / "private.txt")
        refused = _send(socket, {"id": 1, "type": "set_key", "frame": 0,
                                 "positions": character.skeleton.positions.tolist()})
        assert refused["type"] == "error"
        assert "keys.json in the project is a symbolic link" in refused["message"]
        dragged = _send(socket, {"id": 2, "type": "pose", "positions": character.skeleton.positions.tolist()})
        assert dragged["type"] == "mesh"
    assert (secret / "private.txt").read_text() == "not the project's"


def test_a_project_holding_a_link_is_not_opened(editable, tmp_path):
    from toonmotion.errors import LinkError

    folder, _ = editable
    (folder / "history").mkdir(exist_ok=True)
    (folder / "history" / "old").symlink_to(_outside(tmp_path), target_is_directory=True)
    with pytest.raises(LinkError, match=r"^history/old in the project is a symbolic link; the editor reads"):
        create_app(folder, token=TOKEN, origins=ORIGINS)


@pytest.mark.parametrize("host", ["evil.example", "evil.example:8000", "127.0.0.1.evil.example",
                                  "192.168.1.9:8000"])
def test_a_request_for_another_host_is_refused(client, host):
    """DNS rebinding: a page on another name that resolves to this machine sends its own name."""
    reply = _get(client, "/api/project", Host=host)
    assert reply.status_code == 403 and reply.json()["error"].startswith("requests for the host")
    with pytest.raises(WebSocketDisconnect) as refused:
        with client.websocket_connect(f"/ws?token={TOKEN}", headers={"Host": host}) as socket:
            socket.receive_json()
    assert refused.value.code == 1008


@pytest.mark.parametrize("host", ["127.0.0.1:8000", "localhost:8000", "[::1]:8000", "LOCALHOST"])
def test_this_machines_names_are_its_hosts(client, host):
    assert _get(client, "/api/project", Host=host).status_code == 200


def test_a_sign_in_code_is_exchanged_once_for_the_token_as_a_cookie(project):
    from toonmotion.web.server import TOKEN_COOKIE, sign_in_code

    app = create_app(project, token=TOKEN, origins=ORIGINS)
    client = TestClient(app)
    code = sign_in_code(app)
    signed = client.get(f"/?code={code}", follow_redirects=False)
    assert signed.status_code == 303 and signed.headers["location"] == "/"
    cookie = signed.headers["set-cookie"]
    assert f"{TOKEN_COOKIE}={TOKEN}" in cookie and "HttpOnly" in cookie and "SameSite=strict" in cookie
    assert client.get("/api/project").status_code == 200  # the cookie carries the token
    with client.websocket_connect("/ws") as socket:
        assert _send(socket, {"id": 1, "type": "undo"})["id"] == 1
    again = TestClient(app).get(f"/?code={code}", follow_redirects=False)
    assert again.status_code == 403 and "used already or has expired" in again.json()["error"]
    assert TestClient(app).get("/?code=made-up", follow_redirects=False).status_code == 403
    assert TestClient(app).get("/api/project").status_code == 403  # no cookie, no token


def test_a_skeleton_file_over_its_limit_is_refused_as_it_streams_in(editable):
    """A skeleton file has its own, small limit (a 200 MB one was read whole, 746 MB, before it
    was refused): the upload stops at the limit, and nothing is kept."""
    from toonmotion import limits

    folder, client = editable

    def body():  # a stream: the server must stop reading it, not receive it whole first
        for _ in range(100):
            yield b" " * 1000

    with limits.using(skeleton_bytes=5_000):
        reply = client.put(f"/api/uploads/skeleton?format=json&token={TOKEN}", content=body())
    assert reply.status_code == 413
    assert reply.json()["error"] == ("the file is over the limit skeleton_bytes=5,000; make it smaller "
                                     "(or raise the limit with --limit)")
    assert not list((folder / "uploads").glob("*")) if (folder / "uploads").is_dir() else True


def test_a_drag_is_the_librarys_drag_and_its_mesh(client, project):
    """A dragged joint's pose is made by api.drag_joint from the pose at the press, and its mesh is
    the library's; a bad drag is one line and changes nothing."""
    from toonmotion.rig.pose import Pose

    character = api.load_project(project)
    rest = character.skeleton.positions
    hand = character.skeleton.index("right_hand")
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        for mode in ("turn", "reach", "stretch"):
            to = (rest[hand] + (15, -40)).tolist()
            reply = _send(socket, {"id": 1, "type": "drag", "positions": rest.tolist(), "joint": "right_hand",
                                   "to": to, "mode": mode, "pinned": []})
            expected = api.drag_joint(character, Pose(rest), "right_hand", to, mode=mode)
            np.testing.assert_allclose(reply["positions"], expected.positions, atol=1e-9)
            U = api.pose_character(Editing.open(project).deformer, expected).deformation.U
            np.testing.assert_allclose(decode_vertices(reply["U"]), U, atol=2e-3)
        refused = _send(socket, {"id": 2, "type": "drag", "positions": rest.tolist(), "joint": "tail",
                                 "to": [0, 0]})
        assert refused["type"] == "error" and refused["message"].startswith("no joint is called 'tail'")
        refused = _send(socket, {"id": 3, "type": "drag", "positions": rest.tolist(), "joint": "right_hand",
                                 "to": [0, 0], "pinned": "right_elbow"})
        assert refused["message"] == "'pinned' must list the names of the pinned joints, got 'right_elbow'"


def test_every_page_is_told_of_another_pages_change_and_undo_says_what_it_undid(editable):
    """Two tabs on one project: a key set in one is announced to the other (which fetches the
    project again), and the other's undo says what it took back."""
    folder, client = editable
    character = api.load_project(folder)
    positions = character.skeleton.positions.tolist()
    with client.websocket_connect(f"/ws?token={TOKEN}") as one, \
            client.websocket_connect(f"/ws?token={TOKEN}") as two:
        keyed = _send(one, {"id": 1, "type": "set_key", "frame": 12, "positions": positions})
        assert keyed["type"] == "keys" and keyed["says"] == "the key at frame 12 set"
        told = two.receive_json()
        assert told == {"type": "changed", "kind": "keys", "step": None, "says": "the key at frame 12 set",
                        "history": keyed["history"]}
        assert _get(client, "/api/project").json()["keys"]["keys"][0]["frame"] == 12  # what it fetches
        undone = _send(two, {"id": 2, "type": "undo"})
        assert undone["type"] == "undone" and undone["says"] == "the key at frame 12 set"
        told = one.receive_json()
        assert (told["type"], told["kind"], told["step"], told["says"]) == \
            ("changed", "undone", "keys", "the key at frame 12 set")
        dragged = _send(one, {"id": 3, "type": "pose", "positions": positions})  # not a change: nobody told
        assert dragged["type"] == "mesh"
        redone = _send(two, {"id": 4, "type": "redo"})
        assert redone["says"] == "the key at frame 12 set"
        assert one.receive_json()["kind"] == "redone"  # the next message one gets: the pose told nothing


def test_a_slow_answer_does_not_stall_the_other_pages(editable, monkeypatch):
    """Messages are answered off the event loop: while one page's pose is being solved (held
    here until released), another page's request is served by the same server. Answered on the
    loop, the request waited for the solve. (A real server: the test client gives each request
    an event loop of its own.)"""
    import threading
    import urllib.request

    from websockets.sync.client import connect

    from toonmotion.web.background import serving

    folder, _ = editable
    released, finished = threading.Event(), []
    pose = session._HANDLERS["pose"]

    def slow_pose(editing, message):
        released.wait(10)
        finished.append("pose")
        return pose(editing, message)

    monkeypatch.setitem(session._HANDLERS, "pose", slow_pose)
    positions = api.load_project(folder).skeleton.positions.tolist()
    with serving(folder) as served, connect(served.live) as live:
        try:
            live.send(json.dumps({"id": 1, "type": "pose", "positions": positions}))
            time.sleep(0.2)  # the pose is being answered
            request = urllib.request.Request(f"http://127.0.0.1:{served.port}/api/project",
                                             headers={"X-Toonmotion-Token": served.token})
            with urllib.request.urlopen(request, timeout=30) as reply:
                assert reply.status == 200
            assert finished == []  # served while the pose was still held
            released.set()
            assert json.loads(live.recv(timeout=30))["type"] == "mesh"
        finally:
            released.set()
