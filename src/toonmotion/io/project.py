"""Project folders: ``project.json`` beside the drawing's image assets.

A project is a folder::

    hero/
      project.json            versioned, human-readable; everything but the pixels
      texture-<hash>.png      the drawing (RGBA)
      mask-<hash>.png         the figure's mask

Saving is safe at every moment: image assets are named by their content and written first,
``project.json`` is written to a temporary file and renamed over the old one last, and only then
are assets no longer referenced removed. Other files in the folder are left alone. Loading
validates the schema (pydantic, :mod:`toonmotion.io.schema`) and the cross-references (indices,
sizes), and a save followed by a load gives back exactly the same arrays, so a second save writes
the same bytes. Projects of versions 1 and 2 load by stepping their JSON up to version 3 first.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
from pathlib import Path
from typing import Any

import numpy as np

from toonmotion import __version__
from toonmotion.errors import ProjectError, ToonmotionError
from toonmotion.io.atomic import write_bytes, write_text
from toonmotion.io.image import load_image, png_bytes
from toonmotion.io.project_schema import (
    FORMAT,
    PROJECT,
    VERSION,
    BindingModel,
    CorrectionEditModel,
    CurveSkeletonModel,
    DepthEditModel,
    MeshModel,
    ProjectFile,
)
from toonmotion.io.schema import (
    read_versioned,
)
from toonmotion.io.skeleton_json import skeleton_from_joints, skeleton_to_dict
from toonmotion.rig.binding import Binding, Correction, binding_from_bones
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.edits import DepthEdit
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import CurveSkeleton
from toonmotion.shape.mesh import Mesh, check_mesh
from toonmotion.shape.silhouette import Part, Silhouette

PROJECT_FILE = "project.json"


def save_project(path: str | Path, character: Character) -> None:
    """Save a character as a project folder (created if needed).

    Parameters
    ----------
    path : str or Path
        The project folder. If it exists it must be a project folder (a project in it is
        replaced) or an empty folder; if saving fails the folder is left as it was.
    character : Character

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.rig.pipeline import rig_drawing
    >>> hero = sample_rig()
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     save_project(Path(folder) / "hero", hero)
    ...     again = load_project(Path(folder) / "hero")
    >>> bool((again.mesh.V == hero.mesh.V).all() and (again.texture == hero.texture).all())
    True
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise ProjectError(f"{folder} is a file; a project is a folder, so give a folder path")
    if folder.is_dir() and not (folder / PROJECT_FILE).is_file():
        others = sorted(p.name for p in folder.iterdir()
                        if not p.name.startswith(".") and not _ASSET_NAME.fullmatch(p.name))
        if others:
            raise ProjectError(f"{folder} holds other files ({others[0]}, ...) and no project; give a new or "
                               "empty folder, or a project folder to replace")
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
    for name in (old | _asset_files(folder)) - set(assets.values()):
        (folder / name).unlink(missing_ok=True)


def _asset_files(folder: Path) -> set[str]:
    """Texture and mask files in a project folder, those of a save that was killed included."""
    return {p.name for p in folder.glob("*.png") if _ASSET_NAME.fullmatch(p.name)}


_ASSET_NAME = re.compile(r"(texture|mask)-[0-9a-f]{16}\.png")


def load_project(path: str | Path) -> Character:
    """Load a project folder (or its ``project.json``) as a :class:`Character`.

    Parameters
    ----------
    path : str or Path
        The folder :func:`save_project` wrote, or the ``project.json`` in it.

    Returns
    -------
    Character
        Exactly the character that was saved.

    Raises
    ------
    ProjectError
        Not a project, a damaged one, or one from a newer toonmotion (:class:`ProjectVersionError`).

    Examples
    --------
    See :func:`save_project`.
    """
    path = Path(path)
    if path.is_file() and path.suffix.lower() != ".json":  # a drawing given where the project goes
        raise ProjectError(f"{path} is a file, not a project: give the project folder 'toonmotion rig' made")
    file = path / PROJECT_FILE if path.is_dir() else path
    model = read_versioned(file, PROJECT)
    try:
        return _from_model(model, file.parent)
    except ProjectError:
        raise
    except (ToonmotionError, ValueError) as error:
        raise ProjectError(f"{file} is not a valid project: {error}") from None


_NUMBER_LIST = re.compile(r"\[\s+([-+0-9.eE,\s]+?)\s+\]")


def _dumps(data: dict[str, Any]) -> str:
    """Indented JSON with every innermost list of numbers on one line (a point per line)."""
    text = json.dumps(data, indent=1, allow_nan=False)
    return _NUMBER_LIST.sub(lambda m: "[" + " ".join(m.group(1).split()) + "]", text) + "\n"


def _referenced_assets(folder: Path) -> set[str]:
    file = folder / PROJECT_FILE
    try:
        data = json.loads(file.read_text(encoding="utf-8"))
        return {data["texture"], data["mask"]} & {p.name for p in folder.glob("*.png")}
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        return set()


def _points(array: Any) -> list[Any]:
    return np.asarray(array, dtype=float).tolist()


def _to_dict(ch: Character, assets: dict[str, str]) -> dict[str, Any]:
    bone_names = ch.skeleton.bone_names
    return {
        "format": FORMAT,
        "version": VERSION,
        "toonmotion": __version__,
        "width": ch.size[0],
        "height": ch.size[1],
        "texture": assets["texture"],
        "mask": assets["mask"],
        # RigSettings holds its numbers as floats, so an int spacing is saved as 4.0 too.
        "settings": dataclasses.asdict(ch.settings),
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


def _edit_to_dict(edit: Correction | DepthEdit) -> dict[str, Any]:
    if isinstance(edit, Correction):
        return {"kind": "correction", "bone": edit.bone, "curve": _points(edit.curve)}
    out: dict[str, Any] = {"kind": "depth", "value": edit.value}
    if edit.bone is not None:
        out["bone"] = edit.bone
    elif edit.at is not None:
        out["at"] = list(edit.at)
    return out


def _edit_from_model(m: CorrectionEditModel | DepthEditModel, bone_names: tuple[str, ...]
                     ) -> Correction | DepthEdit:
    edit: Correction | DepthEdit
    if isinstance(m, CorrectionEditModel):
        edit = Correction(curve=np.array(m.curve, dtype=float), bone=m.bone)
    else:
        try:
            edit = DepthEdit(value=m.value, bone=m.bone, at=m.at)
        except ToonmotionError as error:
            raise ProjectError(f"a depth edit is malformed: {error}") from None
    if edit.bone is not None and edit.bone not in bone_names:
        raise ProjectError(f"an edit names an unknown bone {edit.bone!r}")
    return edit


def _from_model(m: ProjectFile, folder: Path) -> Character:
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
    skeleton = skeleton_from_joints(m.skeleton.joints)
    mesh = _mesh(m.mesh, size)
    names = skeleton.bone_names
    unknown = set(m.depth) - set(names)
    if unknown:
        raise ProjectError(f"the depth layers name an unknown bone {sorted(unknown)[0]!r}")
    edits = tuple(_edit_from_model(e, names) for e in m.edits)
    undone = tuple(_edit_from_model(e, names) for e in m.undone)
    binding = _binding(m.binding, mesh, skeleton,
                       tuple(e for e in edits if isinstance(e, Correction)))
    depth = np.array([m.depth.get(name, 0) for name in skeleton.bone_names], dtype=np.int64)
    return Character(texture=texture, mask=mask, silhouette=silhouette, curve_skeleton=curve_skeleton,
                     skeleton=skeleton, mesh=mesh, binding=binding,
                     settings=RigSettings(**m.settings.model_dump()), depth=depth, edits=edits,
                     undone=undone)


def _curve_skeleton(m: CurveSkeletonModel) -> CurveSkeleton:
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


def _mesh(m: MeshModel, size: tuple[int, int]) -> Mesh:
    V = np.array(m.vertices, dtype=float)
    # The rest mesh is traced from the drawing's pixels: it lies on the canvas.
    outside = (V < -1.0).any(axis=1) | (V[:, 0] > size[0]) | (V[:, 1] > size[1])
    if outside.any():
        i = int(np.flatnonzero(outside)[0])
        raise ProjectError(f"mesh vertex {i} at ({V[i, 0]:.6g}, {V[i, 1]:.6g}) lies outside the "
                           f"{size[0]}x{size[1]} drawing")
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


def _binding(m: BindingModel, mesh: Mesh, skeleton: Skeleton, corrections: tuple[Correction, ...]) -> Binding:
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
