"""The project file's schema (``project.json``, :mod:`toonmotion.io.project`): its pydantic models,
its format and version, and the steps that bring a version 1 or 2 file up to version 3."""

from __future__ import annotations

import dataclasses
import typing
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, StrictStr, create_model, model_validator

from toonmotion import __version__
from toonmotion.errors import ProjectError, ProjectVersionError, ToonmotionError
from toonmotion.io.schema import (
    Float,
    Int,
    Joints,
    JsonFormat,
    Model,
    Point,
    problem,
    read_json,
)
from toonmotion.rig.character import RigSettings
from toonmotion.shape.curve_skeleton import NODE_KINDS

FORMAT = "toonmotion.project"


VERSION = 3


class PartModel(Model):
    outer: list[Point]
    holes: list[list[Point]] = []


class SilhouetteModel(Model):
    tolerance: Annotated[Float, Field(ge=0)]
    parts: list[PartModel]


class NodeModel(Model):
    position: Point
    kind: Literal[NODE_KINDS]  # type: ignore[valid-type]
    radius: Annotated[Float, Field(ge=0)]


class BranchModel(Model):
    nodes: tuple[Int, Int]
    path: list[Point] = Field(min_length=2)


class CurveSkeletonModel(Model):
    nodes: list[NodeModel]
    branches: list[BranchModel]


class SkeletonModel(Model):
    joints: Joints


class MeshModel(Model):
    spacing: Annotated[Float, Field(gt=0)]
    vertices: list[Point] = Field(min_length=3)
    triangles: list[tuple[Int, Int, Int]] = Field(min_length=1)
    boundary: list[list[Int]] = Field(min_length=1)


class BindingModel(Model):
    bones: list[StrictStr]
    vertex_bone: list[Int]
    fallback: list[Int] = []

    @model_validator(mode="before")
    @classmethod
    def _corrections_are_edits(cls, data: Any) -> Any:
        if isinstance(data, dict) and "corrections" in data:
            raise problem("a version 3 project keeps its corrections in 'edits', not in the binding")
        return data


class CorrectionEditModel(Model):
    kind: Literal["correction"]
    bone: StrictStr
    curve: list[Point] = Field(min_length=3)


class DepthEditModel(Model):
    kind: Literal["depth"]
    value: Int
    bone: StrictStr | None = None
    at: Point | None = None


EditModel = Annotated[CorrectionEditModel | DepthEditModel, Field(discriminator="kind")]


class _Strict(Model):
    model_config = ConfigDict(strict=True)


# RigSettings' own fields, types and defaults (the dataclass checks ranges when it is built),
# but projects saved before the decomposition rule was a setting were rigged by the thesis's.
_HINTS = typing.get_type_hints(RigSettings)


_SAVED_BEFORE = {"decomposition": "straight"}


SettingsModel = create_model(  # type: ignore[call-overload]
    "SettingsModel",
    __base__=_Strict,
    **{f.name: (_HINTS[f.name], _SAVED_BEFORE.get(f.name, f.default))
       for f in dataclasses.fields(RigSettings)},
)


class ProjectFile(Model):
    """``project.json`` as this toonmotion writes it (version 3)."""

    format: Literal["toonmotion.project"]
    version: Literal[3]
    toonmotion: StrictStr
    width: Annotated[Int, Field(gt=0)]
    height: Annotated[Int, Field(gt=0)]
    texture: StrictStr
    mask: StrictStr
    settings: SettingsModel
    silhouette: SilhouetteModel
    curve_skeleton: CurveSkeletonModel
    skeleton: SkeletonModel
    mesh: MeshModel
    binding: BindingModel
    depth: dict[str, Int] = {}
    edits: list[EditModel] = []
    undone: list[EditModel] = []


def _version_1_to_2(data: dict[str, Any]) -> dict[str, Any]:
    """Version 1 had no depth layers: every region is at depth 0."""
    data.setdefault("depth", {})
    return data


def _version_2_to_3(data: dict[str, Any]) -> dict[str, Any]:
    """Versions 1 and 2 kept corrections in the binding and depth as a result only: they become
    an edit history of the corrections followed by a depth edit per region not at depth 0."""
    binding = data.get("binding")
    corrections: Any = []
    if isinstance(binding, dict) and "corrections" in binding:
        binding = dict(binding)
        corrections = binding.pop("corrections")
        data["binding"] = binding
    if not isinstance(corrections, list):
        return data  # left for validation to refuse
    edits = [{"kind": "correction", **c} if isinstance(c, dict) else c for c in corrections]
    depth, bones = data.get("depth"), binding.get("bones") if isinstance(binding, dict) else None
    if isinstance(depth, dict) and isinstance(bones, list):
        edits += [{"kind": "depth", "value": depth[bone], "bone": bone}
                  for bone in bones if isinstance(bone, str) and depth.get(bone, 0) != 0]
    data["edits"] = edits
    return data


class _ProjectFormat(JsonFormat[ProjectFile]):
    """The project format, with the messages ``toonmotion`` has always given for projects."""

    def read(self, path: Path) -> Any:
        if not path.is_file():
            raise ProjectError(f"no project at {path}: give a project folder made by 'toonmotion rig'")
        return read_json(path, ProjectError)

    def not_this_format(self, path: Path) -> ToonmotionError:
        return ProjectError(f"{path} is not a toonmotion project (no 'format': {FORMAT!r})")

    def unreadable_version(self, path: Path, version: Any) -> ToonmotionError:
        if isinstance(version, int) and not isinstance(version, bool) and version > VERSION:
            return ProjectVersionError(
                f"{path} is project version {version}, newer than this toonmotion "
                f"{__version__} reads (version {VERSION}); upgrade toonmotion"
            )
        return ProjectVersionError(
            f"{path} has unknown project version {version!r}; this toonmotion reads versions "
            f"{', '.join(map(str, self.readable))}"
        )

    def invalid(self, path: Path, text: str, error: type[ToonmotionError] | None) -> ToonmotionError:
        return ProjectError(f"{path} is not a valid project: {text}")


PROJECT = _ProjectFormat(models={FORMAT: ProjectFile}, version=VERSION, error=ProjectError,
                         title="toonmotion project", label="project",
                         migrations={1: _version_1_to_2, 2: _version_2_to_3})


READABLE = PROJECT.readable
