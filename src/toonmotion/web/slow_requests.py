"""The editor's slow requests, run off the server's event loop with progress messages: an export, a
tracking, a drawing opened, joints suggested on footage (:mod:`toonmotion.web.messages`).

Each is given the message's text and ``progress(index, count)``, which raises
:class:`~toonmotion.errors.Cancelled` once the page cancels; its reply carries the request's id and
every failure is a one-line error reply (:func:`off_loop`).
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import distance_transform_edt

from toonmotion import api
from toonmotion.errors import (
    Cancelled,
    KeyframeError,
    ProjectError,
    SkeletonError,
    ToonmotionError,
    TrackingError,
)
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.motion_json import save_motion
from toonmotion.render.frame import check_overlays
from toonmotion.rig.skeleton import Skeleton
from toonmotion.web import messages
from toonmotion.web.editing import CAPTURED, EXPORTS, SNAPSHOTS, UPLOADS, Editing
from toonmotion.web.messages import EXPORT_FORMATS, bug, one_line, skeleton_of

log = logging.getLogger("toonmotion.web")

SlowHandler = Callable[[Editing, Any, Callable[[int, int], None]], dict[str, Any]]


SlowReply = Callable[[Editing, str, Callable[[int, int], None]], dict[str, Any]]


def off_loop(verb: str) -> Callable[[SlowHandler], SlowReply]:
    """A handler run off the event loop, given the message's text: its reply carries the id,
    and every failure is a one-line error reply (a file that cannot be written: "cannot
    {verb}: ..."; a bug: one line to the page, the details to the log)."""
    def wrap(handler: SlowHandler) -> SlowReply:
        @functools.wraps(handler)
        def run(editing: Editing, text: str, progress: Callable[[int, int], None]) -> dict[str, Any]:
            ident: Any = None
            try:
                raw = messages.parse(text)
                ident = messages.ident(raw)
                message = messages.read(raw)
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


@off_loop("write the export")
def export(editing: Editing, message: messages.Export,
           progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to an export message (:mod:`toonmotion.web.messages`), calling ``progress(index, count)``.

    Meant to run off the server's event loop, once the loop has computed the animation
    (:attr:`Editing.animation`): this takes it and the character, which are immutable, and only
    renders and writes.
    """
    kind, name = message.format, message.name
    with editing.lock:
        character, animation = editing.character, editing.animated(message.exaggeration())
    relative = f"{EXPORTS}/{name}{EXPORT_FORMATS[kind]}"
    target = editing.path(EXPORTS, f"{name}{EXPORT_FORMATS[kind]}")
    overlays = check_overlays(message.overlays)
    size, background = message.size, message.background

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


@off_loop("open the drawing")
def open_drawing(editing: Editing, message: messages.OpenDrawing,
                 progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to an ``open_drawing`` message (:mod:`toonmotion.web.messages`), calling ``progress(index,
    count)`` through the rigging stages; meant to run off the server's event loop."""
    uploads = editing.path(UPLOADS)
    if not (uploads / "drawing").is_file():
        raise ProjectError("there is no drawing to open yet: send one first")
    keep, with_mask = message.skeleton, message.mask
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


@off_loop("track the footage")
def track(editing: Editing, message: messages.Track,
          progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to a ``track`` message (:mod:`toonmotion.web.messages`), calling ``progress(index, count)``;
    meant to run off the server's event loop, like :func:`export`."""
    if editing.footage is None:
        raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
    frames, fps = editing.footage
    joints = message.joints
    skeleton = skeleton_of(joints)
    sizes = np.array([joint.size for joint in joints], dtype=float)
    order = [next(i for i, j in enumerate(joints) if j.name == name) for name in skeleton.names]
    earlier, at, corrections = None, None, None
    if message.at is not None:  # a correction: the earlier tracking is kept before it
        if editing.capture is None:
            raise TrackingError("there is no earlier tracking to correct: track first")
        if message.set is None:
            raise TrackingError("'set' must give the corrected joints, name to [x, y]")
        earlier, at, corrections = editing.capture.motion, message.at, dict(message.set)
    settings = api.TrackSettings(figure=not message.free, best_path=not message.frame_by_frame,
                                 both_ways=message.both_ways)
    if message.full_resolution:
        settings = replace(settings, working_side=None)
    background = message.background
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
            editing.capture_page = {**editing.capture_page, "joints": [j.model_dump() for j in joints],
                                    "tracked": reply}
    return reply


@off_loop("suggest the joints")
def suggest(editing: Editing, message: messages.Suggest,
            progress: Callable[[int, int], None]) -> dict[str, Any]:
    """The reply to a ``suggest`` message (:mod:`toonmotion.web.messages`); off the event loop, like
    :func:`track` (the figure of a sequence without a flat border is found over every frame)."""
    if editing.footage is None:
        raise TrackingError("there is no footage yet: send a video, a GIF or frames first")
    background = message.background
    skeleton, sizes = api.suggest_joints(editing.footage[0], colour=background)
    return {"type": "suggested", "joints": suggested_joints(skeleton, sizes)}


def suggested_joints(skeleton: Skeleton, sizes: NDArray[np.float64]) -> list[dict[str, Any]]:
    """Joints suggested on footage, for the page: name, parent (a name or null), position and
    rectangle size."""
    return [{"name": n, "parent": None if p < 0 else skeleton.names[p],
             "position": skeleton.positions[i].tolist(), "size": sizes[i].tolist()}
            for i, (n, p) in enumerate(zip(skeleton.names, skeleton.parents, strict=True))]
