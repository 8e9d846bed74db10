"""The editor's WebSocket messages as pydantic models (issue 47): every field checked before any
handler sees it, each refusal one line naming the field and what it must be."""

import json

import pytest

from toonmotion.errors import MessageError, ToonmotionError
from toonmotion.web import messages, session
from toonmotion.web.messages import MODELS, parse, read
from toonmotion.web.socket_flow import SLOW_HANDLERS


@pytest.mark.parametrize("message, said", [
    ({"type": "pose", "positions": "here"}, "'positions' must list [x, y] pairs of numbers"),
    ({"type": "pose", "positions": [[0, 0]], "accel": [1, float("nan")]}, "'accel' must be [x, y]"),
    ({"type": "pose", "positions": [[0, 0]], "accel": [1, 2], "fixed": "hip"}, "'fixed' must list the names"),
    ({"type": "drag", "to": [1, 2]}, "'joint' must name the joint dragged, got None"),
    ({"type": "drag", "joint": "a", "to": [True, 2]}, "'to' must be [x, y], got [True, 2]"),
    ({"type": "drag", "joint": "a", "to": [1, 2], "mode": 3}, "'mode' must be turn, reach or stretch"),
    ({"type": "sketch"}, "'strokes' must be a list of strokes, each a list of [x, y] points, got None"),
    ({"type": "sketch", "strokes": [[[1, "a"]]]}, "a stroke's point must be [x, y], got 'a'"),
    ({"type": "depth", "at": [1, 2], "by": True}, "'by' must be 1 (one layer up) or -1 (one down)"),
    ({"type": "depth", "at": [1, 2], "by": 2}, "'by' must be 1 (one layer up) or -1 (one down), got 2"),
    ({"type": "correct", "bone": "arm", "curve": [[0, 0], [1, 1]]}, "'curve' must be a closed curve of 3"),
    ({"type": "set_key", "frame": -1}, "'frame' must be a frame number, a whole number >= 0"),
    ({"type": "set_key", "frame": 2**31}, "'frame' must be a frame number"),
    ({"type": "move_key", "frame": 1, "to": 1.5}, "'to' must be a frame number"),
    ({"type": "timing", "fps": "fast"}, "'fps' must be a number of frames per second, got 'fast'"),
    ({"type": "frame", "frame": 1, "strength": "big"}, "'strength' must be a number"),
    ({"type": "rig", "joints": [7]}, "joint 1 needs a 'name', a 'parent' (a name or null) and a 'position'"),
    ({"type": "rig", "joints": [{"name": "a", "position": [1, "b"]}]}, "joint 1's position must be [x, y]"),
    ({"type": "track", "joints": [{"name": "a", "position": [1, 2]}]}, "joint 1 needs a 'name'"),
    ({"type": "track", "joints": [{"name": "a", "position": [1, 2], "size": [4, 4]}], "free": "yes"},
     "'free' must be true or false, got 'yes'"),
    ({"type": "suggest", "background": [0, 0]}, "'background' must be null or [r, g, b], each 0 to 255"),
    ({"type": "open_drawing", "skeleton": "old"}, "'skeleton' must be \"keep\" or \"new\", got 'old'"),
    ({"type": "open_drawing", "mask": 1}, "'mask' must be true or false, got 1"),
    ({"type": "export", "format": "exe", "name": "ok"}, "'format' must be gif, mp4, png, apng"),
    ({"type": "export", "format": "gif", "name": "../up"}, "'name' must be 1 to 64 letters"),
    ({"type": "export", "format": "gif", "name": "ok", "size": [0, 10]}, "'size' must be [width, height]"),
    ({"type": "export", "format": "gif", "name": "ok", "overlays": "mesh"}, "'overlays' must list"),
    ({"type": "dance"}, "unknown message type 'dance'; the editor sends 'pose', 'drag'"),
])
def test_a_field_of_the_wrong_kind_is_refused_in_one_line_naming_it(message, said):
    with pytest.raises(MessageError) as refused:
        read(message)
    assert said in str(refused.value), str(refused.value)
    assert "\n" not in str(refused.value) and len(str(refused.value)) < 400


def test_text_that_is_no_json_object_or_too_long_is_refused_before_it_is_read():
    for text in ("not json", "[1, 2]", "[" * 100_000):
        with pytest.raises(MessageError, match="a message must be a JSON object"):
            parse(text)
    with pytest.raises(MessageError, match="1,000,000 bytes at most"):
        parse(" " * (messages.MAX_MESSAGE_BYTES + 1))


def test_a_good_message_reads_as_its_model_with_unknown_fields_ignored():
    drag = read(parse(json.dumps({"id": 7, "type": "drag", "joint": "hand", "to": [1, 2.5], "mode": "reach",
                                  "pinned": ["hip"], "from_an_older_page": True})))
    assert isinstance(drag, messages.Drag)
    assert (drag.id, drag.joint, drag.to, drag.mode, drag.pinned) == (7, "hand", (1.0, 2.5), "reach", ["hip"])
    key = read({"type": "set_key", "frame": 3, "positions": [[1, 2]]})
    assert "edits" not in key.model_fields_set  # a replaced key keeps its own edits
    assert read({"type": "frame", "frame": 2, "strength": 0}).exaggeration() is None
    assert read({"type": "frame", "frame": 2, "strength": 1.5, "sigma": 2}).exaggeration().strength == 1.5


def test_every_message_has_exactly_one_handler():
    slow = set(SLOW_HANDLERS)
    assert {"export", "track", "open_drawing", "suggest", "lift", "scene", "proxy_export"} <= slow
    assert {"keyshape_model", "keyshape_capture"} <= slow
    assert set(session._HANDLERS) | slow | {"cancel"} == set(MODELS)
    assert not set(session._HANDLERS) & slow
    assert issubclass(MessageError, ToonmotionError)  # the page shows it as every other error


def test_an_id_is_echoed_only_when_it_is_a_number_or_a_string():
    echoed = [messages.ident({"id": v}) for v in (3, "a", True, None, [1], 2.5)]
    assert echoed == [3, "a", None, None, None, None]
