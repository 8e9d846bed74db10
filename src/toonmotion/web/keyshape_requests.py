"""The Key-shapes panel's replies (:mod:`toonmotion.web.keyshape_messages`): key-shape models, contour
and video capture, and retargeting onto the character's key poses, with the calls the CLI's
``keyshapes``, ``capture-contours``, ``capture-video`` and ``retarget-keyshapes`` make.

Everything is kept in the project folder's ``keyshapes/`` (:data:`KEYSHAPES`), in the files those
commands read and write, so that a reload or a restart finds it again (the ``keyshapes`` message):

* ``outlines.json``: the key outlines as given (a contours file; drawn ones are not in
  correspondence), and ``model.json``, the model built from them (``toonmotion keyshapes
  outlines.json --points N``), with its in-between sheet ``sheet.png``;
* ``contours.json``: contours sent to capture; ``motion.json``: the captured key-shape motion
  (with the hand-picked keys, as ``capture-contours --keys`` writes it); ``captured.json``: the
  shape of every frame captured (``capture-video``'s output, or the model's fit of the contours);
* ``poses.json``: the Timeline's key poses retargeted onto, one per key-shape (a key-frames file),
  and ``retargeted.json``, the motion ``retarget-keyshapes motion.json model.json --project PROJECT
  --poses poses.json`` writes, which ``toonmotion animate PROJECT retargeted.json`` renders;
* ``panel.json``: what the panel was given besides (points, key frames, the footage captured).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion import api
from toonmotion.errors import KeyframeError, KeyShapeError, MotionError, TrackingError
from toonmotion.io.atomic import atomic_path, write_text
from toonmotion.io.frames import load_frames
from toonmotion.io.image import save_png
from toonmotion.io.keyshape_json import (
    load_contours,
    load_keymotion,
    load_model,
    save_contours,
    save_keymotion,
    save_model,
)
from toonmotion.io.motion_json import load_motion, save_motion
from toonmotion.io.pose_json import save_keyframes
from toonmotion.rig.pose import Pose
from toonmotion.web import keyshape_messages as km
from toonmotion.web.editing import FOOTAGE, Editing
from toonmotion.web.slow_requests import off_loop

KEYSHAPES = "keyshapes"
OUTLINES, MODEL, SHEET, CONTOURS = "outlines.json", "model.json", "sheet.png", "contours.json"
MOTION, CAPTURED, POSES, RETARGETED, PANEL = ("motion.json", "captured.json", "poses.json",
                                              "retargeted.json", "panel.json")
# What a file sent to the panel may be (``PUT /api/keyshapes/{part}``), as the CLI reads them.
OUTLINE_SUFFIXES = ("json", "csv", "svg")
UPLOAD_PARTS = ("outlines", "contours")


def _file(editing: Editing, name: str) -> Path:
    return editing.path(KEYSHAPES, name)


def _panel(editing: Editing) -> dict[str, Any]:
    file = _file(editing, PANEL)
    return json.loads(file.read_text(encoding="utf-8")) if file.is_file() else {}


def _remember(editing: Editing, **given: Any) -> None:
    write_text(_file(editing, PANEL), json.dumps({**_panel(editing), **given}) + "\n")


def _rounded(array: NDArray[np.float64], digits: int = 2) -> Any:
    return np.round(array, digits).tolist()


def state(editing: Editing, message: km.Message | None = None) -> dict[str, Any]:
    """The reply to a ``keyshapes`` message: what ``keyshapes/`` holds, for the panel to show."""
    panel = _panel(editing)
    outlines = _file(editing, OUTLINES)
    model = _file(editing, MODEL)
    reply: dict[str, Any] = {"type": "keyshapes", "outlines": [], "key_frames": panel.get("key_frames"),
                             "points": panel.get("points"), "inbetweens": panel.get("inbetweens", 5),
                             "model": None, "contours": None, "footage": None, "capture": None,
                             "retargeted": None}
    if outlines.is_file():
        reply["outlines"] = [shape.tolist() for shape in _raw_outlines(outlines)]
    if model.is_file():
        space = load_model(model)
        sheet = _file(editing, SHEET)
        version = sheet.stat().st_mtime_ns if sheet.is_file() else 0
        reply["model"] = {"keys": _rounded(space.keys), "closed": space.closed, "eigen": len(space.eigen),
                          "error": round(float(space.error), 4),
                          "sheet": f"api/keyshapes/sheet.png?v={version}"}
    contours = _file(editing, CONTOURS)
    if contours.is_file():
        shapes, fps, _ = load_contours(contours)
        reply["contours"] = {"frames": len(shapes), "points": shapes.shape[1], "fps": fps,
                             "shapes": _rounded(shapes)}
    footage = _footage(editing, panel)
    if footage is not None:
        frames, fps = footage
        reply["footage"] = {"frames": len(frames), "width": frames.shape[2], "height": frames.shape[1],
                            "fps": fps}
    motion, captured = _file(editing, MOTION), _file(editing, CAPTURED)
    if motion.is_file() and captured.is_file() and model.is_file():
        found, fps, _ = load_keymotion(motion)
        shapes, _, _ = load_contours(captured)
        reply["capture"] = described_capture(found, load_model(model).keys, shapes, fps,
                                             panel.get("source", "contours"))
    retargeted = _file(editing, RETARGETED)
    if retargeted.is_file():
        moved = load_motion(retargeted)
        reply["retargeted"] = {"first": 0, "last": moved.frame_count - 1, "fps": moved.fps,
                               "keys": panel.get("retarget_keys"), "file": f"{KEYSHAPES}/{RETARGETED}"}
    return reply


def described_capture(found: api.ContourCapture, keys: NDArray[np.float64], shapes: NDArray[np.float64],
                      fps: float, source: str) -> dict[str, Any]:
    """A capture for the page: each frame's weights, affine, error, the captured shape, and the
    affine path: each frame's affine applied to the centre of its blend of the keys (where the
    model's shape is centred)."""
    centre = np.einsum("tk,kd->td", found.weights, keys.mean(axis=1))
    path = np.einsum("tij,tj->ti", found.affine[:, :, :2], centre) + found.affine[:, :, 2]
    return {"source": source, "fps": fps, "weights": _rounded(found.weights, 5),
            "affine": _rounded(found.affine, 5), "error": _rounded(found.error, 4), "path": _rounded(path),
            "shapes": _rounded(shapes)}


def _raw_outlines(file: Path) -> list[NDArray[np.float64]]:
    """The outlines file's curves as given (of any point counts)."""
    data = json.loads(file.read_text(encoding="utf-8"))
    return [np.asarray(shape, dtype=float) for shape in data["contours"]]


def _footage(editing: Editing, panel: dict[str, Any]) -> tuple[NDArray[np.uint8], float] | None:
    """The footage sent (``PUT /api/footage``), read again from the project after a restart."""
    if editing.footage is None and panel.get("footage"):
        file = editing.path(*str(panel["footage"]).split("/"))
        if file.exists():
            frames, fps = load_frames(file)
            editing.footage = (frames, fps or 24.0)
    return editing.footage


def _footage_file(editing: Editing) -> str | None:
    """The newest footage saved in the project (a clip, or a folder of frames), as a relative path."""
    folder = editing.path(FOOTAGE)
    if not folder.is_dir():
        return None
    sent = [p for p in folder.iterdir() if p.name.startswith("clip.") or p.name == "frames"]
    newest = max(sent, key=lambda p: p.stat().st_mtime_ns, default=None)
    return None if newest is None else f"{FOOTAGE}/{newest.name}"


@off_loop("build the key-shape model")
def build_model(editing: Editing, message: km.KeyshapeModel,
                progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to ``keyshape_model``: the outlines resampled and in correspondence (as
    ``toonmotion keyshapes OUTLINES --points N`` reads them), the model and its sheet saved."""
    outlines = [np.asarray(shape, dtype=float) for shape in message.outlines]
    if message.key_frames is not None and len(message.key_frames) != len(outlines):
        raise KeyShapeError(f"'key_frames' names {len(message.key_frames)} frames for {len(outlines)} "
                            "outlines: one frame each")
    progress(0, 3)
    folder = editing.path(KEYSHAPES)
    folder.mkdir(exist_ok=True)
    given = _file(editing, OUTLINES)
    with atomic_path(given) as partial:  # read back as the CLI reads it before it replaces the last
        write_text(partial, json.dumps({"format": "toonmotion.contours", "version": 1, "fps": 12.0,
                                        "closed": True, "contours": [s.tolist() for s in outlines]}) + "\n")
        try:
            keys, _, closed = load_contours(partial, points=message.points)
        except KeyShapeError as error:  # named as the page gave them, not by the file read
            said = str(error).replace(f"{partial.name}: the contours", "the key outlines")
            if message.points is None:
                said += "; or have them resampled to a number of points"
            raise KeyShapeError(said) from None
        space = api.keyshape_space(keys, closed=closed, inbetweens=message.inbetweens)
        progress(1, 3)
        sheet = api.keyshape_sheet(space)
        progress(2, 3)
        progress(3, 3)  # all made: a cancel comes no later than here, so nothing is saved
    save_model(_file(editing, MODEL), space)
    save_png(_file(editing, SHEET), sheet)
    for stale in (MOTION, CAPTURED, POSES, RETARGETED):  # captured with other keys
        _file(editing, stale).unlink(missing_ok=True)
    with editing.lock:
        editing.keyshaped = None
    _remember(editing, points=message.points, key_frames=message.key_frames, inbetweens=message.inbetweens)
    return state(editing)


def pick(editing: Editing, message: km.KeyshapePick) -> dict[str, Any]:
    """The reply to ``keyshape_pick``: the outline of the layer clicked in a footage frame."""
    footage = _footage(editing, _panel(editing))
    if footage is None:
        raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
    frames = footage[0]
    if message.frame >= len(frames):
        raise KeyShapeError(f"frame {message.frame} is outside the footage's {len(frames)} frames")
    outline = api.pick_layer(frames[message.frame], message.at, tolerance=message.tolerance,
                             points=message.points)
    return {"type": "picked", "frame": message.frame, "outline": _rounded(outline)}


@off_loop("capture the key-shapes")
def capture(editing: Editing, message: km.KeyshapeCapture,
            progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to ``keyshape_capture``: the motion captured with the model's keys, saved."""
    model = _file(editing, MODEL)
    if not model.is_file():
        raise KeyShapeError("there is no key-shape model yet: give the key outlines first")
    keys = load_model(model).keys
    panel = _panel(editing)

    def report(stage: str, index: int, count: int) -> None:
        progress(index, count)

    if message.source == "contours":
        file = _file(editing, CONTOURS)
        if not file.is_file():
            raise KeyShapeError("there are no contours to capture yet: send a contours file first")
        contours, fps, closed = load_contours(file)
        found = api.capture_contours(contours, keys, lower=message.lower, upper=message.upper,
                                     progress=report)
        shapes = np.stack([_fitted(A, w, keys) for A, w in zip(found.affine, found.weights, strict=True)])
        footage_file = None
    else:
        footage = _footage(editing, panel)
        if footage is None:
            raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
        frames, fps = footage
        key_frames = panel.get("key_frames") or ([0] if len(keys) == 1 else None)
        if key_frames is None:
            raise KeyShapeError("say which footage frame each key outline is drawn on (pick them on the "
                                "footage), then build the model again")
        video = api.capture_video(frames, keys, key_frames=key_frames, progress=report)
        shapes, closed = video.shapes, True
        found = api.capture_contours(shapes, keys, lower=message.lower, upper=message.upper)
        footage_file = _footage_file(editing)
    save_keymotion(_file(editing, MOTION), found, fps=fps, space="keys")
    save_contours(_file(editing, CAPTURED), shapes, fps=fps, closed=closed)
    _file(editing, RETARGETED).unlink(missing_ok=True)
    with editing.lock:
        editing.keyshaped = None
    _remember(editing, source=message.source, **({"footage": footage_file} if footage_file else {}))
    return state(editing)


def _fitted(A: NDArray[np.float64], w: NDArray[np.float64], keys: NDArray[np.float64]) -> NDArray[np.float64]:
    """The model's shape for affine ``A`` and weights ``w`` (eq. 1)."""
    return np.einsum("k,knd->nd", w, keys) @ A[:, :2].T + A[:, 2]


def retarget(editing: Editing, message: km.KeyshapeRetarget) -> dict[str, Any]:
    """The reply to ``keyshape_retarget``: the captured motion on the Timeline's key poses at
    ``keys``, saved as the motion ``retarget-keyshapes --project --poses`` writes and animated."""
    motion_file, model = _file(editing, MOTION), _file(editing, MODEL)
    if not (motion_file.is_file() and model.is_file()):
        raise KeyShapeError("there is no captured key-shape motion yet: capture first")
    keys = load_model(model).keys
    found, fps, _ = load_keymotion(motion_file)
    if len(message.keys) != len(keys):
        raise KeyShapeError(f"choose one of the Timeline's keys for each of the {len(keys)} key-shapes, "
                            f"got {len(message.keys)}")
    with editing.lock:
        timeline, character = editing.timeline, editing.character
    if timeline is None:
        raise KeyframeError("there are no key-frames yet: key the character's poses in the Timeline first")
    at = {key.frame: key for key in timeline.keys}
    missing = [frame for frame in message.keys if frame not in at]
    if missing:
        raise KeyframeError(f"the Timeline has no key at frame {missing[0]}; its keys are at "
                            f"{', '.join(str(f) for f in at)}")
    skeleton = character.skeleton
    poses = None
    for i, frame in enumerate(message.keys):  # key i is key-shape i's pose
        poses = api.set_key(skeleton, poses, i, Pose(at[frame].pose.positions), fps=fps)
    assert poses is not None  # at least one key
    held: tuple[str, dict[int, ArrayLike]] | None = None
    if message.pin is not None:
        skeleton.index(message.pin.joint)  # an unknown joint: said in one line
        held = (message.pin.joint, dict.fromkeys(range(len(found.affine)), message.pin.at))
    outline = character.mesh.V[character.mesh.boundary[0]]  # the drawing's extent, at rest
    motion = api.retarget_keyposes(found, keys, skeleton, poses, fps=fps, reference=outline, pin=held)
    animation = api.animate_character(editing.deformer, motion)
    save_keyframes(_file(editing, POSES), skeleton, poses)
    save_motion(_file(editing, RETARGETED), motion)
    with editing.lock:
        editing.keyshaped = (character, animation)
    _remember(editing, retarget_keys=list(message.keys))
    return {"type": "keyshape_retargeted", "first": 0, "last": motion.frame_count - 1, "fps": motion.fps,
            "file": f"{KEYSHAPES}/{RETARGETED}"}


def keyshaped(editing: Editing) -> api.Animation:
    """The retargeted key-shape motion's animation, for ``frame`` with ``"source": "keyshapes"``
    (read from ``keyshapes/retargeted.json`` after a restart)."""
    with editing.lock:
        # Animated again for a drawing rigged since (its mesh is another).
        if editing.keyshaped is None or editing.keyshaped[0] is not editing.character:
            file = _file(editing, RETARGETED)
            if not file.is_file():
                raise MotionError("nothing is retargeted from key-shapes yet: capture, then retarget")
            animation = api.animate_character(editing.deformer, load_motion(file))
            editing.keyshaped = (editing.character, animation)
        return editing.keyshaped[1]


def read_upload(editing: Editing, part: str, file: Path, points: int | None) -> dict[str, Any]:
    """A file sent to the panel, read as the CLI reads contours (``--points``: resampled):
    key ``outlines`` come back to the page to add; ``contours`` are kept to capture."""
    shapes, fps, closed = load_contours(file, points=points)
    if part == "outlines":
        return {"outlines": shapes.tolist(), "closed": closed}  # in full: the model is built from them
    save_contours(_file(editing, CONTOURS), shapes, fps=fps, closed=closed)
    return {"frames": len(shapes), "points": shapes.shape[1], "fps": fps}


HANDLERS: dict[str, Callable[[Editing, Any], dict[str, Any]]] = {
    "keyshapes": state, "keyshape_pick": pick, "keyshape_retarget": retarget,
}
SLOW = {"keyshape_model": build_model, "keyshape_capture": capture}
