"""The 3D panel's requests (:mod:`toonmotion.web.proxy_messages`): the key-frames' animation lifted
into a 3D proxy with a motion-capture prior, simulated elements composited into its frames, and
their exports, on the library calls ``lift --project``, ``scene --project`` and ``proxy-export``
make.

What the panel makes is kept in the project folder's ``proxy3d/`` (:data:`PROXY_DIR`), so a
reload or a restart shows it again: ``proxy.json`` (the proxy, what ``toonmotion scene`` reads),
``lift.json`` (what it was lifted with, what was found, and the warnings), ``frames/NNNN.png``
(the animation's frames it was lifted from), ``scene.json`` and ``scene/NNNN.png`` (the
composited frames), and ``priors/`` (clips sent with ``PUT /api/priors``).
The other priors are the ``.bvh`` files of the library folder the editor was started with
(``toonmotion edit --mocap DIR``, or ``TOONMOTION_MOCAP``), listed by the server and named by
the page only from that list.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

import numpy as np

from toonmotion import api
from toonmotion.errors import ProxyError, SceneError
from toonmotion.io.atomic import write_text
from toonmotion.io.bvh import load_bvh, save_bvh
from toonmotion.io.exchange.proxy_gltf import save_proxy_glb
from toonmotion.io.frames import lay_on
from toonmotion.io.image import load_image, save_png
from toonmotion.io.proxy_json import load_proxy, save_proxy
from toonmotion.io.video import save_animation
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton_bvh import skeleton_clip
from toonmotion.scene.build import check_scene
from toonmotion.scene.elements import Balloon, Balls, Cape, Element, Rain, Scarf, Skirt
from toonmotion.web.editing import EXPORTS, Editing
from toonmotion.web.proxy_messages import PROXY_EXPORTS, Lift, ProxyExport, Scene, SceneElement
from toonmotion.web.slow_requests import off_loop

PROXY_DIR = "proxy3d"
PRIORS = "priors"
PROXY_FILE = "proxy.json"
LIFT_FILE = "lift.json"
SCENE_FILE = "scene.json"
SCENE_FRAMES = "scene"
DRAWN_FRAMES = "frames"
# A prior's name in the list: where it is from, then its file's name.
LIBRARY, UPLOADED = "library", "project"

Progress = Callable[[int, int], None]
# What the lift's warnings ask for, in the panel's words (api.LIFT_REMEDIES has the command line's).
PANEL_REMEDIES = {"view": "set the view on the gizmo",
                  "hold": "tick 'Keep the view's elevation' (the view set on the gizmo)",
                  "level": "turn the gizmo's up dial to 0"}


def priors(editing: Editing) -> list[str]:
    """The motion-capture clips a lift may take: ``project/NAME.bvh`` for those sent to the
    project, ``library/NAME.bvh`` for the library folder's, each sorted by name."""
    sent = editing.path(PROXY_DIR, PRIORS)
    found = [f"{UPLOADED}/{f.name}" for f in sorted(sent.glob("*.bvh"))] if sent.is_dir() else []
    if editing.library is not None and editing.library.is_dir():
        found += [f"{LIBRARY}/{f.name}" for f in sorted(editing.library.glob("*.bvh")) if f.is_file()]
    return found


def prior_file(editing: Editing, name: str) -> Path:
    """The file of the prior ``name`` from :func:`priors` (a one-line error for any other name)."""
    listed = priors(editing)
    if name not in listed:
        offer = ", ".join(listed[:8]) or "none yet: send a .bvh clip, or start the editor with --mocap DIR"
        raise ProxyError(f"no prior {name[:80]!r}; the priors are: {offer}")
    where, file = name.split("/", 1)
    if where == UPLOADED:
        return editing.path(PROXY_DIR, PRIORS, file)
    assert editing.library is not None  # listed only when there is one
    return editing.library / file


def state(editing: Editing) -> dict[str, Any]:
    """The reply to a ``proxy`` message: the priors, and what was last lifted and simulated."""
    editing.check_links()
    lifted, proxy, scene = _read_json(editing, LIFT_FILE), None, None
    file = editing.path(PROXY_DIR, PROXY_FILE)
    if lifted is not None and file.is_file():
        proxy = proxy_view(load_proxy(file))
        lifted["stale"] = lifted.get("keys") != _keys_digest(editing)
        scene = _read_json(editing, SCENE_FILE)
    return {"type": "proxy", "priors": priors(editing), "lift": lifted, "proxy": proxy, "scene": scene,
            "timeline": scene_summary(editing)}


def scene_summary(editing: Editing) -> dict[str, Any] | None:
    """The scene the Timeline can play over the key-frames: ``{"frames", "fps", "made"}`` (when it
    was made, for the page's cache), or None without one or once the key-frames have changed."""
    said, lifted = _read_json(editing, SCENE_FILE), _read_json(editing, LIFT_FILE)
    if said is None or lifted is None or lifted.get("keys") != _keys_digest(editing):
        return None
    made = editing.path(PROXY_DIR, SCENE_FILE).stat().st_mtime_ns
    return {"frames": said["frames"], "fps": said["fps"], "made": made}


def proxy_view(proxy: Proxy) -> dict[str, Any]:
    """A proxy as the panel's 3D view draws it: metres, +Y up, the ground Y = 0; the camera's
    centre and its axes (rows of its rotation: right, down, forward) per frame."""
    camera = proxy.camera
    return {
        "names": list(proxy.names), "parents": np.asarray(proxy.parents).tolist(), "fps": proxy.fps,
        "limbs": np.asarray(proxy.limbs).tolist(), "points": _rounded(proxy.points),
        "skeleton": _rounded(proxy.skeleton), "radii": None if proxy.radii is None else _rounded(proxy.radii),
        "camera": {"centres": _rounded(camera.centres), "axes": _rounded(camera.rotations),
                   "focal": float(camera.focal), "width": camera.width, "height": camera.height},
    }


@off_loop("lift the animation")
def lift(editing: Editing, message: Lift, progress: Progress) -> dict[str, Any]:
    """The reply to a ``lift`` message: the proxy saved, then shown (as :func:`state`, typed
    ``lifted``: the other pages are told)."""
    clip = load_bvh(prior_file(editing, message.prior))
    with editing.lock:
        character, animation = editing.character, editing.animation
    proxy, report = api.lift_animation(
        character, animation, clip, view=message.view, up=message.up, hold_elevation=message.hold_elevation,
        ground=message.ground, segment=message.segment,
        progress=lambda stage, index, count: progress(index, count))
    warnings = api.lift_warnings(proxy, report, remedies=PANEL_REMEDIES)
    if report.left_out:
        warnings.append(f"left out {', '.join(report.left_out)}: no joint of the prior matches them")
    folder = editing.path(PROXY_DIR)
    folder.mkdir(exist_ok=True)
    save_proxy(folder / PROXY_FILE, proxy)
    _clear_scene(editing)  # its frames were another proxy's
    drawn = lay_on(api.animation_frames(character, animation, proxy)[0])
    _save_frames(editing, DRAWN_FRAMES, drawn)
    write_text(folder / LIFT_FILE, json.dumps({
        "prior": message.prior, "view": message.view, "up": message.up,
        "hold_elevation": message.hold_elevation, "ground": message.ground, "segment": message.segment,
        "found": [round(report.azimuth, 2), round(report.elevation, 2)],
        "searched": report.view_found, "camera_px": round(report.camera_px, 3), "warnings": warnings,
        "keys": _keys_digest(editing)}, indent=1))
    return {**state(editing), "type": "lifted", "says": "the animation lifted into 3D"}


@off_loop("simulate the scene")
def scene(editing: Editing, message: Scene, progress: Progress) -> dict[str, Any]:
    """The reply to a ``scene`` message: the elements simulated, composited into the animation's
    frames and saved under ``proxy3d/scene/``."""
    proxy = _proxy(editing)
    elements = [element for given in message.elements for element in _elements(given)]
    check_scene(proxy, elements)
    with editing.lock:
        character, animation = editing.character, editing.animation
    pictures, limbs = api.animation_frames(character, animation, proxy)
    motion = api.simulate_scene(proxy, elements, progress=lambda stage, index, count: progress(index, count))
    made = api.composite_scene(proxy, pictures, motion, shading=message.shading, background=(255, 255, 255),
                               limbs=limbs, antialias=message.antialias,
                               progress=lambda stage, index, count: progress(index, count))
    _clear_scene(editing)
    count = _save_frames(editing, SCENE_FRAMES, made)
    said = {"elements": [e.model_dump(exclude={"type", "id"}) for e in message.elements], "frames": count,
            "fps": proxy.fps, "warnings": api.scene_warnings(motion), "shading": message.shading,
            "antialias": message.antialias}
    write_text(editing.path(PROXY_DIR, SCENE_FILE), json.dumps(said, indent=1))
    return {"type": "scene", **said, "says": "a 3D scene simulated"}


@off_loop("write the export")
def proxy_export(editing: Editing, message: ProxyExport, progress: Progress) -> dict[str, Any]:
    """The reply to a ``proxy_export`` message: the proxy or the scene written into ``exports/``."""
    proxy, kind, name = _proxy(editing), message.format, message.name
    exports = editing.path(EXPORTS)
    exports.mkdir(exist_ok=True)
    if kind in ("glb", "bvh"):
        target = exports / f"{name}{PROXY_EXPORTS[kind]}"
        save_proxy_glb(target, proxy) if kind == "glb" else save_bvh(target, skeleton_clip(proxy))
        progress(1, 1)
        return _exported([target], proxy.frame_count)
    if kind == "passes":
        written = []
        said = _said_scene(editing)
        given = [SceneElement.model_validate(e) for e in said["elements"]]
        motion = api.simulate_scene(proxy, [element for g in given for element in _elements(g)])
        passes = api.scene_passes(proxy, motion, shading=said["shading"], antialias=said["antialias"])
        for t, (beauty, depth, occlusion) in enumerate(passes):
            for part, picture in (("beauty", beauty), ("depth", depth), ("occlusion", occlusion)):
                written.append(exports / f"{name}_{part}_{t:04d}.png")
                save_png(written[-1], picture)
            progress(t + 1, proxy.frame_count)
        return _exported(written, proxy.frame_count)
    frames = _scene_frames(editing)
    if kind == "png":
        written = []
        for t, frame in enumerate(frames):
            written.append(exports / f"{name}_{t:04d}.png")
            save_png(written[-1], frame)
        return _exported(written, len(frames))
    target = exports / f"{name}{PROXY_EXPORTS[kind]}"
    rgba = (np.dstack([f, np.full(f.shape[:2], 255, np.uint8)]) for f in frames)
    count = save_animation(target, rgba, fps=proxy.fps)
    return _exported([target], count)


# The 3D panel's requests, by message type: answered at once, or off the event loop.
PROXY_HANDLERS = {"proxy": lambda editing, message: state(editing)}
PROXY_SLOW = {"lift": lift, "scene": scene, "proxy_export": proxy_export}


def _elements(given: SceneElement) -> list[Element]:
    """The scene elements one element of the message stands for (balls: a set per marker)."""
    markers = given.markers
    need = {"balloon": 1, "scarf": 1, "skirt": 1, "cape": 2, "rain": 0}.get(given.kind)
    if need is not None and len(markers) != need:
        what = {0: "no markers", 1: "one marker", 2: "two markers, the figure's own left and right shoulders"}
        raise SceneError(f"a {given.kind} takes {what[need]}, got {len(markers)}")
    if given.kind == "balls":
        if not markers:
            raise SceneError("balls take the markers whose paths they lie in (the feet, say)")
        return [Balls(m, count=given.count) for m in markers]
    if given.kind == "rain":
        return [Rain(count=given.count)]
    if given.kind == "cape":
        return [Cape(markers[0], markers[1])]
    kind = {"balloon": Balloon, "scarf": Scarf, "skirt": Skirt}[given.kind]
    return [kind(markers[0])]


def _proxy(editing: Editing) -> Proxy:
    file = editing.path(PROXY_DIR, PROXY_FILE)
    if not file.is_file():
        raise ProxyError("there is no 3D proxy yet: lift the animation first")
    lifted = _read_json(editing, LIFT_FILE)
    if lifted is not None and lifted.get("keys") != _keys_digest(editing):
        raise ProxyError("the key-frames changed since the proxy was lifted: lift the animation again")
    return load_proxy(file)


def _said_scene(editing: Editing) -> dict[str, Any]:
    said = _read_json(editing, SCENE_FILE)
    if said is None:
        raise SceneError("there is no scene yet: add elements and simulate first")
    return said


def _scene_frames(editing: Editing) -> list[np.ndarray]:
    folder = editing.path(PROXY_DIR, SCENE_FRAMES)
    return [load_image(folder / f"{t:04d}.png")[..., :3] for t in range(_said_scene(editing)["frames"])]


def _save_frames(editing: Editing, name: str, frames: Iterable[np.ndarray]) -> int:
    """Save ``frames`` as ``proxy3d/{name}/NNNN.png``, in place of any there only once all are
    written; how many."""
    folder = editing.path(PROXY_DIR, name + ".new")
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    count = 0
    for t, frame in enumerate(frames):
        save_png(folder / f"{t:04d}.png", frame)
        count += 1
    shutil.rmtree(editing.path(PROXY_DIR, name), ignore_errors=True)
    folder.rename(editing.path(PROXY_DIR, name))
    return count


def _clear_scene(editing: Editing) -> None:
    editing.path(PROXY_DIR, SCENE_FILE).unlink(missing_ok=True)
    shutil.rmtree(editing.path(PROXY_DIR, SCENE_FRAMES), ignore_errors=True)


def _exported(files: list[Path], frames: int) -> dict[str, Any]:
    named = [f"{EXPORTS}/{file.name}" for file in files]
    return {"type": "exported", "file": named[0], "files": named, "frames": frames}


def _read_json(editing: Editing, name: str) -> dict[str, Any] | None:
    file = editing.path(PROXY_DIR, name)
    return json.loads(file.read_text(encoding="utf-8")) if file.is_file() else None


def _keys_digest(editing: Editing) -> str | None:
    """What the key-frames were when the proxy was lifted: a lift is the animation of those."""
    text = editing.keys_text()
    return None if text is None else hashlib.sha256(text.encode()).hexdigest()[:16]


def _rounded(values: Any) -> Any:
    return np.round(np.asarray(values, dtype=float), 4).tolist()
