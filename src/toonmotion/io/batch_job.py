"""The batch job file, ``JOB.toml``: characters, motions, outputs, and which pairs to make.

A job lists ``[[character]]`` entries (a drawing with an optional mask and skeleton, or a
project folder made by ``toonmotion rig``), ``[[motion]]`` entries (a motion-capture clip or a
folder of clips seen from a view, a key-frames file, a motion file, or a key-shape motion with
each character's key poses), one ``[output]`` or several ``[[output]]`` (formats, picture size,
exaggeration, deformation options) and optionally ``pairs``; by default every character
is animated with every motion. Paths are relative to the job file. docs/batch.md describes
every key.

:func:`load_job` checks the file against a pydantic model and that every file it names exists;
each problem is one :class:`~toonmotion.errors.BatchError` line naming the file and the key:

>>> import tempfile
>>> folder = Path(tempfile.mkdtemp()).resolve()
>>> _ = (folder / "job.toml").write_text('''
... [[character]]
... name = "hero"
... drawing = "hero.png"
... [[motion]]
... name = "wave"
... keys = "wave.json"
... [output]
... formats = ["gif"]
... ''')
>>> try:
...     load_job(folder / "job.toml")
... except BatchError as error:
...     print(str(error).replace(str(folder), "DIR"))
DIR/job.toml: character[0].drawing: no such file DIR/hero.png
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, StrictBool, StrictStr, model_validator

from toonmotion.errors import BatchError
from toonmotion.io.schema import Float, Int, Model, problem, validate

# The formats a batch output can hold, with the ending of the file each writes (Spine and a
# sprite sheet write a .json with an .atlas and/or .png beside it).
FORMATS = {
    "gif": ".gif",
    "glb": ".glb",
    "mp4": ".mp4",
    "apng": ".apng",
    "webp": ".webp",
    "webm": ".webm",
    "spine": "-spine.json",
    "sheet": "-sheet.json",
}

# The kinds of motion a ``[[motion]]`` holds, each named by the key of its file.
MOTION_KINDS = ("bvh", "keys", "motion", "keyshapes")

FormatName = Literal["gif", "glb", "mp4", "apng", "webp", "webm", "spine", "sheet"]

# Names become parts of file names: letters, digits, '_', '.', '-', not starting with '.'.
_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]*")
Name = Annotated[StrictStr, Field(pattern=_NAME.pattern, max_length=100)]
_NAME_CHARACTER = re.compile(r"[^A-Za-z0-9_.-]")  # what a clip's file name may not bring into a name
Path_ = Annotated[StrictStr, Field(min_length=1)]


class CharacterModel(Model):
    """A ``[[character]]``: ``drawing`` (with optional ``mask``, ``skeleton``) or ``project``."""

    name: Name
    drawing: Path_ | None = None
    mask: Path_ | None = None
    skeleton: Path_ | None = None
    project: Path_ | None = None
    vertices: Annotated[Int, Field(ge=3)] | None = None
    spacing: Annotated[Float, Field(ge=1.0)] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> CharacterModel:
        if (self.drawing is None) == (self.project is None):
            raise problem("give either 'drawing' or 'project'")
        if self.project is not None and any(
            v is not None for v in (self.mask, self.skeleton, self.vertices, self.spacing)
        ):
            raise problem("'mask', 'skeleton', 'vertices' and 'spacing' go with 'drawing', not 'project'")
        if self.vertices is not None and self.spacing is not None:
            raise problem("give either 'vertices' or 'spacing', not both")
        return self


class MotionModel(Model):
    """A ``[[motion]]``: ``bvh`` (a clip or a folder of clips, with ``view``), ``keys``, ``motion``,
    or ``keyshapes`` (with ``model`` and each character's key ``poses``)."""

    name: Name
    bvh: Path_ | None = None
    keys: Path_ | None = None
    motion: Path_ | None = None
    keyshapes: Path_ | None = None
    model: Path_ | None = None
    poses: dict[StrictStr, Path_] | None = None
    view: tuple[Float, Float] | None = None
    map: dict[StrictStr, StrictStr] | None = None
    segment: tuple[Int, Int | None] | None = None
    fps: Annotated[Float, Field(gt=0)] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> MotionModel:
        given = [k for k in MOTION_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            raise problem("give exactly one of 'bvh', 'keys', 'motion' or 'keyshapes'")
        if self.bvh is not None and self.view is None:
            raise problem("a 'bvh' motion needs 'view = [azimuth, elevation]' in degrees")
        if self.bvh is None and (self.view is not None or self.segment is not None):
            raise problem("'view' and 'segment' go with 'bvh'")
        if self.map is not None and (self.keys is not None or self.keyshapes is not None):
            raise problem("'map' goes with 'bvh' or 'motion'")
        if self.keyshapes is not None and (self.model is None or not self.poses):
            raise problem("a 'keyshapes' motion needs its 'model' (from 'toonmotion keyshapes') and "
                          "'poses = { CHARACTER = \"KEYS.json\" }': each character's key poses, one per key")
        if self.keyshapes is None and (self.model is not None or self.poses is not None):
            raise problem("'model' and 'poses' go with 'keyshapes'")
        return self


class DeformModel(Model):
    """An output's ``deform = { ... }``: :class:`~toonmotion.deform.deformer.DeformSettings`, as the
    animation commands' options set them; what is not given keeps the settings' own default."""

    preserve_area: StrictBool | None = None
    stage_two: StrictBool | None = None
    weights: tuple[Float, Float, Float] | None = None
    joint_width: Annotated[Float, Field(ge=0)] | None = None
    skinning: Literal["one-bone", "weights"] | None = None
    joint_anchor: Annotated[Float, Field(ge=0)] | None = None


class OutputModel(Model):
    """An ``[output]``: the formats to write and how."""

    name: Name | None = None
    formats: Annotated[list[FormatName], Field(min_length=1)]
    size: tuple[Annotated[Int, Field(ge=8, le=8192)], Annotated[Int, Field(ge=8, le=8192)]] | None = None
    exaggerate: Annotated[Float, Field(ge=0)] | None = None
    background: Literal["transparent", "white", "black"] | None = None
    solve_inbetweens: StrictBool = False
    deform: DeformModel | None = None


class JobModel(Model):
    """The whole ``JOB.toml``."""

    character: Annotated[list[CharacterModel], Field(min_length=1)]
    motion: Annotated[list[MotionModel], Field(min_length=1)]
    output: OutputModel | Annotated[list[OutputModel], Field(min_length=1)]
    pairs: list[tuple[StrictStr, StrictStr]] | None = None


@dataclass(frozen=True)
class Job:
    """A checked job: its entries with every path made absolute.

    Attributes
    ----------
    path : Path
        The job file.
    characters, motions, outputs : tuple of models
        As in the file, paths resolved against the job file's folder.
    pairs : tuple of (str, str)
        Every (character, motion) to make, in order.
    """

    path: Path
    characters: tuple[CharacterModel, ...]
    motions: tuple[MotionModel, ...]
    outputs: tuple[OutputModel, ...]
    pairs: tuple[tuple[str, str], ...]


def load_job(path: str | os.PathLike[str]) -> Job:
    """Read and check a job file; every problem is one :class:`BatchError` line.

    Parameters
    ----------
    path : str or Path
        A ``JOB.toml``.

    Returns
    -------
    Job
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BatchError(f"cannot read job file {path}: no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise BatchError(f"cannot read job file {path}: {error}") from None
    except tomllib.TOMLDecodeError as error:
        raise BatchError(f"{path} is not valid TOML: {error}") from None
    model = validate(JobModel, data, where=str(path), error=BatchError)
    folder = path.parent
    outputs = (model.output,) if isinstance(model.output, OutputModel) else tuple(model.output)
    _unique(path, "character", [c.name for c in model.character])
    _unique(path, "motion", [m.name for m in model.motion])
    if len(outputs) > 1:
        for i, output in enumerate(outputs):
            if output.name is None:
                raise BatchError(f"{path}: output[{i}].name: several outputs need a name each")
        _unique(path, "output", [o.name or "" for o in outputs])
    characters = tuple(_resolved(path, folder, "character", i, c, ("drawing", "mask", "skeleton", "project"))
                       for i, c in enumerate(model.character))
    names_c = [c.name for c in characters]
    expanded: dict[str, list[MotionModel]] = {}  # each entry's motions: a folder of clips gives several
    for i, m in enumerate(model.motion):
        resolved = _resolved(path, folder, "motion", i, m, ("bvh", "keys", "motion", "keyshapes", "model"))
        if m.poses is not None:
            for c in m.poses:
                if c not in names_c:
                    raise BatchError(f"{path}: motion[{i}].poses: no character named {c!r} (the job has "
                                     f"{', '.join(names_c)})")
            poses = {c: _existing(path, f"motion[{i}].poses.{c}", folder / f) for c, f in m.poses.items()}
            resolved = resolved.model_copy(update={"poses": poses})
        expanded[m.name] = _clips(path, i, resolved)
    motions = tuple(m for group in expanded.values() for m in group)
    _unique(path, "motion", [m.name for m in motions])
    names_m = [m.name for m in model.motion]
    if model.pairs is None:
        wanted = [(c, m) for c in names_c for m in names_m]
    else:
        for i, (c, m) in enumerate(model.pairs):
            if c not in names_c:
                raise BatchError(f"{path}: pairs[{i}]: no character named {c!r} (the job has "
                                 f"{', '.join(names_c)})")
            if m not in names_m:
                raise BatchError(f"{path}: pairs[{i}]: no motion named {m!r} (the job has "
                                 f"{', '.join(names_m)})")
        wanted = list(model.pairs)
    for c, m in wanted:
        given = expanded[m][0].poses
        if given is not None and c not in given:
            raise BatchError(f"{path}: motion {m!r} is a key-shape motion with no key poses for character "
                             f"{c!r}: add it to its 'poses', or list the pairs to make")
    pairs = tuple(dict.fromkeys((c, one.name) for c, m in wanted for one in expanded[m]))
    return Job(path=path, characters=characters, motions=motions, outputs=outputs, pairs=pairs)


def _clips(path: Path, index: int, entry: MotionModel) -> list[MotionModel]:
    """A ``bvh`` folder's clips as motions ``NAME-CLIP`` (its ``.bvh`` files, sorted); any other
    entry as it is."""
    if entry.bvh is None or not Path(entry.bvh).is_dir():
        return [entry]
    clips = sorted(p for p in Path(entry.bvh).iterdir() if p.suffix.lower() == ".bvh" and p.is_file())
    if not clips:
        raise BatchError(f"{path}: motion[{index}].bvh: the folder {entry.bvh} holds no .bvh file")
    return [entry.model_copy(update={"name": f"{entry.name}-{_NAME_CHARACTER.sub('_', clip.stem)}",
                                     "bvh": str(clip)}) for clip in clips]


def _existing(path: Path, key: str, target: Path) -> str:
    target = target.resolve()
    if not target.is_file():
        raise BatchError(f"{path}: {key}: no such file {target}")
    return str(target)


def _unique(path: Path, what: str, names: list[str]) -> None:
    seen: set[str] = set()
    for i, name in enumerate(names):
        if name in seen:
            raise BatchError(f"{path}: {what}[{i}].name: {name!r} is given twice; names must differ")
        seen.add(name)


def _resolved(path: Path, folder: Path, what: str, index: int, entry: Any, keys: tuple[str, ...]) -> Any:
    """``entry`` with each path key resolved against ``folder`` and checked to exist."""
    changes = {}
    for key in keys:
        value = getattr(entry, key)
        if value is None:
            continue
        target = (folder / value).resolve()
        if key == "project":
            if not (target / "project.json").is_file():
                raise BatchError(f"{path}: {what}[{index}].project: {target} is not a project folder "
                                 "(no project.json; make one with 'toonmotion rig')")
        elif key == "bvh" and target.is_dir():
            pass  # a folder of clips (:func:`_clips`)
        elif not target.is_file():
            raise BatchError(f"{path}: {what}[{index}].{key}: no such file {target}")
        changes[key] = str(target)
    return entry.model_copy(update=changes)


def output_name(character: str, motion: str, output: OutputModel, format: str) -> str:
    """The file an output task writes for ``format``: ``hero-walk.gif``, ``hero-walk-small.glb``.

    >>> output_name("hero", "walk", OutputModel(formats=["gif"]), "gif")
    'hero-walk.gif'
    >>> output_name("hero", "walk", OutputModel(name="small", formats=["spine"]), "spine")
    'hero-walk-small-spine.json'
    """
    stem = f"{character}-{motion}" + (f"-{output.name}" if output.name else "")
    return stem + FORMATS[format]
