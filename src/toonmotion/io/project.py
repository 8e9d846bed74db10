"""Project folders: ``project.json`` beside the drawing's image assets.

A project is a folder::

    hero/
      project.json            versioned, human-readable; everything but the pixels
      texture-<hash>.png      the drawing (RGBA)
      mask-<hash>.png         the figure's mask

Saving is safe at every moment: image assets are named by their content and written first,
``project.json`` is written to a temporary file and renamed over the old one last, and only then
are assets no longer referenced removed. Other files in the folder are left alone. Loading
validates the schema (pydantic) and the cross-references (indices, sizes), and a save followed
by a load gives back exactly the same arrays, so a second save writes the same bytes.
"""

import hashlib
import json
import re
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from toonmotion import __version__
from toonmotion.errors import ProjectError, ProjectVersionError, ToonmotionError
from toonmotion.io.atomic import write_bytes, write_text
from toonmotion.io.image import load_image, png_bytes
from toonmotion.io.skeleton_json import skeleton_from_dict, skeleton_to_dict
from toonmotion.rig.binding import Correction, binding_from_bones
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.edits import DepthEdit
from toonmotion.shape.curve_skeleton import NODE_KINDS, CurveSkeleton
from toonmotion.shape.mesh import Mesh, check_mesh
from toonmotion.shape.silhouette import Part, Silhouette

FORMAT = "toonmotion.project"
VERSION = 3
# Version 1 had no depth layers; it loads with every region at depth 0. Versions 1 and 2 kept
# corrections in the binding and depth as a result only; they load as an edit history of the
# corrections followed by a depth edit per region not at depth 0.
READABLE = (1, 2, 3)
PROJECT_FILE = "project.json"

Point = tuple[float, float]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


class _Part(_Model):
    outer: list[Point]
    holes: list[list[Point]] = []


class _Silhouette(_Model):
    tolerance: float = Field(ge=0)
    parts: list[_Part]


class _Node(_Model):
    position: Point
    kind: Literal[NODE_KINDS]  # type: ignore[valid-type]
    radius: float = Field(ge=0)


class _Branch(_Model):
    nodes: tuple[int, int]
    path: list[Point] = Field(min_length=2)


class _CurveSkeleton(_Model):
    nodes: list[_Node]
    branches: list[_Branch]


class _Joint(_Model):
    name: str = Field(min_length=1)
    parent: str | None
    position: Point


class _Skeleton(_Model):
    joints: list[_Joint] = Field(min_length=1)


class _Mesh(_Model):
    spacing: float = Field(gt=0)
    vertices: list[Point] = Field(min_length=3)
    triangles: list[tuple[int, int, int]] = Field(min_length=1)
    boundary: list[list[int]] = Field(min_length=1)


class _Correction(_Model):
    bone: str
    curve: list[Point] = Field(min_length=3)


class _Binding(_Model):
    bones: list[str]
    vertex_bone: list[int]
    fallback: list[int] = []
    corrections: list[_Correction] = []  # versions 1 and 2; version 3 keeps them in edits


class _CorrectionEdit(_Correction):
    kind: Literal["correction"]


class _DepthEdit(_Model):
    kind: Literal["depth"]
    value: int
    bone: str | None = None
    at: Point | None = None


_Edit = Annotated[_CorrectionEdit | _DepthEdit, Field(discriminator="kind")]


class _Settings(_Model):
    spacing: float | None = None
    vertices: int | None = None
    tolerance: float | None = None
    refine_joints: bool = False
    largest_only: bool = False
    min_part: float = 0.01
    prune: float = 0.5
    max_bone: float | None = None
    segmentation: str = "auto"


class _Project(_Model):
    format: Literal["toonmotion.project"]
    version: Literal[1, 2, 3]
    toonmotion: str
    width: int = Field(gt=0)
    height: int = Field(gt=0)
    texture: str
    mask: str
    settings: _Settings
    silhouette: _Silhouette
    curve_skeleton: _CurveSkeleton
    skeleton: _Skeleton
    mesh: _Mesh
    binding: _Binding
    depth: dict[str, int] = {}
    edits: list[_Edit] = []
    undone: list[_Edit] = []


def save_project(path, character):
    """Save a character as a project folder (created if needed).

    Parameters
    ----------
    path : str or Path
        The project folder. If it exists it must be a folder; a project in it is replaced.
    character : Character
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise ProjectError(f"{folder} is a file; a project is a folder, so give a folder path")
    folder.mkdir(parents=True, exist_ok=True)
    old = _referenced_assets(folder)
    assets, written, saved = {}, [], False
    try:
        for kind, array in (("texture", character.texture), ("mask", character.mask)):
            data = png_bytes(array)
            name = f"{kind}-{hashlib.sha256(data).hexdigest()[:16]}.png"
            if not (folder / name).is_file():
                write_bytes(folder / name, data)
                written.append(folder / name)
            assets[kind] = name
        text = _dumps(_to_dict(character, assets))
        write_text(folder / PROJECT_FILE, text)
        saved = True
    finally:
        if not saved:  # leave the folder as it was: no assets nothing refers to
            for file in written:
                file.unlink(missing_ok=True)
    for name in old - set(assets.values()):
        (folder / name).unlink(missing_ok=True)


def load_project(path):
    """Load a project folder (or its ``project.json``) as a :class:`Character`."""
    path = Path(path)
    file = path / PROJECT_FILE if path.is_dir() else path
    folder = file.parent
    data = _read_json(file)
    _check_version(data, file)
    try:
        model = _Project.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise ProjectError(f"{file} is not a valid project: {where}: {first['msg']}") from None
    try:
        return _from_model(model, folder)
    except ProjectError:
        raise
    except ToonmotionError as error:
        raise ProjectError(f"{file} is not a valid project: {error}") from None


def _read_json(file):
    if not file.is_file():
        raise ProjectError(f"no project at {file}: give a project folder made by 'toonmotion rig'")
    try:
        return json.loads(file.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise ProjectError(f"cannot read {file}: {error}") from None


def _check_version(data, file):
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ProjectError(f"{file} is not a toonmotion project (no 'format': {FORMAT!r})")
    version = data.get("version")
    if version in READABLE:
        return
    if isinstance(version, int) and version > VERSION:
        raise ProjectVersionError(
            f"{file} is project version {version}, newer than this toonmotion "
            f"{__version__} reads (version {VERSION}); upgrade toonmotion"
        )
    raise ProjectVersionError(
        f"{file} has unknown project version {version!r}; this toonmotion reads versions "
        f"{', '.join(map(str, READABLE))}"
    )


_NUMBER_LIST = re.compile(r"\[\s+([-+0-9.eE,\s]+?)\s+\]")


def _dumps(data):
    """Indented JSON with every innermost list of numbers on one line (a point per line)."""
    text = json.dumps(data, indent=1, allow_nan=False)
    return _NUMBER_LIST.sub(lambda m: "[" + " ".join(m.group(1).split()) + "]", text) + "\n"


def _referenced_assets(folder):
    file = folder / PROJECT_FILE
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
        return {data["texture"], data["mask"]} & {p.name for p in folder.glob("*.png")}
    except (OSError, ValueError, KeyError, TypeError):
        return set()


def _float_or_none(value):
    return None if value is None else float(value)


def _points(array):
    return np.asarray(array, dtype=float).tolist()


def _to_dict(ch, assets):
    s = ch.settings
    bone_names = ch.skeleton.bone_names
    return {
        "format": FORMAT,
        "version": VERSION,
        "toonmotion": __version__,
        "width": ch.size[0],
        "height": ch.size[1],
        "texture": assets["texture"],
        "mask": assets["mask"],
        # Typed as loading types them, so an int spacing is saved as 4.0 the first time too.
        "settings": {
            "spacing": _float_or_none(s.spacing),
            "vertices": None if s.vertices is None else int(s.vertices),
            "tolerance": _float_or_none(s.tolerance),
            "refine_joints": bool(s.refine_joints),
            "largest_only": bool(s.largest_only),
            "min_part": float(s.min_part),
            "prune": float(s.prune),
            "max_bone": _float_or_none(s.max_bone),
            "segmentation": str(s.segmentation),
        },
        "silhouette": {
            "tolerance": ch.silhouette.tolerance,
            "parts": [
                {"outer": _points(p.outer), "holes": [_points(h) for h in p.holes]}
                for p in ch.silhouette.parts
            ],
        },
        "curve_skeleton": {
            "nodes": [
                {"position": _points(xy), "kind": kind, "radius": float(r)}
                for xy, kind, r in zip(
                    ch.curve_skeleton.nodes,
                    ch.curve_skeleton.kinds,
                    ch.curve_skeleton.radius,
                    strict=True,
                )
            ],
            "branches": [
                {"nodes": [int(a), int(b)], "path": _points(path)}
                for (a, b), path in zip(
                    ch.curve_skeleton.branches, ch.curve_skeleton.paths, strict=True
                )
            ],
        },
        "skeleton": {"joints": skeleton_to_dict(ch.skeleton)},
        "mesh": {
            "spacing": ch.mesh.spacing,
            "vertices": _points(ch.mesh.V),
            "triangles": ch.mesh.F.tolist(),
            "boundary": [loop.tolist() for loop in ch.mesh.boundary],
        },
        "binding": {
            "bones": list(bone_names),
            "vertex_bone": ch.binding.bone.tolist(),
            "fallback": np.flatnonzero(ch.binding.fallback).tolist(),
        },
        "depth": {name: int(d) for name, d in zip(bone_names, ch.depth, strict=True)},
        "edits": [_edit_to_dict(e) for e in ch.edits],
        "undone": [_edit_to_dict(e) for e in ch.undone],
    }


def _edit_to_dict(edit):
    if isinstance(edit, Correction):
        return {"kind": "correction", "bone": edit.bone, "curve": _points(edit.curve)}
    out = {"kind": "depth", "value": edit.value}
    if edit.bone is not None:
        out["bone"] = edit.bone
    else:
        out["at"] = list(edit.at)
    return out


def _edit_from_model(m, bone_names):
    if m.kind == "correction":
        edit = Correction(curve=np.array(m.curve, dtype=float), bone=m.bone)
    else:
        try:
            edit = DepthEdit(value=m.value, bone=m.bone, at=m.at)
        except ToonmotionError as error:
            raise ProjectError(f"a depth edit is malformed: {error}") from None
    if getattr(edit, "bone", None) is not None and edit.bone not in bone_names:
        raise ProjectError(f"an edit names an unknown bone {edit.bone!r}")
    return edit


def _from_model(m, folder):
    size = (m.width, m.height)
    texture = load_image(folder / m.texture)
    mask = load_image(folder / m.mask)[..., 0] >= 128
    for name, shape in (("texture", texture.shape), ("mask", mask.shape)):
        if (shape[1], shape[0]) != size:
            raise ProjectError(
                f"the project's {name} is {shape[1]}x{shape[0]} but the project says "
                f"{size[0]}x{size[1]}; the folder's images were changed or mixed up"
            )
    silhouette = Silhouette(
        parts=tuple(
            Part(outer=np.array(p.outer, dtype=float), holes=tuple(np.array(h) for h in p.holes))
            for p in m.silhouette.parts
        ),
        tolerance=m.silhouette.tolerance,
    )
    curve_skeleton = _curve_skeleton(m.curve_skeleton)
    skeleton = skeleton_from_dict([j.model_dump() for j in m.skeleton.joints])
    mesh = _mesh(m.mesh)
    names = skeleton.bone_names
    unknown = set(m.depth) - set(names)
    if unknown:
        raise ProjectError(f"the depth layers name an unknown bone {sorted(unknown)[0]!r}")
    edits = tuple(_edit_from_model(e, names) for e in m.edits)
    undone = tuple(_edit_from_model(e, names) for e in m.undone)
    if m.version < 3:
        corrections = tuple(_edit_from_model(_CorrectionEdit(kind="correction", **c.model_dump()), names)
                            for c in m.binding.corrections)
        edits = corrections + tuple(DepthEdit(value=m.depth[n], bone=n) for n in names
                                    if m.depth.get(n, 0) != 0)
    elif m.binding.corrections:
        raise ProjectError("a version 3 project keeps its corrections in 'edits', not in the binding")
    binding = _binding(m.binding, mesh, skeleton,
                       tuple(e for e in edits if isinstance(e, Correction)))
    return Character(
        texture=texture,
        mask=mask,
        silhouette=silhouette,
        curve_skeleton=curve_skeleton,
        skeleton=skeleton,
        mesh=mesh,
        binding=binding,
        settings=RigSettings(**m.settings.model_dump()),
        depth=[m.depth.get(name, 0) for name in skeleton.bone_names],
        edits=edits,
        undone=undone,
    )


def _curve_skeleton(m):
    k = len(m.nodes)
    if any(not (0 <= i < k) for b in m.branches for i in b.nodes):
        raise ProjectError("a curve-skeleton branch names a node that does not exist")
    return CurveSkeleton(
        nodes=np.array([n.position for n in m.nodes], dtype=float).reshape(-1, 2),
        kinds=tuple(n.kind for n in m.nodes),
        radius=np.array([n.radius for n in m.nodes], dtype=float),
        branches=np.array([b.nodes for b in m.branches], dtype=np.int64).reshape(-1, 2),
        paths=tuple(np.array(b.path, dtype=float) for b in m.branches),
    )


def _mesh(m):
    V = np.array(m.vertices, dtype=float)
    F = np.array(m.triangles, dtype=np.int64)
    boundary = tuple(np.array(loop, dtype=np.int64) for loop in m.boundary)
    n_outline = sum(len(loop) for loop in boundary)
    if F.min() < 0 or F.max() >= len(V):
        raise ProjectError("a mesh triangle names a vertex that does not exist")
    if not np.array_equal(np.concatenate(boundary), np.arange(n_outline)):
        raise ProjectError("the mesh outline loops must list vertices 0, 1, 2, ... in order")
    mesh = Mesh(V=V, F=F, boundary=boundary, spacing=m.spacing)
    problems = check_mesh(mesh)
    if problems:
        raise ProjectError(f"the project's mesh is broken: {problems[0]}")
    return mesh


def _binding(m, mesh, skeleton, corrections):
    if tuple(m.bones) != skeleton.bone_names:
        raise ProjectError("the binding's bone list does not match the skeleton's bones")
    bone = np.array(m.vertex_bone, dtype=np.int64)
    if len(bone) != len(mesh.V):
        raise ProjectError(
            f"the binding has {len(bone)} vertices but the mesh has {len(mesh.V)}"
        )
    if len(bone) and (bone.min() < 0 or bone.max() >= len(m.bones)):
        raise ProjectError("the binding names a bone that does not exist")
    fallback = np.zeros(len(bone), dtype=bool)
    if m.fallback and not all(0 <= i < len(bone) for i in m.fallback):
        raise ProjectError("the binding's fallback list names a vertex that does not exist")
    fallback[m.fallback] = True
    return binding_from_bones(mesh, bone, fallback, corrections)
