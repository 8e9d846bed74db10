"""The open project in the editor, and the replies to the WebSocket messages that read and change it.

The messages, their fields and their replies are listed in :mod:`toonmotion.web.messages`, whose
models check every field before a handler here sees it. A handler answers from memory (a drag)
or changes the project (a key set, a region edited), saving it before the reply with the CLI's
atomic writes and recording the change for undo (:mod:`toonmotion.web.history`); the slow ones
(an export, a tracking, a drawing opened, joints suggested) run off the server's event loop with
progress messages (:func:`_off_loop`). Every failure is a one-line error reply.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion import api
from toonmotion.animate.timeline import Timeline
from toonmotion.deform.depth import draw_order
from toonmotion.deform.tuning import TuningEdit
from toonmotion.errors import (
    EditError,
    FilterError,
    KeyframeError,
    MessageError,
    MotionError,
    PoseError,
    SkeletonError,
    ToonmotionError,
)
from toonmotion.io.pose_json import edits_from_json, edits_to_json
from toonmotion.io.project import PROJECT_FILE
from toonmotion.rig.pose import Pose, check_pose
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import joint_suggestions
from toonmotion.web import messages
from toonmotion.web.editing import SNAPSHOTS, Editing
from toonmotion.web.history import History
from toonmotion.web.keyshape_requests import HANDLERS as KEYSHAPE_HANDLERS
from toonmotion.web.keyshape_requests import keyshaped
from toonmotion.web.messages import bug, one_line, skeleton_of
from toonmotion.web.proxy_requests import PROXY_HANDLERS, scene_summary
from toonmotion.web.wire import encode_vertices


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
        "scene": scene_summary(editing),
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


log = logging.getLogger("toonmotion.web")


def answer(editing: Editing, text: str) -> dict[str, Any]:
    """The reply to one message (:mod:`toonmotion.web.messages`); errors are replies too."""
    ident: Any = None
    try:
        raw = messages.parse(text)
        ident = messages.ident(raw)
        message = messages.read(raw)
        if message.type not in _HANDLERS:  # a slow one's, or a cancel of a request answered already
            raise MessageError(f"a {message.type!r} message is answered off the event loop, not here")
        if message.type not in _IN_MEMORY:
            editing.check_links()  # a request that touches files: refused while the project holds a link
        return {"id": ident, **_HANDLERS[message.type](editing, message)}
    except ToonmotionError as error:
        return {"id": ident, "type": "error", "message": one_line(str(error))}
    except Exception as error:  # a bug: one line to the page, the details to the log
        log.error("internal error answering a message: %s: %s", type(error).__name__, error)
        return {"id": ident, "type": "error", "message": bug(error)}


# --- handlers: (editing, message) -> the reply's fields -------------------------------------------


def _pose(editing: Editing, message: messages.Pose) -> dict[str, Any]:
    if message.accel is None:
        U = _posed(editing, message.positions, _tuning(message.edits))
        return {"type": "mesh", "U": encode_vertices(U)}
    if message.fixed is None:
        raise FilterError("'fixed' must list the names of the joints that stay put")
    pose = Pose(_positions(editing, message.positions))
    frame = api.pose_character(editing.deformer, pose, accel=message.accel, fixed=message.fixed)
    return {"type": "mesh", "U": encode_vertices(frame.deformation.U),
            "positions": frame.pose.positions.tolist()}


def _drag(editing: Editing, message: messages.Drag) -> dict[str, Any]:
    start = Pose(_positions(editing, message.positions))
    pose = api.drag_joint(editing.character, start, message.joint, message.to, mode=message.mode,
                          pinned=message.pinned)
    U = api.pose_character(editing.deformer, pose, edits=_tuning(message.edits)).deformation.U
    return {"type": "mesh", "U": encode_vertices(U), "positions": pose.positions.tolist()}


def _sketch(editing: Editing, message: messages.Sketch) -> dict[str, Any]:
    current = Pose(_positions(editing, message.positions))
    found = api.sketch_pose(editing.character, [list(stroke) for stroke in message.strokes], pose=current)
    U = api.pose_character(editing.deformer, found.pose).deformation.U
    return {"type": "sketched", "positions": found.pose.positions.tolist(), "bones": list(found.bones),
            "elsewhere": found.elsewhere, "U": encode_vertices(U)}


def _overlaps(editing: Editing, message: messages.Overlaps) -> dict[str, Any]:
    found = api.same_depth_overlaps(editing.character, [(0, _posed(editing, message.positions))])
    pairs = [{"a": o.bone_a, "b": o.bone_b, "area": round(o.area, 1)} for o in found]
    return {"type": "overlaps", "pairs": pairs}


def _region_edit(change: Callable[[api.Character, Any], api.Character],
                 says: Callable[[Any], str]) -> Handler:
    """A region edit's handler; ``says`` tells what a message did, for undo and the other pages."""
    def handle(editing: Editing, message: Any) -> dict[str, Any]:
        with editing.lock:
            editing.edited(change(editing.character, message))
            told = says(message)
            editing.history.record({"kind": "regions", "count": len(editing.character.edits), "says": told})
            return {"type": "regions", **regions(editing.character), "history": editing.history.counts(),
                    "says": told}

    return handle


def _depth(character: api.Character, message: messages.Depth) -> api.Character:
    return api.set_depth(character, 0, at=message.at, by=message.by)


def _correct(character: api.Character, message: messages.Correct) -> api.Character:
    return api.correct_regions(character, message.bone, list(message.curve))


def _key_edit(change: Callable[[Editing, Any], Timeline | None], says: Callable[[Any], str]) -> Handler:
    """A key edit's handler; ``says`` tells what a message did, for undo and the other pages."""
    def handle(editing: Editing, message: Any) -> dict[str, Any]:
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


def _retarget(editing: Editing, message: messages.Message) -> dict[str, Any]:
    if editing.capture is None:
        raise MotionError("there is no tracked motion yet: track the footage first")
    motion = api.retarget(editing.capture.motion, editing.character.skeleton)
    with editing.lock:
        editing.captured = api.animate_character(editing.deformer, motion)
    frames = [frame for frame, _ in editing.captured.meshes]
    return {"type": "retargeted", "first": frames[0], "last": frames[-1], "fps": motion.fps}


def _rig(editing: Editing, message: messages.Rig) -> dict[str, Any]:
    skeleton = skeleton_of(message.joints)
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


def _set_key(editing: Editing, message: messages.SetKey) -> Timeline | None:
    pose = Pose(_positions(editing, message.positions))
    edits = _tuning(message.edits) if "edits" in message.model_fields_set else None
    return api.set_key(editing.character.skeleton, editing.timeline, message.frame, pose, edits=edits)


def _timing(editing: Editing, message: messages.Timing) -> Timeline | None:
    timeline = _timeline(editing)
    fps = timeline.fps if message.fps is None else message.fps
    ease = timeline.ease if message.ease is None else message.ease
    return api.retime(editing.character.skeleton, timeline, fps=fps, ease=ease)


def _delete_key(editing: Editing, message: messages.DeleteKey) -> Timeline | None:
    return api.delete_key(editing.character.skeleton, _timeline(editing), message.frame)


def _move_key(editing: Editing, message: messages.MoveKey) -> Timeline | None:
    return api.move_key(editing.character.skeleton, _timeline(editing), message.frame, message.to)


def _frame_of_animation(editing: Editing, message: messages.ShowFrame) -> dict[str, Any]:
    if message.source == "capture":
        if editing.captured is None:
            raise MotionError("nothing is retargeted yet: track footage, then retarget it")
        animation = editing.captured
    elif message.source == "keyshapes":
        animation = keyshaped(editing)
    else:
        animation = editing.animated(message.exaggeration())
    frames = [frame for frame, _ in animation.meshes]
    at = min(max(message.frame, frames[0]), frames[-1])
    index = frames.index(at)
    U = animation.meshes[index][1]
    return {"type": "frame", "frame": at, "U": encode_vertices(U),
            "positions": animation.motion.positions[index].tolist()}


Handler = Callable[[Editing, Any], dict[str, Any]]

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
    "depth": _region_edit(_depth, lambda m: "a region brought forward" if m.by == 1
                          else "a region sent back"),
    "correct": _region_edit(_correct, lambda m: f"vertices lassoed to {m.bone}"),
    "undo": lambda editing, message: _step(editing, undo=True),
    "redo": lambda editing, message: _step(editing, undo=False),
    "set_key": _key_edit(_set_key, lambda m: f"the key at frame {m.frame} set"),
    "delete_key": _key_edit(_delete_key, lambda m: f"the key at frame {m.frame} deleted"),
    "move_key": _key_edit(_move_key, lambda m: f"the key at frame {m.frame} moved to {m.to}"),
    "timing": _key_edit(_timing, lambda m: "the key-frames' rate and easing changed"),
    "frame": _frame_of_animation,
    "rig": _rig,
    "retarget": _retarget,
    **PROXY_HANDLERS,
    **KEYSHAPE_HANDLERS,
}


# --- a message's fields against the project -----------------------------------------------------


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


def _tuning(edits: list[Any] | None) -> tuple[TuningEdit, ...]:
    """A message's fine-tuning ``edits``, in the key-frames file's form (none when absent)."""
    return () if edits is None else edits_from_json(edits, where="'edits'")
