"""The editor's WebSocket messages, as pydantic models like the project's files (:mod:`toonmotion.io.schema`).

Messages are JSON objects with a ``type``; ``id``, when given, is echoed back. An error is a reply
too, ``{"id": ..., "type": "error", "message": "..."}``, and changes nothing. :func:`read` turns
a message's text into its model, or raises a one-line :class:`~toonmotion.errors.MessageError`
saying which field is wrong and what it must be; fields the model does not know are ignored, so
an older page's extra fields do no harm. What each message does, and its reply, is
:mod:`toonmotion.web.session`'s and :mod:`toonmotion.web.slow_requests`'s. The 3D panel's messages
(``proxy``, ``lift``, ``scene``, ``proxy_export``) are :mod:`toonmotion.web.proxy_messages`'.

* ``pose``: every joint's ``positions`` in the skeleton's order and optional fine-tuning
  ``edits`` (thesis 3.5) in the key-frames file's form (``{"kind": "curve", "points": [...]}``
  or ``{"kind": "drag", "from": [...], "to": [...]}``); with ``accel`` and ``fixed``, the pose
  exaggerated by the single-frame cartoon filter first. Reply ``{"type": "mesh", "U": "..."}``,
  the deformed vertices as :mod:`toonmotion.web.wire` writes them (base64 of little-endian
  float32 ``x0, y0, x1, y1, ...``, as every reply's ``"U"``).
* ``drag``: ``joint`` of the pose ``positions`` dragged ``to`` [x, y], ``mode`` turn, reach or
  stretch, ``pinned`` joints (:func:`toonmotion.api.drag_joint`). Reply ``{"type": "mesh", "U",
  "positions"}``.
* ``sketch``: the ``strokes`` of a sketched skeleton, matched to the bones from ``positions``
  (:func:`toonmotion.api.sketch_pose`). Reply ``{"type": "sketched", "positions", "bones",
  "elsewhere", "U"}``.
* ``overlaps``: the regions that overlap at the same depth in the pose ``positions``. Reply
  ``{"type": "overlaps", "pairs": [{"a", "b", "area"}]}``.
* ``depth`` (``at`` [x, y], ``by`` 1 or -1: the region there a layer up or down) and ``correct``
  (``bone``, a lasso ``curve``): region edits, saved before the reply ``{"type": "regions",
  ...}`` and recorded for undo.
* ``undo``, ``redo``: the newest edit of any kind, from the history kept in the project folder
  (:mod:`toonmotion.web.history`). Reply ``{"type": "undone" | "redone", "kind", ...}``. Every
  edit's reply carries ``"history": {"undo": n, "redo": m}``.
* ``set_key`` (``frame``, ``positions``, optional ``edits``: a replaced key keeps its own),
  ``delete_key`` (``frame``), ``move_key`` (``frame``, ``to``), ``timing`` (``fps``, ``ease``):
  the key-frames, saved in the project folder's ``keys.json`` (what ``toonmotion animate``
  reads) before the reply ``{"type": "keys", ...}``.
* ``rig``: the drawing rigged again with ``joints`` ``[{"name", "parent", "position"}]``,
  replaying the region edits (the joints keep their names while key-frames name them). Reply
  ``{"type": "rigged", "skipped": n}``.
* ``track``: the ``joints`` (each with its rectangle's ``size``) tracked through the footage
  sent with ``PUT /api/footage``, off the event loop with progress messages; the motion is saved
  in ``motions/captured.json``. With ``at`` and ``set`` (name to [x, y]) it corrects the earlier
  tracking from frame ``at``; ``free``, ``frame_by_frame``, ``both_ways``, ``full_resolution``
  and ``background`` [r, g, b] are ``toonmotion track``'s options. Reply ``{"type": "tracked",
  "first", "names", "positions", "confidence", "notes", "poorly"}``.
* ``suggest``: joints suggested on the footage's first frame again, on the figure drawn on
  ``background`` (null: the border's colour). Reply ``{"type": "suggested", "joints": [...]}``.
* ``retarget``: the tracked motion replayed on the character. Reply ``{"type": "retargeted",
  "first", "last", "fps"}``, whose frames a ``frame`` message with ``"source": "capture"`` gives.
* ``open_drawing``: the drawing sent with ``PUT /api/uploads/drawing`` rigged into this project
  (``skeleton`` keep or new; ``mask``: use the uploaded mask), off the event loop; undo brings
  the old drawing back. Reply ``{"type": "opened", "width", "height", "joints"}``.
* ``frame``: the animation's ``frame`` (clamped to the keys' span), through the cartoon filter
  with ``strength`` and ``sigma``, or of the retargeted capture with ``"source": "capture"``.
  Reply ``{"type": "frame", "frame", "U", "positions"}``.
* ``export``: the key-frames' animation written into the project folder's ``exports/`` as
  ``name`` in ``format`` (gif, mp4, png, apng, webp, webm, glb, spine, sheet), with the CLI's
  ``size``, ``background`` and ``overlays``, off the event loop with progress messages
  ``{"type": "progress", "index", "count"}`` carrying the request's id. Reply ``{"type":
  "exported", "file", "files", "frames", "size"}``. The name never names a path.
* ``keyshapes``, ``keyshape_model``, ``keyshape_pick``, ``keyshape_capture``,
  ``keyshape_retarget``: the Key-shapes panel's (key-shape models, capture and retargeting, kept in
  the project folder's ``keyshapes/``), listed in :mod:`toonmotion.web.keyshape_messages`; a
  ``frame`` message with ``"source": "keyshapes"`` gives a frame of the retargeted motion.
* ``cancel``: stop the slow request ``id`` at its next progress step; its reply is then an
  error with ``"cancelled": true`` and nothing it would have saved is saved. Messages sent while
  a slow request runs are answered after it, in order.
"""

from __future__ import annotations

import json
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    StrictBool,
    StrictInt,
    StrictStr,
    ValidationError,
)

from toonmotion import limits
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.errors import MessageError
from toonmotion.io.schema import Float, Point, describe, explained, problem
from toonmotion.rig.skeleton import Skeleton
from toonmotion.web.keyshape_messages import KEYSHAPE_MODELS
from toonmotion.web.message_base import Message, must, required
from toonmotion.web.proxy_messages import PROXY_MODELS

# A WebSocket message longer than this is refused unread (a pose of 10,000 joints fits easily).
MAX_MESSAGE_BYTES = 1_000_000
# Each export format's file name after the export's name: Spine's skeleton and a sprite sheet's
# atlas are both JSON, so they carry a second suffix (their .atlas and .png are written beside them).
EXPORT_FORMATS = {"gif": ".gif", "mp4": ".mp4", "png": "", "apng": ".apng", "webp": ".webp", "webm": ".webm",
                  "glb": ".glb", "spine": ".spine.json", "sheet": ".sheet.json"}


def _always(text: str) -> Any:
    """A field whose every problem, inside it too, reads ``text``."""
    return explained(lambda value, errors: text)


def _within_canvas(size: tuple[int, int] | None) -> tuple[int, int] | None:
    side = limits.current().canvas_side
    if size is not None and not all(1 <= v <= side for v in size):
        raise problem(f"'size' must be [width, height], whole pixels from 1 to {side:,}; got {list(size)}")
    return size


def _one_layer(by: int) -> int:
    if by not in (1, -1):
        raise problem(f"'by' must be 1 (one layer up) or -1 (one down), got {by}")
    return by


Frame = Annotated[StrictInt, Field(ge=0, le=2**31 - 1)]
Byte = Annotated[StrictInt, Field(ge=0, le=255)]
Background = Annotated[tuple[Byte, Byte, Byte] | None,
                       must("'background' must be null or [r, g, b], each 0 to 255")]
Positions = Annotated[list[Point] | None,
                      must("'positions' must list [x, y] pairs of numbers, one for each joint")]
Edits = Annotated[list[Any] | None, must("'edits' must be a list of edits")]
Flag = StrictBool


class Exaggerated(Message):
    """A message that may ask for the cartoon filter (``strength``; 0 or none: off)."""

    strength: Annotated[Float | None, must("'strength' must be a number")] = None
    sigma: Annotated[Float, must("'sigma' must be a number of frames")] = 3.0

    def exaggeration(self) -> FilterSettings | None:
        """The cartoon filter asked for, or None (the filter checks its own ranges)."""
        return FilterSettings(strength=self.strength, sigma=self.sigma) if self.strength else None


class Pose(Message):
    positions: Positions = None
    edits: Edits = None
    accel: Annotated[Point | None, must("'accel' must be [x, y]")] = None
    fixed: Annotated[list[StrictStr] | None,
                     must("'fixed' must list the names of the joints that stay put")] = None


class Drag(Message):
    positions: Positions = None
    edits: Edits = None
    joint: Annotated[StrictStr, must("'joint' must name the joint dragged")] = required()
    to: Annotated[Point, must("'to' must be [x, y]")] = required()
    mode: Annotated[StrictStr, must("'mode' must be turn, reach or stretch")] = "turn"
    pinned: Annotated[list[StrictStr], must("'pinned' must list the names of the pinned joints")] = []


class Sketch(Message):
    positions: Positions = None
    strokes: Annotated[list[list[Point]],
                       must("'strokes' must be a list of strokes, each a list of [x, y] points",
                            inner="a stroke's point must be [x, y]")] = required()


class Overlaps(Message):
    positions: Positions = None


class Depth(Message):
    at: Annotated[Point, must("'at' must be [x, y]")] = required()
    by: Annotated[StrictInt, AfterValidator(_one_layer),
                  must("'by' must be 1 (one layer up) or -1 (one down)")] = required()


class Correct(Message):
    bone: Annotated[StrictStr, must("'bone' must name the bone to attach to")] = required()
    curve: Annotated[list[Point], Field(min_length=3, max_length=10_000),
                     must("'curve' must be a closed curve of 3 to 10,000 [x, y] points")] = required()


class SetKey(Message):
    frame: Annotated[Frame, must("'frame' must be a frame number, a whole number >= 0")] = required()
    positions: Positions = None
    edits: Edits = None


class DeleteKey(Message):
    frame: Annotated[Frame, must("'frame' must be a frame number, a whole number >= 0")] = required()


class MoveKey(Message):
    frame: Annotated[Frame, must("'frame' must be a frame number, a whole number >= 0")] = required()
    to: Annotated[Frame, must("'to' must be a frame number, a whole number >= 0")] = required()


class Timing(Message):
    fps: Annotated[Float | None, must("'fps' must be a number of frames per second")] = None
    ease: Annotated[StrictStr | None, must("'ease' must be linear, in-out, in or out")] = None


class ShowFrame(Exaggerated):
    frame: Annotated[Frame, must("'frame' must be a frame number, a whole number >= 0")] = required()
    source: Literal["keys", "capture", "keyshapes"] | None = None


class Joint(BaseModel):
    """A joint of a skeleton sent by the page: ``{"name", "parent": name or null, "position"}``."""

    model_config = ConfigDict(extra="ignore", frozen=True, allow_inf_nan=False)

    name: StrictStr
    parent: StrictStr | None = None
    position: Annotated[Point, _always("joint {n}'s position must be [x, y]")]


def skeleton_of(joints: list[Joint] | list[TrackedJoint]) -> Skeleton:
    """The skeleton a message's joints make (:class:`~toonmotion.errors.SkeletonError` if they do not)."""
    return Skeleton.from_joints((joint.name, joint.parent, joint.position) for joint in joints)


class TrackedJoint(Joint):
    """A joint to track, with its rectangle's ``size`` [width, height] in pixels."""

    size: Annotated[Point, _always("joint {n}'s size must be [width, height]")]


_NEEDS = "joint {n} needs a 'name', a 'parent' (a name or null) and a 'position'"


def _needs(text: str) -> Any:
    """A joint that is not an object, or lacks a field or has one of the wrong kind: ``text``."""
    return explained(lambda value, errors: text if len(errors[0]["loc"]) <= 1 else None)



class Rig(Message):
    joints: Annotated[list[Annotated[Joint, _needs(_NEEDS)]], Field(min_length=1),
                      must("'joints' must list the skeleton's joints")] = required()


_TRACKED = "'joints' must list the joints to track, each with its rectangle's 'size'"


class Track(Message):
    joints: Annotated[list[Annotated[TrackedJoint, _needs(_NEEDS + " and 'size'")]], Field(min_length=1),
                      must(_TRACKED)] = required()
    at: Annotated[Frame | None, must("'at' must be a frame number, a whole number >= 0")] = None
    set: Annotated[dict[str, Point] | None, Field(min_length=1),
                   must("'set' must give the corrected joints, name to [x, y]")] = None
    free: Annotated[Flag, must("'free' must be true or false")] = False
    frame_by_frame: Annotated[Flag, must("'frame_by_frame' must be true or false")] = False
    both_ways: Annotated[Flag, must("'both_ways' must be true or false")] = False
    full_resolution: Annotated[Flag, must("'full_resolution' must be true or false")] = False
    background: Background = None


class Suggest(Message):
    background: Background = None


class OpenDrawing(Message):
    skeleton: Annotated[Literal["keep", "new"], must("'skeleton' must be \"keep\" or \"new\"")] = "keep"
    mask: Annotated[Flag, must("'mask' must be true or false")] = False


class Export(Exaggerated):
    format: Annotated[Literal["gif", "mp4", "png", "apng", "webp", "webm", "glb", "spine", "sheet"],
                      must(f"'format' must be {', '.join(EXPORT_FORMATS)}")] = required()
    name: Annotated[StrictStr, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$"),
                    must("'name' must be 1 to 64 letters, digits, - or _, not starting with - or _")
                    ] = required()
    size: Annotated[tuple[StrictInt, StrictInt] | None, AfterValidator(_within_canvas),
                    must("'size' must be [width, height] in whole pixels")] = None
    background: Background = None
    overlays: Annotated[list[StrictStr], must("'overlays' must list overlay names")] = []


class Cancel(Message):
    pass


# Every message the editor sends, by its ``type``.
MODELS: dict[str, type[Message]] = {
    "pose": Pose, "drag": Drag, "sketch": Sketch, "overlaps": Overlaps, "depth": Depth, "correct": Correct,
    "undo": Message, "redo": Message, "set_key": SetKey, "delete_key": DeleteKey, "move_key": MoveKey,
    "timing": Timing, "frame": ShowFrame, "rig": Rig, "retarget": Message, "track": Track,
    "suggest": Suggest, "open_drawing": OpenDrawing, "export": Export, "cancel": Cancel, **PROXY_MODELS,
    **KEYSHAPE_MODELS,
}


def parse(text: str) -> dict[str, Any]:
    """A message's JSON object, or :class:`MessageError` (too long, not JSON, not an object)."""
    if len(text) > MAX_MESSAGE_BYTES:
        raise MessageError(f"a message may be {MAX_MESSAGE_BYTES:,} bytes at most, got {len(text):,}")
    try:
        message = json.loads(text)
    except (ValueError, RecursionError):
        raise MessageError("a message must be a JSON object") from None
    if not isinstance(message, dict):
        raise MessageError("a message must be a JSON object")
    return message


def ident(message: dict[str, Any]) -> int | str | None:
    """A parsed message's ``id`` to echo back (None unless a number or a string)."""
    value = message.get("id")
    return value if isinstance(value, (int, str)) and not isinstance(value, bool) else None


def read(message: dict[str, Any]) -> Message:
    """The model of a parsed message (:func:`parse`), by its ``type``.

    Raises
    ------
    MessageError
        An unknown type, or the first field that is not what the protocol says, in one line.
    """
    kind = message.get("type")
    model = MODELS.get(kind) if isinstance(kind, str) else None
    if model is None:
        sent = ", ".join(map(repr, MODELS))
        raise MessageError(f"unknown message type {str(kind)[:40]!r}; the editor sends {sent}")
    try:
        return model.model_validate(message)
    except ValidationError as error:
        text, cls = describe(error.errors()[0])
        raise (cls or MessageError)(text) from None


# --- how a reply words a failure ------------------------------------------------------------------


def bug(error: Exception) -> str:
    return f"internal error ({type(error).__name__}); this is a bug in toonmotion, please report it"


def one_line(text: str) -> str:
    return " ".join(text.split())[:400]
