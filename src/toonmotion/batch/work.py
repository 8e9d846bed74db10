"""What the workers run: rig a character, prepare a motion, render and export one output.

Each function takes the data the client sent (:mod:`toonmotion.batch.plan`) and returns
values, never touching the client's paths. Inputs are written into a private temporary folder
on the worker and read by the library's own loaders; an error naming such a file is reworded
to name the client's file. Outputs are written into another temporary folder, read back as
bytes and returned: only the client writes into the job's output folder.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion import api
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.animate.motion import Motion
from toonmotion.animate.timeline import Timeline
from toonmotion.batch.plan import CharacterInput, InputFile, MotionInput, OutputTask, deform_settings
from toonmotion.errors import KeyShapeError, ToonmotionError
from toonmotion.io.bvh import load_bvh
from toonmotion.io.keyshape_json import load_keymotion, load_model
from toonmotion.io.motion_json import load_motion
from toonmotion.io.pose_json import load_keyframes
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.rig.character import Character, RigSettings

BACKGROUNDS = {"white": (255, 255, 255), "black": (0, 0, 0)}


@dataclass(frozen=True)
class KeyShapeMotion:
    """A key-shape motion captured with the hand-picked keys, those keys, its frame rate, and each
    character's key poses (a key-frames file's bytes, one pose per key)."""

    capture: ContourCapture
    keys: NDArray[np.float64]
    fps: float
    poses: dict[str, InputFile]


@dataclass(frozen=True)
class PreparedMotion:
    """A motion ready to meet a character: a :class:`Motion` (from a clip or a motion file,
    retargeted per character), a key-frames file's bytes (read against each skeleton), or a
    key-shape motion (replayed on each character's key poses)."""

    name: str
    motion: Motion | None
    keys: InputFile | None
    map: tuple[tuple[str, str], ...]
    fps: float | None
    keyshapes: KeyShapeMotion | None = None


@dataclass(frozen=True)
class Rendered:
    """An output task's files (name -> bytes), frame count and seconds of work on the worker."""

    files: dict[str, bytes]
    frames: int
    seconds: float


@contextmanager
def _materialised(
    files: Sequence[InputFile], *, project: str = ""
) -> Iterator[tuple[Path, list[Path], dict[str, str]]]:
    """A temporary folder holding ``files`` (inside ``project/`` if given), their paths there, and
    a map of the temporary names back to the client's, for messages."""
    with tempfile.TemporaryDirectory(prefix="toonmotion-batch-") as tmp:
        root = Path(tmp) / project if project else Path(tmp)
        names: dict[str, str] = {}
        paths = []
        for i, f in enumerate(files):
            target = root / f.relative if project else root / str(i) / f.relative
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(f.data)
            names[str(target)] = f.name
            paths.append(target)
        if project and files:
            folder = Path(files[0].name)
            for _ in Path(files[0].relative).parts:
                folder = folder.parent
            names[str(root)] = str(folder)
        yield root, paths, names


def _reworded(error: ToonmotionError, names: dict[str, str]) -> ToonmotionError:
    text = str(error)
    for temporary in sorted(names, key=len, reverse=True):
        text = text.replace(temporary, names[temporary])
    if text == str(error):
        return error
    try:
        return type(error)(text)
    except TypeError:
        return error


def rig_character(spec: CharacterInput) -> Character:
    """Rig ``spec``'s drawing (or load its project): the task every output of it depends on."""
    if spec.error is not None:
        raise ToonmotionError(spec.error)
    if spec.project:
        with _materialised(spec.project, project=spec.project_name) as (root, _, names):
            try:
                return api.load_project(root)
            except ToonmotionError as error:
                raise _reworded(error, names) from None
    if spec.drawing is None:
        raise ToonmotionError(f"character {spec.name!r} has no drawing")
    roles = [f for f in (spec.drawing, spec.mask, spec.skeleton)]
    with _materialised([f for f in roles if f is not None]) as (_, found, names):
        it = iter(found)
        drawing, mask, skeleton = (None if f is None else next(it) for f in roles)
        settings = RigSettings(vertices=spec.vertices, spacing=spec.spacing)
        try:
            return api.rig_image(drawing or "", mask=mask, skeleton=skeleton, settings=settings)
        except ToonmotionError as error:
            raise _reworded(error, names) from None


def prepare_motion(spec: MotionInput) -> PreparedMotion:
    """Read a motion once for every character: a clip seen from its view, a motion file, or a
    key-frames file kept as bytes (it can only be read against a skeleton)."""
    if spec.error is not None or spec.file is None:
        raise ToonmotionError(spec.error or f"motion {spec.name!r} has no file")
    if spec.kind == "keys":
        return PreparedMotion(spec.name, None, spec.file, (), spec.fps)
    if spec.kind == "keyshapes":
        return PreparedMotion(spec.name, None, None, (), None, keyshapes=_keyshape_motion(spec))
    with _materialised([spec.file]) as (_, (path,), names):
        try:
            if spec.kind == "bvh":
                view = spec.view or (0.0, 0.0)
                motion = api.project_mocap(load_bvh(path), view=(view[0], view[1]), joint_map=dict(spec.map),
                                           segment=spec.segment or (0, None), fps=spec.fps)
                return PreparedMotion(spec.name, motion, None, (), None)
            return PreparedMotion(spec.name, load_motion(path), None, spec.map, spec.fps)
        except ToonmotionError as error:
            raise _reworded(error, names) from None


def _keyshape_motion(spec: MotionInput) -> KeyShapeMotion:
    if spec.file is None or spec.model is None:
        raise ToonmotionError(f"motion {spec.name!r} has no key-shape motion or model")
    with _materialised([spec.file, spec.model]) as (_, (path, model), names):
        try:
            captured, fps, space = load_keymotion(path)
            if space != "keys":
                raise KeyShapeError(f"{path} was captured in the extended space: capture it with the "
                                    "hand-picked keys ('capture-contours --keys') to retarget it")
            keys = load_model(model).keys
        except ToonmotionError as error:
            raise _reworded(error, names) from None
    return KeyShapeMotion(captured, keys, spec.fps or fps, dict(spec.poses))


def _replayed(motion: KeyShapeMotion, character: Character, name: str) -> Motion:
    """A key-shape motion replayed on ``character``'s key poses (``retarget-keyshapes --project``)."""
    poses = motion.poses.get(name)
    if poses is None:
        raise ToonmotionError(f"the key-shape motion has no key poses for character {name!r}")
    with _materialised([poses]) as (_, (path,), names):
        try:
            timeline = load_keyframes(path, character.skeleton)
            outline = character.mesh.V[character.mesh.boundary[0]]  # the drawing's extent, at rest
            return api.retarget_keyposes(motion.capture, motion.keys, character.skeleton, timeline,
                                         fps=motion.fps, reference=outline)
        except ToonmotionError as error:
            raise _reworded(error, names) from None


def render_output(character: Character, motion: PreparedMotion, task: OutputTask) -> Rendered:
    """Animate ``character`` with ``motion`` and export every format of ``task`` to bytes."""
    start = time.perf_counter()
    output = task.output
    exaggeration = FilterSettings(strength=output.exaggerate) if output.exaggerate else None
    settings = deform_settings(output)
    source: Motion | Timeline
    with tempfile.TemporaryDirectory(prefix="toonmotion-batch-") as tmp:
        folder = Path(tmp)
        try:
            if motion.keys is not None:
                with _materialised([motion.keys]) as (_, (path,), names):
                    try:
                        source = load_keyframes(path, character.skeleton, fps=motion.fps)
                    except ToonmotionError as error:
                        raise _reworded(error, names) from None
            elif motion.motion is not None:
                source = api.retarget(motion.motion, character.skeleton, joint_map=dict(motion.map))
            elif motion.keyshapes is not None:
                source = _replayed(motion.keyshapes, character, task.character)
            else:
                raise ToonmotionError(f"motion {motion.name!r} holds neither a motion nor key-frames")
            animation = api.animate_character(character, source, settings=settings, exaggeration=exaggeration,
                                              fps=motion.fps if motion.keys is None else None,
                                              method="solve" if output.solve_inbetweens else "interpolate")
        except ToonmotionError as error:
            raise type(error)(f"{task.character} x {task.motion}: {error}") from None
        frames = 0
        for format, name in task.files:
            size = None if output.size is None else (output.size[0], output.size[1])
            done = api.export_animation(folder / "out" / name, character, animation, format=format,
                                        size=size, settings=settings,
                                        background=BACKGROUNDS.get(output.background or ""))
            frames = done.frames
        files = {p.relative_to(folder / "out").as_posix(): p.read_bytes()
                 for p in sorted((folder / "out").rglob("*")) if p.is_file()}
    return Rendered(files=files, frames=frames, seconds=time.perf_counter() - start)


def trivial(index: int) -> int:
    """A task that does nothing, for measuring the scheduler's overhead (benchmarks/batch.py)."""
    return index
