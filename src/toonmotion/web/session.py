"""The open project in the editor, and the WebSocket messages that read and change it.

Messages are JSON objects; ``id``, when given, is echoed back. An error is a reply too,
``{"id": ..., "type": "error", "message": "..."}``, and changes nothing.

* ``{"type": "pose", "positions": [[x, y], ...], "edits": [...]}``: every joint's position, in
  the skeleton's order, and optional fine-tuning edits (thesis 3.5) in the key-frames file's
  form, ``{"kind": "curve", "points": [...]}`` or ``{"kind": "drag", "from": [...], "to":
  [...]}``. Reply: ``{"type": "mesh", "U": "..."}``, the deformed vertices (the needle model,
  then the joint-area solve) as :mod:`toonmotion.web.wire` writes them: base64 of
  little-endian float32 ``x0, y0, x1, y1, ...``, as every reply's ``"U"`` below.
* ``{"type": "drag", "positions": [...], "joint": name, "to": [x, y], "mode": "turn" | "reach" |
  "stretch", "pinned": [names], "edits": [...]}``: ``joint`` of the pose ``positions`` (the one
  at the press) dragged to ``to`` (:func:`toonmotion.api.drag_joint`: its bone turns and carries
  the joints below, or the chain above it reaches, or its bone stretches). Reply: ``{"type":
  "mesh", "U": "...", "positions": [...]}``, the pose made and its deformed vertices.
* ``{"type": "sketch", "strokes": [[[x, y], ...], ...], "positions": [...]}``: the strokes of a
  sketched skeleton, matched to the bones (:func:`toonmotion.api.sketch_pose`), starting from
  ``positions``. Reply: ``{"type": "sketched", "positions": [...], "bones": [...],
  "elsewhere": bool, "U": "..."}``, the pose, the bones covered and the deformed vertices.
* ``{"type": "overlaps", "positions": [...]}``: the regions that overlap at the same depth in
  that pose. Reply: ``{"type": "overlaps", "pairs": [{"a": bone, "b": bone, "area": px2}]}``.
* Edits of the regions, each saved in the project before the reply (atomic writes, as the
  CLI's) and recorded for undo: ``{"type": "depth", "at": [x, y], "by": 1 | -1}`` (the region
  there one layer up or down), ``{"type": "correct", "bone": name, "curve": [[x, y], ...]}``
  (a lasso). Reply: ``{"type": "regions", ...}``, as :func:`regions` gives them.
* ``{"type": "undo"}``, ``{"type": "redo"}``: the newest edit of any kind (regions, keys,
  rigging) undone or made again, from the history kept in the project folder
  (:mod:`toonmotion.web.history`). Reply: ``{"type": "undone" | "redone", "kind": ...}`` with
  the regions and keys as they are now. Every edit's reply carries ``"history": {"undo": n,
  "redo": m}``.
* Key-frames, saved in the project folder's ``keys.json`` (the key-frames format
  ``toonmotion animate`` reads) before the reply: ``{"type": "set_key", "frame": n,
  "positions": [...], "edits": [...]}`` (edits optional: a replaced key keeps its own),
  ``{"type": "delete_key", "frame": n}``, ``{"type": "move_key", "frame": n, "to": m}``.
  Reply: ``{"type": "keys", ...}``, as :func:`keys` gives them.
* ``{"type": "rig", "joints": [{"name": ..., "parent": name or null, "position": [x, y]}, ...]}``:
  rig the drawing again with this skeleton, replaying the region edits; saved before the reply
  ``{"type": "rigged", "skipped": n}`` (edits that no longer apply). While there are key-frames,
  the joints' names must stay the same (the keys name them).
* ``{"type": "timing", "fps": 12, "ease": "in-out"}``: the key-frames' rate and easing, saved
  like a key edit. Reply: ``{"type": "keys", ...}``.
* Capture, on footage sent with ``PUT /api/footage``: ``{"type": "track", "joints": [{"name",
  "parent", "position", "size": [w, h]}, ...]}`` tracks them from the first frame (off the event
  loop, with progress messages, as an export) and saves the motion in the project folder's
  ``motions/captured.json``; with ``"at": t, "set": {name: [x, y]}`` it corrects the earlier
  tracking instead, tracking again from frame ``t``; with ``"free": true`` the joints are not held
  to the figure on a plain background (``toonmotion track --free``); with ``"frame_by_frame":
  true`` each frame's own choice is kept (``toonmotion track --frame-by-frame``); with
  ``"both_ways": true`` the footage is tracked backwards too (``toonmotion track --both-ways``);
  with ``"full_resolution": true`` footage larger than 1000 px is tracked at its own size, not
  halved (``toonmotion track --full-resolution``);
  with ``"background": [r, g, b]`` the joints are held to the figure drawn on that colour
  (``toonmotion track --background``; default null, the border's colour when flat). Reply
  ``{"type": "tracked", "first": n, "names": [...], "positions": [...], "confidence": [...]}``,
  joints in ``names``' order.
  ``{"type": "suggest", "background": [r, g, b] or null}`` suggests the joints on the footage's
  first frame again, on the figure drawn on that colour (``toonmotion track --background``; null:
  the border's colour when flat, as when the footage was sent). Reply ``{"type": "suggested",
  "joints": [{"name", "parent", "position", "size"}, ...]}``, as ``PUT /api/footage`` gives them.
  ``{"type": "retarget"}`` replays it on the character; reply
  ``{"type": "retargeted", "first": n, "last": m, "fps": f}``, whose frames a ``frame`` message
  with ``"source": "capture"`` gives.
* ``{"type": "open_drawing", "skeleton": "keep" | "new", "mask": bool}``: rig the drawing sent
  with ``PUT /api/uploads/drawing`` (and its mask, ``PUT /api/uploads/mask``, when ``mask``)
  into this project, keeping the skeleton or finding a new one (not while key-frames name the
  joints), off the event loop with progress messages; the project it replaces and the new one
  are kept under ``history/`` so undo brings the old drawing back. Reply ``{"type": "opened",
  "width": w, "height": h, "joints": n}``.
* ``{"type": "frame", "frame": n}``: the animation's frame ``n`` (clamped to the keys' span).
  Reply: ``{"type": "frame", "frame": n, "U": "...", "positions": [[x, y], ...]}``.
* ``{"type": "export", "format": "gif" | "mp4" | "png" | "apng" | "webp" | "webm" | "glb" |
  "spine" | "sheet", "name": "walk", "size": [w, h] | null, "background": [r, g, b] | null,
  "overlays": ["mesh", "skeleton", "rest"]}`` (the last three optional, as the CLI's ``--size``,
  ``--background`` and ``--overlay``; rigs, glb and spine, take none of them): export the
  key-frames' animation into the project folder's ``exports/`` (``walk.gif``, the folder
  ``walk/`` of PNG frames, ``walk.glb``, ``walk.spine.json`` with its ``.atlas`` and ``.png``,
  ``walk.sheet.json`` with its ``.png``; see :data:`EXPORT_FORMATS`), through the CLI's atomic
  writes. While it runs, progress messages ``{"type": "progress", "index": i, "count": n}`` carry
  the request's id; the reply is ``{"type": "exported", "file": "exports/walk.gif", "files":
  [...every file written], "frames": n, "size": [w, h] | null}``. The name is letters, digits,
  ``-`` and ``_``: a request never names a path.
* ``{"type": "cancel", "id": n}``: stop the slow request ``n`` (an export, a tracking, a drawing
  opened, suggestions) at its next progress step. Its reply is then ``{"id": n, "type":
  "error", "cancelled": true, "message": "cancelled: ..."}`` and nothing it would have saved is
  saved; a cancel has no reply of its own. Messages sent while a slow request runs are answered
  after it, in order.
"""

from __future__ import annotations

import functools
import json
import logging
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from toonmotion import api, limits
from toonmotion.animate.timeline import Timeline
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.deform.depth import draw_order
from toonmotion.deform.tuning import TuningEdit
from toonmotion.errors import (
    Cancelled,
    EditError,
    ExportError,
    FilterError,
    KeyframeError,
    MotionError,
    PoseError,
    ProjectError,
    SkeletonError,
    SketchError,
    ToonmotionError,
    TrackingError,
)
from toonmotion.io.atomic import write_text
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.links import confined, no_links
from toonmotion.io.motion_json import save_motion
from toonmotion.io.pose_json import edits_from_json, edits_to_json, load_keyframes, save_keyframes
from toonmotion.io.project import PROJECT_FILE
from toonmotion.render.frame import check_overlays
from toonmotion.rig.pose import Pose, check_pose
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import joint_suggestions
from toonmotion.web.history import History
from toonmotion.web.wire import encode_vertices

# The project folder's key-frames, in the format `toonmotion animate` reads.
KEYS_FILE = "keys.json"
# Where footage sent to the editor is kept, and the motion tracked in it, in the project folder.
FOOTAGE = "footage"
CAPTURED = "motions/captured.json"
# The upload area in the project folder: a new drawing, its mask, a skeleton file; and where the
# projects an opened drawing replaced are kept, to undo it.
UPLOADS = "uploads"
UPLOAD_PARTS = ("drawing", "mask", "skeleton")
SNAPSHOTS = "history"
# Where the editor's exports go, in the project folder; and what an export's name may be.
EXPORTS = "exports"
EXPORT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,63}")
# Each format's file name after the export's name: Spine's skeleton and a sprite sheet's atlas are
# both JSON, so they carry a second suffix (their .atlas and .png are written beside them).
EXPORT_FORMATS = {"gif": ".gif", "mp4": ".mp4", "png": "", "apng": ".apng", "webp": ".webp", "webm": ".webm",
                  "glb": ".glb", "spine": ".spine.json", "sheet": ".sheet.json"}
# The files an export may leave, which the editor serves for download, by suffix.
EXPORT_FILE = re.compile(r"(?P<stem>[A-Za-z0-9][A-Za-z0-9_-]{0,63})(?:\.spine|\.sheet)?"
                         r"\.(?P<suffix>gif|mp4|apng|webp|webm|glb|json|atlas|png)")
# A WebSocket message longer than this is refused unread (a pose of 10,000 joints fits easily).
MAX_MESSAGE_BYTES = 1_000_000

log = logging.getLogger("toonmotion.web")


def _deformer_for(character: api.Character) -> Deformer:
    """The editor's deformer: every drag is a solve, so it runs the compiled loop."""
    return Deformer(character, DeformSettings(compiled=True))


@dataclass
class Editing:
    """The open project, its key-frames and what is built once for them, shared by every client."""

    folder: Path
    character: api.Character
    timeline: Timeline | None = None
    lock: threading.RLock = field(default_factory=threading.RLock)
    _deformer: Deformer | None = None
    _animation: api.Animation | None = None
    _exaggerated: tuple[api.FilterSettings, api.Animation] | None = None
    footage: tuple[NDArray[np.uint8], float] | None = None  # frames and their rate
    capture: api.Capture | None = None
    captured: api.Animation | None = None  # the capture retargeted onto the character
    # What the Capture panel last showed, to show it again after a reload: the footage as
    # ``PUT /api/footage`` described it, the joints last tracked (with their rectangles) and the
    # ``tracked`` reply; None before footage is sent.
    capture_page: dict[str, Any] | None = None
    _history: History | None = None

    @property
    def history(self) -> History:
        """The undo history (:mod:`toonmotion.web.history`), read from the folder once."""
        with self.lock:
            if self._history is None:
                self._history = History.open(self.folder)
            return self._history

    @classmethod
    def open(cls, folder: str | Path) -> Editing:
        """The project in ``folder`` and its ``keys.json`` if it has one (errors name the file); a
        project holding a symbolic link is refused (:mod:`toonmotion.io.links`)."""
        folder = Path(folder)
        if folder.is_dir():
            no_links(folder)
        character = api.load_project(folder)
        keys = folder / KEYS_FILE
        timeline = load_keyframes(keys, character.skeleton) if keys.is_file() else None
        return cls(folder=folder, character=character, timeline=timeline)

    def check_links(self) -> None:
        """Refuse to go on while anything under the project is a symbolic link
        (:func:`~toonmotion.io.links.no_links`): once per request that touches files, since one
        may have been made since the last."""
        no_links(self.folder)

    def path(self, *parts: str) -> Path:
        """The project's file or folder ``parts``, to read, write or delete, once checked: no part
        of it is a symbolic link and it resolves inside the project (the request has called
        :meth:`check_links` first)."""
        return confined(self.folder, self.folder.joinpath(*parts))

    @property
    def deformer(self) -> Deformer:
        with self.lock:
            if self._deformer is None:
                self._deformer = _deformer_for(self.character)
            return self._deformer

    def prepare_deformer(self) -> None:
        """Build the deformer ahead of the first drag (the server does it in a thread at start).

        The build loads Numba and the compiled loop, about 1.6 s the first time in a process, so it
        runs outside the lock, and edits made meanwhile do not wait for it; it is kept only if the
        character has not changed since. A failure leaves it to be built on demand, where the
        error reaches the page as every other does.
        """
        with self.lock:
            character = self.character
            if self._deformer is not None:
                return
        try:
            deformer = _deformer_for(character)
        except Exception as error:  # said again, to the page, when a drag builds it
            log.debug("the deformer was not prepared: %s", error)
            return
        with self.lock:
            if self._deformer is None and self.character is character:
                self._deformer = deformer

    @property
    def animation(self) -> api.Animation:
        """Every frame of the key-frames, deformed (computed once per change of keys or regions)."""
        return self.animated(None)

    def animated(self, exaggeration: api.FilterSettings | None) -> api.Animation:
        """The key-frames' animation, through the cartoon filter when ``exaggeration`` is given
        (the last exaggerated one is kept, for scrubbing and playing it)."""
        with self.lock:
            if self.timeline is None:
                raise KeyframeError("there are no key-frames yet: set a key first")
            if exaggeration is not None:
                if self._exaggerated is None or self._exaggerated[0] != exaggeration:
                    found = api.animate_character(self.deformer, self.timeline, exaggeration=exaggeration)
                    self._exaggerated = (exaggeration, found)
                return self._exaggerated[1]
            if self._animation is None:
                self._animation = api.animate_character(self.deformer, self.timeline)
            return self._animation

    def edited(self, character: api.Character) -> None:
        """Save ``character`` in the project, then make it the one edited (a failed save changes nothing)."""
        with self.lock:
            api.save_project(self.folder, character)
            self.character, self._deformer, self._animation, self._exaggerated = character, None, None, None

    def keys_text(self) -> str | None:
        """The key-frames file as saved, or None when there are no keys."""
        file = self.path(KEYS_FILE)
        return file.read_text(encoding="utf-8") if file.is_file() else None

    def restore_keys(self, text: str | None) -> None:
        """Put back the key-frames file ``text`` (None: no keys) as it was saved."""
        with self.lock:
            file = self.path(KEYS_FILE)
            if text is None:
                file.unlink(missing_ok=True)
                timeline = None
            else:
                write_text(file, text)
                timeline = load_keyframes(file, self.character.skeleton)
            self.timeline, self._animation, self._exaggerated = timeline, None, None

    def keyed(self, timeline: Timeline | None) -> None:
        """Save the key-frames (none: the file goes), then make them the ones edited."""
        with self.lock:
            file = self.path(KEYS_FILE)
            if timeline is None:
                file.unlink(missing_ok=True)
            else:
                save_keyframes(file, self.character.skeleton, timeline)
            self.timeline, self._animation, self._exaggerated = timeline, None, None


def describe(editing: Editing) -> dict[str, Any]:
    """The project as the page draws it: size, rest mesh, skeleton, regions and key-frames."""
    character = editing.character
    mesh, skeleton = character.mesh, character.skeleton
    return {
        "name": editing.folder.name,
        "width": character.size[0],
        "height": character.size[1],
        "vertices": mesh.V.ravel().tolist(),
        "joints": [{"name": n, "parent": int(p), "position": skeleton.positions[i].tolist()}
                   for i, (n, p) in enumerate(zip(skeleton.names, skeleton.parents, strict=True))],
        "bones": list(skeleton.bone_names),
        # The curve skeleton (every 3rd pixel of each branch) and the joints it suggests, to place
        # joints by (thesis 6.1).
        "curve_skeleton": [path[::3].round(1).tolist() + [path[-1].tolist()]
                           for path in character.curve_skeleton.paths],
        "suggestions": joint_suggestions(character.curve_skeleton)[0].round(1).tolist(),
        "outline": [loop.round(1).tolist() for loop in character.silhouette.loops],
        **regions(character),
        "keys": keys(editing.timeline),
        "history": editing.history.counts(),
        "capture": editing.capture_page,
    }


def regions(character: api.Character) -> dict[str, Any]:
    """The bone regions: the triangles in draw order (depth layers), each vertex's bone (an index
    into the bone names), each bone's depth, and how many edits there are to undo and redo."""
    order = draw_order(character.mesh, character.binding, character.depth)
    return {
        "triangles": character.mesh.F[order].ravel().tolist(),
        "vertex_bone": character.binding.bone.tolist(),
        # Vertices the decomposition could not place by the rule and attached by distance.
        "fallback": np.flatnonzero(character.binding.fallback).tolist(),
        "depth": character.depth.tolist(),
        "edits": len(character.edits),
        "undone": len(character.undone),
    }


def keys(timeline: Timeline | None) -> dict[str, Any] | None:
    """The key-frames: frame rate, easing, and each key's frame and joint positions."""
    if timeline is None:
        return None
    return {"fps": timeline.fps, "ease": timeline.ease,
            "keys": [{"frame": k.frame, "positions": k.pose.positions.tolist(),
                      "edits": edits_to_json(k.edits)} for k in timeline.keys]}


def answer(editing: Editing, text: str) -> dict[str, Any]:
    """The reply to one message (module docstring); errors are replies too."""
    ident: Any = None
    try:
        if len(text) > MAX_MESSAGE_BYTES:
            raise PoseError(f"a message may be {MAX_MESSAGE_BYTES:,} bytes at most, got {len(text):,}")
        try:
            message = json.loads(text)
        except (ValueError, RecursionError):
            raise PoseError("a message must be a JSON object") from None
        if not isinstance(message, dict):
            raise PoseError("a message must be a JSON object")
        ident = message.get("id")
        if not isinstance(ident, (int, str, type(None))) or isinstance(ident, bool):
            ident = None
        kind = message.get("type")
        if kind not in _HANDLERS:
            sent = ", ".join(map(repr, _HANDLERS))
            raise PoseError(f"unknown message type {kind!r}; the editor sends {sent}")
        if kind not in _IN_MEMORY:
            editing.check_links()  # a request that touches files: refused while the project holds a link
        return {"id": ident, **_HANDLERS[kind](editing, message)}
    except ToonmotionError as error:
        return {"id": ident, "type": "error", "message": one_line(str(error))}
    except Exception as error:  # a bug: one line to the page, the details to the log
        log.error("internal error answering a message: %s: %s", type(error).__name__, error)
        return {"id": ident, "type": "error", "message": bug(error)}


SlowHandler = Callable[[Editing, dict[str, Any], Callable[[int, int], None]], dict[str, Any]]
SlowReply = Callable[[Editing, str, Callable[[int, int], None]], dict[str, Any]]


def _off_loop(verb: str) -> Callable[[SlowHandler], SlowReply]:
    """A handler run off the event loop, given the message's text: its reply carries the id,
    and every failure is a one-line error reply (a file that cannot be written: "cannot
    {verb}: ..."; a bug: one line to the page, the details to the log)."""
    def wrap(handler: SlowHandler) -> SlowReply:
        @functools.wraps(handler)
        def run(editing: Editing, text: str, progress: Callable[[int, int], None]) -> dict[str, Any]:
            ident: Any = None
            try:
                message = json.loads(text)
                ident = message.get("id") if isinstance(message.get("id"), (int, str)) else None
                editing.check_links()  # it reads or writes files: refused while the project holds a link
                return {"id": ident, **handler(editing, message, progress)}
            except Cancelled:
                return {"id": ident, "type": "error", "cancelled": True,
                        "message": f"cancelled: did not {verb}; nothing saved before was changed"}
            except ToonmotionError as error:
                return {"id": ident, "type": "error", "message": one_line(str(error))}
            except OSError as error:
                return {"id": ident, "type": "error", "message": one_line(f"cannot {verb}: {error}")}
            except Exception as error:  # a bug
                log.error("internal error (%s): %s: %s", verb, type(error).__name__, error)
                return {"id": ident, "type": "error", "message": bug(error)}

        return run

    return wrap


@_off_loop("write the export")
def export(editing: Editing, message: dict[str, Any],
           progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to an export message (module docstring), calling ``progress(index, count)``.

    Meant to run off the server's event loop, once the loop has computed the animation
    (:attr:`Editing.animation`): this takes it and the character, which are immutable, and only
    renders and writes.
    """
    kind, name = message.get("format"), message.get("name")
    if kind not in EXPORT_FORMATS:
        raise KeyframeError(f"'format' must be {', '.join(EXPORT_FORMATS)}; got {str(kind)[:20]!r}")
    if not isinstance(name, str) or not EXPORT_NAME.fullmatch(name):
        raise KeyframeError("'name' must be 1 to 64 letters, digits, - or _, not starting with - or _")
    with editing.lock:
        character, animation = editing.character, editing.animated(exaggeration_of(message))
    relative = f"{EXPORTS}/{name}{EXPORT_FORMATS[kind]}"
    target = editing.path(EXPORTS, f"{name}{EXPORT_FORMATS[kind]}")
    overlays = check_overlays(_names(message.get("overlays", [])))
    size, background = _export_size(message.get("size")), _export_background(message.get("background"))

    def report(stage: str, index: int, total: int) -> None:
        progress(index, total)

    if overlays and kind in ("gif", "mp4", "png"):
        count, out_size = api.write_animation(target, character, animation, size=size,
                                              background=background, overlays=overlays, progress=report)
        return {"type": "exported", "file": relative, "files": [relative], "frames": count,
                "size": list(out_size)}
    if overlays:
        raise KeyframeError("overlays are drawn on GIF, MP4 and PNG frames only")
    done = api.export_animation(target, character, animation, format=kind,
                                settings=editing.deformer.settings, size=size, background=background,
                                progress=report)
    files = [f"{EXPORTS}/{path.name}" for path in done.files]
    return {"type": "exported", "file": relative, "files": files, "frames": done.frames,
            "size": None if done.size is None else list(done.size)}


@_off_loop("open the drawing")
def open_drawing(editing: Editing, message: dict[str, Any],
                 progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to an ``open_drawing`` message (module docstring), calling ``progress(index,
    count)`` through the rigging stages; meant to run off the server's event loop."""
    uploads = editing.path(UPLOADS)
    if not (uploads / "drawing").is_file():
        raise ProjectError("there is no drawing to open yet: send one first")
    keep, with_mask = message.get("skeleton", "keep"), message.get("mask", False)
    if keep not in ("keep", "new") or not isinstance(with_mask, bool):
        raise SkeletonError("'skeleton' must be \"keep\" or \"new\", and 'mask' true or false")
    if with_mask and not (uploads / "mask").is_file():
        raise ProjectError("there is no mask to use: send the mask first, "
                           "or open the drawing without one")
    with editing.lock:
        before = editing.character
    image = load_image(uploads / "drawing")
    skeleton = before.skeleton if keep == "keep" else None
    if skeleton is None and editing.timeline is not None:
        raise SkeletonError("the key-frames name the joints: keep the skeleton, or delete the keys first")
    height, width = image.shape[:2]
    x, y = before.skeleton.positions.T
    if skeleton is not None and (x.min() < 0 or y.min() < 0 or x.max() > width or y.max() > height):
        raise SkeletonError(f"this skeleton does not fit the new {width}x{height} drawing: "
                            "find a new skeleton for it, or load one made for it")
    try:
        character = api.rig_image(image, mask=load_mask(uploads / "mask", size=(width, height))
                                  if with_mask else None, skeleton=skeleton, settings=before.settings,
                                  progress=lambda stage, index, total: progress(index, total))
    except SkeletonError as error:
        if skeleton is None:
            raise
        raise SkeletonError(f"the kept skeleton does not fit the new figure ({error}): find a new "
                            "skeleton, or load one made for it") from None
    if skeleton is not None:
        _check_on_figure(character)
    with editing.lock:
        snapshot = _snapshot_folder(editing)
        api.save_project(snapshot / "before", before)
        api.save_project(snapshot / "after", character)
        editing.edited(character)
        editing.history.record({"kind": "drawing", "before": f"{snapshot.name}/before",
                                "after": f"{snapshot.name}/after", "says": "a new drawing opened"})
    return {"type": "opened", "width": character.size[0], "height": character.size[1],
            "joints": len(character.skeleton), "says": "a new drawing opened"}


def _check_on_figure(character: api.Character) -> None:
    """Refuse a kept skeleton whose joints lie off the new figure (beyond 3% of its size)."""
    away = distance_transform_edt(~character.mask)
    reach = max(4.0, 0.03 * float(np.hypot(*character.size)))
    rows = np.clip(np.rint(character.skeleton.positions[:, 1]).astype(int), 0, character.mask.shape[0] - 1)
    cols = np.clip(np.rint(character.skeleton.positions[:, 0]).astype(int), 0, character.mask.shape[1] - 1)
    off = np.flatnonzero(away[rows, cols] > reach)
    if len(off):
        names = ", ".join(character.skeleton.names[i] for i in off[:3])
        raise SkeletonError(f"{len(off)} of the skeleton's joints lie off the new figure ({names}"
                            f"{', ...' if len(off) > 3 else ''}): find a new skeleton, "
                            "or load one made for it")


def _snapshot_folder(editing: Editing) -> Path:
    """A new folder under the project's ``history/`` for the projects around one opened drawing."""
    root = editing.path(SNAPSHOTS)
    taken = {p.name for p in root.iterdir()} if root.is_dir() else set()
    n = 1
    while f"drawing-{n}" in taken:
        n += 1
    return root / f"drawing-{n}"


def _export_size(value: Any) -> tuple[int, int] | None:
    """An export's ``size``: null (the view at 1:1) or ``[width, height]`` in pixels."""
    if value is None:
        return None
    side = limits.current().canvas_side
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= side for v in value)):
        raise ExportError(f"'size' must be [width, height], whole pixels from 1 to {side:,}; "
                          f"got {str(value)[:40]}")
    return value[0], value[1]


def _export_background(value: Any) -> tuple[int, int, int] | None:
    """An export's ``background``: null (transparent; white behind a GIF or an MP4) or ``[r, g, b]``."""
    return _colour(value, ExportError)


def _colour(value: Any, error: type[ToonmotionError]) -> tuple[int, int, int] | None:
    """A message's ``background``: null or ``[r, g, b]``; else an ``error``."""
    if value is None:
        return None
    if not (isinstance(value, list) and len(value) == 3
            and all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 255 for v in value)):
        raise error(f"'background' must be null or [r, g, b], each 0 to 255; got {str(value)[:40]}")
    return value[0], value[1], value[2]


def _names(value: Any) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ExportError("'overlays' must list overlay names")
    return value


@_off_loop("track the footage")
def track(editing: Editing, message: dict[str, Any],
          progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to a ``track`` message (module docstring), calling ``progress(index, count)``;
    meant to run off the server's event loop, like :func:`export`."""
    if editing.footage is None:
        raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
    frames, fps = editing.footage
    joints = message.get("joints")
    if not isinstance(joints, list) or not joints:
        raise TrackingError("'joints' must list the joints to track, each with its rectangle's 'size'")
    skeleton = _skeleton(joints)
    sizes = np.array([_point(j.get("size"), f"the size of joint {j['name']!r}") for j in joints], dtype=float)
    order = [next(i for i, j in enumerate(joints) if j["name"] == name) for name in skeleton.names]
    earlier, at, corrections = None, None, None
    if message.get("at") is not None:  # a correction: the earlier tracking is kept before it
        if editing.capture is None:
            raise TrackingError("there is no earlier tracking to correct: track first")
        earlier, at, moved = editing.capture.motion, _frame(message, "at"), message.get("set")
        if not isinstance(moved, dict) or not moved:
            raise TrackingError("'set' must give the corrected joints, name to [x, y]")
        corrections = {str(name): _point(xy, f"joint {name!r}") for name, xy in moved.items()}
    flags = ("free", "frame_by_frame", "both_ways", "full_resolution")
    how = {name: message.get(name, False) for name in flags}
    for name, value in how.items():
        if not isinstance(value, bool):
            raise TrackingError(f"'{name}' must be true or false, got {value!r}")
    settings = api.TrackSettings(figure=not how["free"], best_path=not how["frame_by_frame"],
                                 both_ways=how["both_ways"])
    if how["full_resolution"]:
        settings = replace(settings, working_side=None)
    background = _colour(message.get("background"), TrackingError)
    capture = api.track_footage(frames, joints=(skeleton, sizes[order]), fps=fps, earlier=earlier,
                                corrections=corrections, at=at, settings=settings, background=background,
                                progress=lambda stage, index, total: progress(index, total))
    save_motion(editing.path(*CAPTURED.split("/")), capture.motion)
    confidence = capture.motion.confidence
    assert confidence is not None  # tracking always says how sure it is
    # What may have gone wrong from the start (rectangles too small, joints on one another).
    notes = [] if at is not None else api.setup_warnings(frames, skeleton, sizes[order], colour=background)
    reply = {"type": "tracked", "first": capture.first, "names": list(skeleton.names), "notes": notes,
             "positions": np.round(capture.motion.positions, 2).tolist(),
             "confidence": np.round(confidence, 3).tolist(),
             "poorly": [{"name": joint.name, "fraction": round(joint.fraction, 3), "start": joint.start,
                         "length": joint.length} for joint in capture.poorly_matched()]}
    with editing.lock:
        editing.capture, editing.captured = capture, None
        if editing.capture_page is not None:
            editing.capture_page = {**editing.capture_page, "joints": joints, "tracked": reply}
    return reply


@_off_loop("suggest the joints")
def suggest(editing: Editing, message: dict[str, Any],
            progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to a ``suggest`` message (module docstring); off the event loop, like
    :func:`track` (the figure of a sequence without a flat border is found over every frame)."""
    if editing.footage is None:
        raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
    background = _colour(message.get("background"), TrackingError)
    skeleton, sizes = api.suggest_joints(editing.footage[0], colour=background)
    return {"type": "suggested", "joints": suggested_joints(skeleton, sizes)}


def suggested_joints(skeleton: Skeleton, sizes: NDArray[np.float64]) -> list[dict[str, Any]]:
    """Joints suggested on footage, for the page: name, parent (a name or null), position and
    rectangle size."""
    return [{"name": n, "parent": None if p < 0 else skeleton.names[p],
             "position": skeleton.positions[i].tolist(), "size": sizes[i].tolist()}
            for i, (n, p) in enumerate(zip(skeleton.names, skeleton.parents, strict=True))]


def bug(error: Exception) -> str:
    return f"internal error ({type(error).__name__}); this is a bug in toonmotion, please report it"


def one_line(text: str) -> str:
    return " ".join(text.split())[:400]


# --- handlers: (editing, message) -> the reply's fields -------------------------------------------


def _pose(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    if message.get("accel") is None:
        U = _posed(editing, message.get("positions"), _tuning(message))
        return {"type": "mesh", "U": encode_vertices(U)}
    fixed = message.get("fixed")
    if not isinstance(fixed, list) or not all(isinstance(name, str) for name in fixed):
        raise FilterError("'fixed' must list the names of the joints that stay put")
    pose = Pose(_positions(editing, message.get("positions")))
    frame = api.pose_character(editing.deformer, pose, accel=_point(message.get("accel"), "'accel'"),
                               fixed=fixed)
    return {"type": "mesh", "U": encode_vertices(frame.deformation.U),
            "positions": frame.pose.positions.tolist()}


def _drag(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    joint, mode, pinned = message.get("joint"), message.get("mode", "turn"), message.get("pinned", [])
    if not isinstance(joint, str):
        raise PoseError("'joint' must name the joint dragged")
    if not isinstance(mode, str):
        raise PoseError("'mode' must be turn, reach or stretch")
    if not isinstance(pinned, list) or not all(isinstance(name, str) for name in pinned):
        raise PoseError("'pinned' must list the names of the pinned joints")
    start = Pose(_positions(editing, message.get("positions")))
    pose = api.drag_joint(editing.character, start, joint, _point(message.get("to"), "'to'"), mode=mode,
                          pinned=pinned)
    U = api.pose_character(editing.deformer, pose, edits=_tuning(message)).deformation.U
    return {"type": "mesh", "U": encode_vertices(U), "positions": pose.positions.tolist()}


def _sketch(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    strokes = message.get("strokes")
    if not isinstance(strokes, list) or not all(isinstance(stroke, list) for stroke in strokes):
        raise SketchError("'strokes' must be a list of strokes, each a list of [x, y] points")
    lines = [[_point(p, "a stroke's point") for p in stroke] for stroke in strokes]
    current = Pose(_positions(editing, message.get("positions")))
    found = api.sketch_pose(editing.character, lines, pose=current)
    U = api.pose_character(editing.deformer, found.pose).deformation.U
    return {"type": "sketched", "positions": found.pose.positions.tolist(), "bones": list(found.bones),
            "elsewhere": found.elsewhere, "U": encode_vertices(U)}


def _overlaps(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    found = api.same_depth_overlaps(editing.character, [(0, _posed(editing, message.get("positions")))])
    pairs = [{"a": o.bone_a, "b": o.bone_b, "area": round(o.area, 1)} for o in found]
    return {"type": "overlaps", "pairs": pairs}


def _region_edit(change: Callable[[api.Character, dict[str, Any]], api.Character],
                 says: Callable[[dict[str, Any]], str]) -> Handler:
    """A region edit's handler; ``says`` tells what a message did, for undo and the other pages."""
    def handle(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
        with editing.lock:
            editing.edited(change(editing.character, message))
            told = says(message)
            editing.history.record({"kind": "regions", "count": len(editing.character.edits), "says": told})
            return {"type": "regions", **regions(editing.character), "history": editing.history.counts(),
                    "says": told}

    return handle


def _depth(character: api.Character, message: dict[str, Any]) -> api.Character:
    by = message.get("by")
    if by not in (-1, 1) or isinstance(by, bool):
        raise EditError("'by' must be 1 (one layer up) or -1 (one down)")
    return api.set_depth(character, 0, at=_point(message.get("at"), "'at'"), by=by)


def _correct(character: api.Character, message: dict[str, Any]) -> api.Character:
    bone, curve = message.get("bone"), message.get("curve")
    if not isinstance(bone, str):
        raise EditError("'bone' must name the bone to attach to")
    if not isinstance(curve, list) or not 3 <= len(curve) <= 10_000:
        raise EditError("'curve' must be a closed curve of 3 to 10,000 [x, y] points")
    return api.correct_regions(character, bone, [_point(p, "a curve point") for p in curve])


def _key_edit(change: Callable[[Editing, dict[str, Any]], Timeline | None],
              says: Callable[[dict[str, Any]], str]) -> Handler:
    """A key edit's handler; ``says`` tells what a message did, for undo and the other pages."""
    def handle(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
        with editing.lock:
            before = editing.keys_text()
            editing.keyed(change(editing, message))
            after = editing.keys_text()
            told = says(message)
            if after != before:  # an edit that changed nothing is no step to undo
                editing.history.record({"kind": "keys", "before": before, "after": after, "says": told})
            return {"type": "keys", "keys": keys(editing.timeline), "history": editing.history.counts(),
                    "says": told}

    return handle


def _skeleton(joints: Any) -> Skeleton:
    """A skeleton from ``[{"name", "parent", "position"}, ...]``."""
    if not isinstance(joints, list) or not joints:
        raise SkeletonError("'joints' must list the skeleton's joints")
    triples = []
    for n, joint in enumerate(joints, start=1):
        if not isinstance(joint, dict) or not isinstance(joint.get("name"), str) \
                or not isinstance(joint.get("parent"), (str, type(None))):
            raise SkeletonError(f"joint {n} needs a 'name', a 'parent' (a name or null) and a 'position'")
        position = _point(joint.get("position"), f"joint {n}'s position")
        triples.append((joint["name"], joint["parent"], position))
    return Skeleton.from_joints(triples)


def _retarget(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    if editing.capture is None:
        raise MotionError("there is no tracked motion yet: track the footage first")
    motion = api.retarget(editing.capture.motion, editing.character.skeleton)
    with editing.lock:
        editing.captured = api.animate_character(editing.deformer, motion)
    frames = [frame for frame, _ in editing.captured.meshes]
    return {"type": "retargeted", "first": frames[0], "last": frames[-1], "fps": motion.fps}


def _rig(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    skeleton = _skeleton(message.get("joints"))
    with editing.lock:
        if editing.timeline is not None and set(skeleton.names) != set(editing.character.skeleton.names):
            raise SkeletonError("the key-frames name the joints: keep their names, or delete the keys first")
        before, keys_before = _joints(editing.character.skeleton), editing.keys_text()
        character, skipped = api.rig_again(editing.character, skeleton)
        # The keys follow the joints moved: a key of the rest pose stays the rest pose (checked
        # before anything is saved).
        carried = None if editing.timeline is None else api.carry_keys(
            editing.character.skeleton, character.skeleton, editing.timeline)
        editing.edited(character)
        if carried is not None:
            editing.keyed(carried)
        editing.history.record({"kind": "rig", "before": before, "after": _joints(character.skeleton),
                                "keys_before": keys_before, "keys_after": editing.keys_text(),
                                "says": "the drawing rigged again"})
    return {"type": "rigged", "skipped": len(skipped), "says": "the drawing rigged again"}


def _joints(skeleton: Skeleton) -> list[list[Any]]:
    return [[name, parent, list(xy)] for name, parent, xy in skeleton.joints()]


def _step(editing: Editing, *, undo: bool) -> dict[str, Any]:
    """Undo (or redo) the newest edit of any kind (:mod:`toonmotion.web.history`)."""
    with editing.lock:
        history = editing.history
        stack = history.done if undo else history.undone
        says: str | None  # what the step takes back or makes again
        if not stack:  # region edits made outside the editor are still in the project's history
            if not undo:
                raise EditError("there is nothing to redo")
            if not editing.character.edits:
                raise EditError("there are no edits to undo")
            editing.edited(api.undo_edits(editing.character))
            kind, says = "regions", "a region edit made outside the editor"
        else:
            entry = stack[-1]
            kind, says = entry["kind"], entry.get("says")
            if kind == "regions":
                count = len(editing.character.edits)
                if undo and count > entry["count"]:  # edits the history missed (a kill, the CLI) go first
                    editing.edited(api.undo_edits(editing.character))
                    return {"type": "undone", "kind": kind, **regions(editing.character),
                            "keys": keys(editing.timeline), "history": history.counts(),
                            "says": "a region edit made outside the editor"}
                if count != (entry["count"] if undo else entry["count"] - 1):
                    _stale(history)
                step = api.undo_edits if undo else api.redo_edits
                editing.edited(step(editing.character))
            elif kind == "keys":
                now, then = (entry["after"], entry["before"]) if undo else (entry["before"], entry["after"])
                if editing.keys_text() != now:
                    _stale(history)
                editing.restore_keys(then)
            elif kind == "drawing":
                now, then = (entry["after"], entry["before"]) if undo else (entry["before"], entry["after"])
                snapshots = editing.path(SNAPSHOTS)
                saved = editing.path(PROJECT_FILE).read_text(encoding="utf-8")
                if saved != (snapshots / now / PROJECT_FILE).read_text(encoding="utf-8"):
                    _stale(history)
                editing.edited(api.load_project(snapshots / then))
            else:
                now, then = (entry["after"], entry["before"]) if undo else (entry["before"], entry["after"])
                keys_now, keys_then = ((entry.get("keys_after"), entry.get("keys_before")) if undo
                                       else (entry.get("keys_before"), entry.get("keys_after")))
                carries_keys = "keys_before" in entry  # a rig step saved before the keys followed has not
                keys_changed = carries_keys and editing.keys_text() != keys_now
                if _joints(editing.character.skeleton) != now or keys_changed:
                    _stale(history)
                skeleton = Skeleton.from_joints((name, parent, xy) for name, parent, xy in then)
                editing.edited(api.rig_again(editing.character, skeleton)[0])
                if carries_keys:
                    editing.restore_keys(keys_then)
            history.moved(entry, undo=undo)
        return {"type": "undone" if undo else "redone", "kind": kind, **regions(editing.character),
                "keys": keys(editing.timeline), "history": history.counts(),
                "says": says or _EDIT_KINDS.get(kind, "an edit")}


def _stale(history: History) -> None:
    history.clear()
    raise EditError("the undo history no longer matches the project (it was changed outside the "
                    "editor), so it is cleared; the project is as it was")


def _set_key(editing: Editing, message: dict[str, Any]) -> Timeline | None:
    frame = _frame(message, "frame")
    pose = Pose(_positions(editing, message.get("positions")))
    edits = _tuning(message) if "edits" in message else None
    return api.set_key(editing.character.skeleton, editing.timeline, frame, pose, edits=edits)


def _timing(editing: Editing, message: dict[str, Any]) -> Timeline | None:
    timeline = _timeline(editing)
    fps, ease = message.get("fps", timeline.fps), message.get("ease", timeline.ease)
    if isinstance(fps, bool) or not isinstance(fps, (int, float)):
        raise KeyframeError(f"'fps' must be a number of frames per second, got {str(fps)[:20]}")
    return api.retime(editing.character.skeleton, timeline, fps=fps, ease=ease)


def _delete_key(editing: Editing, message: dict[str, Any]) -> Timeline | None:
    return api.delete_key(editing.character.skeleton, _timeline(editing), _frame(message, "frame"))


def _move_key(editing: Editing, message: dict[str, Any]) -> Timeline | None:
    return api.move_key(editing.character.skeleton, _timeline(editing), _frame(message, "frame"),
                        _frame(message, "to"))


def exaggeration_of(message: dict[str, Any]) -> api.FilterSettings | None:
    """The cartoon filter a message asks for (``strength``, ``sigma``), or None."""
    strength = message.get("strength")
    if strength is None or strength == 0:
        return None
    return api.FilterSettings(strength=strength, sigma=message.get("sigma", 3.0))


def _frame_of_animation(editing: Editing, message: dict[str, Any]) -> dict[str, Any]:
    if message.get("source") == "capture":
        if editing.captured is None:
            raise MotionError("nothing is retargeted yet: track footage, then retarget it")
        animation = editing.captured
    else:
        animation = editing.animated(exaggeration_of(message))
    frames = [frame for frame, _ in animation.meshes]
    at = min(max(_frame(message, "frame"), frames[0]), frames[-1])
    index = frames.index(at)
    U = animation.meshes[index][1]
    return {"type": "frame", "frame": at, "U": encode_vertices(U),
            "positions": animation.motion.positions[index].tolist()}


Handler = Callable[[Editing, dict[str, Any]], dict[str, Any]]

# What an undo of each kind of edit says when its entry does not (one recorded before it did).
_EDIT_KINDS = {"regions": "a region edit", "keys": "a key-frame edit", "rig": "a rigging",
               "drawing": "a new drawing opened"}

# Messages answered from memory alone (a drag is one), which need no check of the project's files.
_IN_MEMORY = frozenset({"pose", "drag", "sketch", "overlaps", "frame"})

_HANDLERS: dict[str, Handler] = {
    "pose": _pose,
    "drag": _drag,
    "sketch": _sketch,
    "overlaps": _overlaps,
    "depth": _region_edit(_depth, lambda m: "a region brought forward" if m.get("by") == 1
                          else "a region sent back"),
    "correct": _region_edit(_correct, lambda m: f"vertices lassoed to {m.get('bone')}"),
    "undo": lambda editing, message: _step(editing, undo=True),
    "redo": lambda editing, message: _step(editing, undo=False),
    "set_key": _key_edit(_set_key, lambda m: f"the key at frame {m.get('frame')} set"),
    "delete_key": _key_edit(_delete_key, lambda m: f"the key at frame {m.get('frame')} deleted"),
    "move_key": _key_edit(_move_key, lambda m: f"the key at frame {m.get('frame')} moved to {m.get('to')}"),
    "timing": _key_edit(_timing, lambda m: "the key-frames' rate and easing changed"),
    "frame": _frame_of_animation,
    "rig": _rig,
    "retarget": _retarget,
}


# --- reading a message's fields -------------------------------------------------------------------


def _point(value: Any, what: str) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2 and all(_is_number(v) for v in value)):
        raise EditError(f"{what} must be [x, y], got {str(value)[:40]}")
    return float(value[0]), float(value[1])


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _frame(message: dict[str, Any], name: str) -> int:
    value = message.get(name)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 2**31 - 1:
        raise KeyframeError(f"'{name}' must be a frame number, a whole number >= 0, got {str(value)[:40]}")
    return value


def _timeline(editing: Editing) -> Timeline:
    if editing.timeline is None:
        raise KeyframeError("there are no key-frames yet: set a key first")
    return editing.timeline


def _positions(editing: Editing, positions: Any) -> NDArray[np.float64]:
    skeleton = editing.character.skeleton
    if not isinstance(positions, list) or len(positions) != len(skeleton):
        raise PoseError(f"'positions' must list [x, y] for each of the {len(skeleton)} joints")
    try:
        array = np.array(positions, dtype=float)
    except (TypeError, ValueError):
        raise PoseError("'positions' must be [x, y] pairs of numbers") from None
    if array.shape != (len(skeleton), 2):
        raise PoseError("'positions' must be [x, y] pairs of numbers")
    return check_pose(skeleton, Pose(array)).positions


def _posed(editing: Editing, positions: Any, edits: tuple[TuningEdit, ...] = ()) -> NDArray[np.float64]:
    pose = Pose(_positions(editing, positions))
    return api.pose_character(editing.deformer, pose, edits=edits).deformation.U


def _tuning(message: dict[str, Any]) -> tuple[TuningEdit, ...]:
    """A message's fine-tuning ``edits``, in the key-frames file's form (none when absent)."""
    edits = message.get("edits")
    return () if edits is None else edits_from_json(edits, where="'edits'")
