"""A job as tasks: what the client reads and sends, and each task's key.

The client reads every input file here, once, into bytes: workers get the data, never a path
of the submitting machine. A character or motion's key is the SHA-256 of its files' bytes and
its options; an output task's key is the SHA-256 of its character's and motion's keys and its
output options, so a task's key changes exactly when something it depends on changes.

>>> key_of({"b": 1, "a": [1, 2]}) == key_of({"a": [1, 2], "b": 1})
True
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from toonmotion import __version__
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import BatchError, ToonmotionError
from toonmotion.io.batch_job import MOTION_KINDS, Job, OutputModel, output_name


@dataclass(frozen=True)
class InputFile:
    """One input file's bytes. ``name`` is its path on the client, for messages only; ``relative``
    places it inside a project folder (else its base name)."""

    name: str
    relative: str
    data: bytes


@dataclass(frozen=True)
class CharacterInput:
    """What rigging one character needs. ``project`` holds a project folder's files (its
    ``name`` is the folder); ``error`` is why the client could not read an input."""

    name: str
    key: str
    drawing: InputFile | None = None
    mask: InputFile | None = None
    skeleton: InputFile | None = None
    project: tuple[InputFile, ...] = ()
    project_name: str = ""
    vertices: int | None = None
    spacing: float | None = None
    error: str | None = None


@dataclass(frozen=True)
class MotionInput:
    """What a motion needs: one file of ``kind`` (``bvh``, ``keys``, ``motion`` or ``keyshapes``) and
    its options; a key-shape motion also its model and each character's key poses."""

    name: str
    key: str
    kind: str
    file: InputFile | None
    view: tuple[float, float] | None = None
    map: tuple[tuple[str, str], ...] = ()
    segment: tuple[int, int | None] | None = None
    fps: float | None = None
    error: str | None = None
    model: InputFile | None = None
    poses: tuple[tuple[str, InputFile], ...] = ()


@dataclass(frozen=True)
class OutputTask:
    """One (character, motion, output): ``files`` maps each format to the file it writes."""

    key: str
    character: str
    motion: str
    output: OutputModel
    files: tuple[tuple[str, str], ...]


@dataclass(frozen=True)
class Plan:
    """Every character and motion input, and every output task in the job's order."""

    characters: dict[str, CharacterInput]
    motions: dict[str, MotionInput]
    tasks: tuple[OutputTask, ...]


def key_of(value: Any) -> str:
    """The SHA-256 (hex) of ``value`` as canonical JSON."""
    text = json.dumps(value, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def sha256(data: bytes) -> str:
    """The SHA-256 of ``data``, hex."""
    return hashlib.sha256(data).hexdigest()


def plan_job(job: Job) -> Plan:
    """Read every input of ``job`` and lay out its tasks.

    An input that cannot be read becomes an input with an ``error``: only the tasks that need
    it fail.
    """
    for output in job.outputs:  # deformation options out of range: refused before anything runs
        try:
            deform_settings(output)
        except ToonmotionError as error:
            where = f"output {output.name}" if output.name else "output"
            raise BatchError(f"{job.path}: {where}.deform: {error}") from None
    characters = {c.name: _character(c) for c in job.characters}
    motions = {m.name: _motion(m) for m in job.motions}
    tasks = []
    for c, m in job.pairs:
        for output in job.outputs:
            files = tuple((f, output_name(c, m, output, f)) for f in dict.fromkeys(output.formats))
            key = key_of({"version": __version__, "character": characters[c].key, "motion": motions[m].key,
                          "output": output.model_dump(), "files": files})
            tasks.append(OutputTask(key=key, character=c, motion=m, output=output, files=files))
    return Plan(characters=characters, motions=motions, tasks=tuple(tasks))


def deform_settings(output: OutputModel) -> DeformSettings | None:
    """An output's deformation options as settings (None: the defaults).

    Raises
    ------
    SettingsError
        A value out of range.
    """
    if output.deform is None:
        return None
    return DeformSettings(**output.deform.model_dump(exclude_none=True))


def _read(path: str, relative: str | None = None) -> InputFile:
    return InputFile(name=path, relative=relative or Path(path).name, data=Path(path).read_bytes())


def _character(entry: Any) -> CharacterInput:
    options = {"vertices": entry.vertices, "spacing": entry.spacing}
    try:
        if entry.project is not None:
            folder = Path(entry.project)
            files = tuple(_read(str(p), p.relative_to(folder).as_posix()) for p in sorted(folder.rglob("*"))
                          if p.is_file() and not p.name.startswith("."))
            key = key_of({"project": [(f.relative, sha256(f.data)) for f in files], **options})
            return CharacterInput(name=entry.name, key=key, project=files, project_name=folder.name)
        found = {role: _read(getattr(entry, role)) for role in ("drawing", "mask", "skeleton")
                 if getattr(entry, role) is not None}
    except OSError as error:
        return CharacterInput(name=entry.name, key=key_of({"unreadable": entry.name}),
                              error=f"character {entry.name!r}: cannot read {error.filename}: "
                                    f"{(error.strerror or str(error)).lower()}")
    key = key_of({"files": {role: (f.relative, sha256(f.data)) for role, f in found.items()}, **options})
    return CharacterInput(name=entry.name, key=key, drawing=found.get("drawing"), mask=found.get("mask"),
                          skeleton=found.get("skeleton"), vertices=entry.vertices, spacing=entry.spacing)


def _motion(entry: Any) -> MotionInput:
    kind = next(k for k in MOTION_KINDS if getattr(entry, k) is not None)
    options = {"view": entry.view, "map": sorted((entry.map or {}).items()), "segment": entry.segment,
               "fps": entry.fps}
    base = {"name": entry.name, "kind": kind, "view": entry.view, "map": tuple(options["map"]),
            "segment": entry.segment, "fps": entry.fps}
    try:
        file = _read(getattr(entry, kind))
        model = _read(entry.model) if entry.model is not None else None
        poses = tuple((c, _read(f)) for c, f in sorted((entry.poses or {}).items()))
    except OSError as error:
        return MotionInput(key=key_of({"unreadable": entry.name}), file=None,
                           error=f"motion {entry.name!r}: cannot read {error.filename}: "
                                 f"{(error.strerror or str(error)).lower()}", **base)
    key = key_of({"kind": kind, "file": sha256(file.data), **options,
                  **({"model": sha256(model.data), "poses": [(c, sha256(f.data)) for c, f in poses]}
                     if model is not None else {})})
    return MotionInput(key=key, file=file, model=model, poses=poses, **base)
