"""The Key-shapes panel's server side (toonmotion.web.keyshape_requests) without a browser: outlines
in, the model and its sheet, capture from contours and from footage with progress, retargeting onto
the Timeline's keys, the files the CLI reads, one-line refusals, and resuming after a restart."""

import io
import json
import shutil

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image

from tests.web.slow_work import slow_work
from toonmotion import api
from toonmotion.cli import main
from toonmotion.io.frames import load_frames
from toonmotion.io.keyshape_json import load_contours, load_keymotion, load_model
from toonmotion.io.motion_json import load_motion
from toonmotion.io.pose_json import load_keyframes
from toonmotion.keyshape.model import warp
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_cartoons import morphing_character
from toonmotion.samples import sample_character
from toonmotion.web import session
from toonmotion.web.editing import Editing
from toonmotion.web.server import create_app
from toonmotion.web.wire import decode_vertices

TOKEN = "secret-token"
ORIGINS = ("http://127.0.0.1:8000", "http://testserver")


@pytest.fixture(scope="module")
def hero():
    return morphing_character(frames=12)


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("keyshapes") / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    return folder


@pytest.fixture
def editable(project, tmp_path):
    folder = tmp_path / "hero"
    shutil.copytree(project, folder)
    return folder, TestClient(create_app(folder, token=TOKEN, origins=ORIGINS))


def _send(socket, message):
    socket.send_text(json.dumps(message))
    said = [socket.receive_json()]
    while said[-1]["type"] == "progress":
        said.append(socket.receive_json())
    return said[-1], said[:-1]


def _contours_file(shapes, fps=24.0):
    return json.dumps({"format": "toonmotion.contours", "version": 1, "fps": fps, "closed": True,
                       "contours": np.asarray(shapes).tolist()}).encode()


def _put(client, part, body, suffix="json", **query):
    extra = "".join(f"&{k}={v}" for k, v in query.items())
    return client.put(f"/api/keyshapes/{part}?suffix={suffix}&token={TOKEN}{extra}", content=body)


def _key_poses(folder, socket):
    """Three keys on the Timeline, at frames 0, 5 and 9: rest, the right arm up, the left out."""
    character = api.load_project(folder)
    poses = [character.skeleton.positions, api.rotate_joint(character, "right_elbow", -1.0).positions,
             api.rotate_joint(character, "left_elbow", 0.8).positions]
    for frame, pose in zip((0, 5, 9), poses, strict=True):
        reply, _ = _send(socket, {"type": "set_key", "frame": frame, "positions": pose.tolist()})
        assert reply["type"] == "keys", reply
    return character, poses


def test_contours_are_captured_retargeted_onto_timeline_keys_and_saved_as_the_cli_reads_them(
        editable, hero, capsys):
    folder, client = editable
    keys = hero.contours[list(hero.key_frames)]
    sent = _put(client, "outlines", _contours_file(keys))
    assert sent.status_code == 200, sent.text
    assert np.allclose(sent.json()["outlines"], keys, atol=1e-3)
    contours = _put(client, "contours", _contours_file(hero.contours))
    assert contours.json() == {"frames": 12, "points": keys.shape[1], "fps": 24.0}
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        built, steps = _send(socket, {"id": 1, "type": "keyshape_model", "outlines": keys.tolist()})
        assert built["type"] == "keyshapes", built
        assert [(s["index"], s["count"]) for s in steps] == [(0, 3), (1, 3), (2, 3), (3, 3)]
        captured, progress = _send(socket, {"id": 2, "type": "keyshape_capture", "source": "contours"})
        assert captured["type"] == "keyshapes", captured
        assert [(p["id"], p["index"], p["count"]) for p in progress] == [(2, t, 12) for t in range(1, 13)]
        character, poses = _key_poses(folder, socket)
        retargeted, _ = _send(socket, {"type": "keyshape_retarget", "keys": [0, 5, 9]})
        assert retargeted == {"id": None, "type": "keyshape_retargeted", "first": 0, "last": 11, "fps": 24.0,
                              "file": "keyshapes/retargeted.json"}
        shown, _ = _send(socket, {"type": "frame", "frame": 7, "source": "keyshapes"})
    # The model and its sheet are the library's, from the same keys.
    space = api.keyshape_space(keys)
    assert np.allclose(load_model(folder / "keyshapes" / "model.json").keys, space.keys)
    assert built["model"]["eigen"] == len(space.eigen) and built["model"]["closed"] is True
    sheet = client.get(built["model"]["sheet"], headers={"X-Toonmotion-Token": TOKEN})
    assert sheet.status_code == 200 and sheet.headers["content-type"] == "image/png"
    assert np.array_equal(np.asarray(Image.open(io.BytesIO(sheet.content)).convert("RGB")),
                          api.keyshape_sheet(space))
    # The capture is the library's, with the hand-picked keys.
    found = api.capture_contours(hero.contours, space.keys)
    assert np.allclose(captured["capture"]["weights"], found.weights, atol=1e-5)
    assert np.allclose(captured["capture"]["affine"], found.affine, atol=1e-5)
    assert np.allclose(captured["capture"]["error"], found.error, atol=1e-4)
    saved, fps, space_kind = load_keymotion(folder / "keyshapes" / "motion.json")
    assert (fps, space_kind) == (24.0, "keys") and np.array_equal(saved.weights, found.weights)
    # The shape overlaid on each frame is the model's (eq. 2), its distance to the contour the error.
    fitted = np.asarray(captured["capture"]["shapes"])
    model = np.stack([warp(a, w, space.keys) for a, w in zip(found.affine, found.weights, strict=True)])
    assert np.allclose(fitted, model, atol=0.01)
    assert np.allclose(captured["capture"]["path"], model.mean(axis=1), atol=0.01)  # the affine path
    rms = np.sqrt(((model - hero.contours) ** 2).sum(axis=2).mean(axis=1))
    assert np.allclose(rms, found.error, atol=1e-6)
    # The retargeted motion is retarget_keyposes' on the chosen keys, the character's outline its reference.
    timeline = load_keyframes(folder / "keyshapes" / "poses.json", character.skeleton)
    assert [k.frame for k in timeline.keys] == [0, 1, 2]
    assert all(np.allclose(k.pose.positions, p) for k, p in zip(timeline.keys, poses, strict=True))
    expected = api.retarget_keyposes(found, space.keys, character.skeleton, timeline, fps=24.0,
                                     reference=character.mesh.V[character.mesh.boundary[0]])
    motion = load_motion(folder / "keyshapes" / "retargeted.json")
    assert np.allclose(motion.positions, expected.positions, atol=1e-6)
    assert np.allclose(shown["positions"], expected.positions[7], atol=1e-6)
    assert len(decode_vertices(shown["U"])) == len(character.mesh.V)
    # The CLI makes the same motion from the files the panel saved.
    out = folder / "cli.json"
    k = folder / "keyshapes"
    with pytest.raises(SystemExit) as done:
        main(["retarget-keyshapes", str(k / "motion.json"), str(k / "model.json"), "--project", str(folder),
              "--poses", str(k / "poses.json"), "-o", str(out)])
    assert done.value.code in (0, None), capsys.readouterr()
    assert np.allclose(load_motion(out).positions, motion.positions)


def test_the_panel_resumes_after_a_restart(editable, hero):
    folder, client = editable
    keys = hero.contours[list(hero.key_frames)]
    _put(client, "contours", _contours_file(hero.contours))
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "keyshape_model", "outlines": keys.tolist()})
        before, _ = _send(socket, {"type": "keyshape_capture", "source": "contours"})
        _key_poses(folder, socket)
        _send(socket, {"type": "keyshape_retarget", "keys": [9, 0, 5],
                       "pin": {"joint": "left_foot", "at": [60, 120]}})
        shown, _ = _send(socket, {"type": "frame", "frame": 4, "source": "keyshapes"})
    again = Editing.open(folder)  # a new server on the same folder
    after = session.answer(again, json.dumps({"id": 3, "type": "keyshapes"}))
    assert after["type"] == "keyshapes", after
    for part in ("model", "contours", "capture"):
        assert after[part] == before[part], part
    assert np.allclose(after["outlines"], keys)
    assert after["retargeted"] == {"first": 0, "last": 11, "fps": 24.0, "keys": [9, 0, 5],
                                   "file": "keyshapes/retargeted.json"}
    replayed = session.answer(again, json.dumps({"type": "frame", "frame": 4, "source": "keyshapes"}))
    assert replayed["positions"] == shown["positions"]
    character = api.load_project(folder)
    foot = np.asarray(replayed["positions"])[character.skeleton.index("left_foot")]
    assert np.allclose(foot, [60, 120])  # the pin holds the foot there


def test_drawn_outlines_of_any_point_count_are_resampled_by_the_library(editable):
    folder, client = editable
    angles = [np.linspace(0, 2 * np.pi, n, endpoint=False) for n in (40, 57, 33)]
    drawn = [np.column_stack([100 + r * np.cos(a), 80 + s * np.sin(a)])
             for a, r, s in zip(angles, (30, 40, 22), (30, 20, 38), strict=True)]
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        refused, _ = _send(socket, {"type": "keyshape_model", "outlines": [d.tolist() for d in drawn]})
        built, _ = _send(socket, {"type": "keyshape_model", "outlines": [d.tolist() for d in drawn],
                                  "points": 48})
    assert refused["type"] == "error" and "\n" not in refused["message"]
    assert refused["message"].startswith("the key outlines must be lists of [x, y] points with the same")
    assert "tmp" not in refused["message"] and "resample" in refused["message"]
    assert not (folder / "keyshapes" / "model.json").exists() or built["type"] == "keyshapes"
    assert built["type"] == "keyshapes", built
    # What `toonmotion keyshapes outlines.json --points 48` reads: the outlines as drawn, resampled.
    resampled, _, _ = load_contours(folder / "keyshapes" / "outlines.json", points=48)
    assert np.allclose(built["model"]["keys"], resampled, atol=0.01)
    assert [len(o) for o in built["outlines"]] == [40, 57, 33]


def test_footage_is_captured_frame_by_frame_with_the_keys_drawn_on_their_frames(editable):
    folder, client = editable
    hero = morphing_character(frames=24)  # the clip api.capture_video's example captures
    for index, picture in enumerate(hero.frames):  # a folder of frames (a GIF would merge the held ones)
        buffer = io.BytesIO()
        Image.fromarray(picture).save(buffer, format="PNG")
        sent = client.put(f"/api/footage/frames/{index}?count=24&suffix=png&token={TOKEN}",
                          content=buffer.getvalue())
        assert sent.status_code == 200, sent.text
    key_frames = list(hero.key_frames)
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        picked, _ = _send(socket, {"type": "keyshape_pick", "frame": 8,
                                   "at": hero.contours[8].mean(axis=0).tolist(), "points": 60})
        _send(socket, {"type": "keyshape_model", "outlines": hero.contours[key_frames].tolist(),
                       "key_frames": key_frames})
        captured, progress = _send(socket, {"type": "keyshape_capture", "source": "video"})
    assert picked["type"] == "picked" and len(picked["outline"]) == 60
    inside = hero.contours[8]  # the picked outline runs round the character drawn there
    assert np.hypot(*(np.mean(picked["outline"], axis=0) - inside.mean(axis=0))) < 3
    assert captured["type"] == "keyshapes", captured
    assert progress and progress[-1]["index"] == progress[-1]["count"]
    frames, _ = load_frames(folder / "footage" / "frames")
    assert np.array_equal(frames, hero.frames)
    keys = hero.contours[key_frames]
    video = api.capture_video(frames, keys, key_frames=key_frames)
    found = api.capture_contours(video.shapes, keys)
    assert np.allclose(captured["capture"]["shapes"], video.shapes, atol=0.01)
    assert np.allclose(captured["capture"]["weights"], found.weights, atol=1e-5)
    assert np.hypot(*(video.shapes - hero.contours).T).mean() < 1  # on the drawn character
    assert captured["footage"]["frames"] == 24
    # A restart reads the footage the capture was made on back from the project.
    again = session.answer(Editing.open(folder), json.dumps({"type": "keyshapes"}))
    assert again["footage"] == captured["footage"] and again["capture"] == captured["capture"]


TRIANGLE = [[0, 0], [9, 0], [0, 9]]


@pytest.mark.parametrize(("message", "said"), [
    ({"type": "keyshape_model"}, "'outlines' must list 1 to 64 closed curves"),
    ({"type": "keyshape_model", "outlines": [[[0, 0], [1, 0]]]}, "'outlines' must list 1 to 64 closed"),
    ({"type": "keyshape_model", "outlines": [TRIANGLE], "points": 2}, "'points' must be null"),
    ({"type": "keyshape_model", "outlines": [TRIANGLE], "key_frames": [0, 1]},
     "'key_frames' names 2 frames for 1 outlines"),
    ({"type": "keyshape_capture"}, "'source' must be \"contours\" or \"video\""),
    ({"type": "keyshape_capture", "source": "contours"}, "there is no key-shape model yet"),
    ({"type": "keyshape_retarget", "keys": [0]}, "there is no captured key-shape motion yet"),
    ({"type": "keyshape_retarget", "keys": "0"}, "'keys' must list the frames of the Timeline's keys"),
    ({"type": "keyshape_pick", "at": [1, 2]}, "there is no footage yet"),
    ({"type": "frame", "frame": 0, "source": "keyshapes"}, "nothing is retargeted from key-shapes yet"),
])
def test_bad_requests_are_refused_in_one_line_and_save_nothing(editable, message, said):
    folder, client = editable
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        reply, _ = _send(socket, message)
    assert reply["type"] == "error" and reply["message"].startswith(said), reply
    assert "\n" not in reply["message"] and "Traceback" not in reply["message"]
    assert not (folder / "keyshapes" / "model.json").exists()


def test_retargeting_needs_one_timeline_key_per_key_shape(editable, hero):
    folder, client = editable
    _put(client, "contours", _contours_file(hero.contours))
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "keyshape_model", "outlines": hero.contours[list(hero.key_frames)].tolist()})
        _send(socket, {"type": "keyshape_capture", "source": "contours"})
        no_keys, _ = _send(socket, {"type": "keyshape_retarget", "keys": [0, 5, 9]})
        _key_poses(folder, socket)
        too_few, _ = _send(socket, {"type": "keyshape_retarget", "keys": [0, 5]})
        elsewhere, _ = _send(socket, {"type": "keyshape_retarget", "keys": [0, 5, 7]})
        bad_pin, _ = _send(socket, {"type": "keyshape_retarget", "keys": [0, 5, 9],
                                    "pin": {"joint": "tail", "at": [0, 0]}})
    assert no_keys["message"].startswith("there are no key-frames yet")
    assert too_few["message"] == "choose one of the Timeline's keys for each of the 3 key-shapes, got 2"
    assert elsewhere["message"] == "the Timeline has no key at frame 7; its keys are at 0, 5, 9"
    assert bad_pin["type"] == "error" and "tail" in bad_pin["message"]
    assert not (folder / "keyshapes" / "retargeted.json").exists()


@pytest.mark.parametrize(("part", "suffix", "body", "status", "said"), [
    ("drawing", "json", b"{}", 404, "the key-shapes panel takes outlines or contours"),
    ("outlines", "exe", b"x", 400, "send outlines as json, csv, svg"),
    ("outlines", "json", b"not json", 400, "keys.json"),
    ("contours", "csv", b"contour,point,x,y\n0,0,1,1\n", 400, "keys.json"),
])
def test_bad_files_are_refused_in_one_line(editable, part, suffix, body, status, said):
    folder, client = editable
    reply = _put(client, part, body, suffix=suffix, name="keys.json")
    assert reply.status_code == status
    message = reply.json()["error"]
    assert said in message and "\n" not in message and str(folder) not in message
    assert not (folder / "keyshapes" / "contours.json").exists()


def test_an_svg_of_shapes_is_read_as_outlines_resampled_into_correspondence(editable):
    _, client = editable
    svg = (b'<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200">'
           b'<circle cx="100" cy="100" r="40"/><ellipse cx="100" cy="100" rx="60" ry="30"/></svg>')
    reply = _put(client, "outlines", svg, suffix="svg", points=32)
    assert reply.status_code == 200, reply.text
    outlines = np.asarray(reply.json()["outlines"])
    assert outlines.shape == (2, 32, 2)
    assert np.allclose(np.hypot(*(outlines[0] - 100).T), 40, atol=0.5)


def test_a_capture_can_be_cancelled_and_the_earlier_one_is_kept(editable, hero, monkeypatch):
    folder, client = editable
    _put(client, "contours", _contours_file(hero.contours))
    saved = folder / "keyshapes" / "motion.json"
    stopped: list[str] = []
    with client.websocket_connect(f"/ws?token={TOKEN}") as socket:
        _send(socket, {"type": "keyshape_model", "outlines": hero.contours[list(hero.key_frames)].tolist()})
        first, _ = _send(socket, {"type": "keyshape_capture", "source": "contours"})
        before = saved.read_bytes()
        monkeypatch.setattr(api, "capture_contours", slow_work(stopped))
        socket.send_text(json.dumps({"id": 7, "type": "keyshape_capture", "source": "contours"}))
        assert socket.receive_json() == {"id": 7, "type": "progress", "index": 0, "count": 3000}
        socket.send_text(json.dumps({"id": 7, "type": "cancel"}))
        cancelled, _ = _send(socket, {"type": "keyshapes"})  # the reply to 7 comes first
        while cancelled.get("id") != 7:
            cancelled = socket.receive_json()
        state, _ = _send(socket, {"type": "keyshapes"})
    said = "cancelled: did not capture the key-shapes; nothing saved before was changed"
    assert cancelled == {"id": 7, "type": "error", "cancelled": True, "message": said}
    assert stopped == ["Cancelled"]
    assert saved.read_bytes() == before and state["capture"] == first["capture"]
