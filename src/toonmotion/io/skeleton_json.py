"""toonmotion's own skeleton file: JSON, versioned.

``{"format": "toonmotion.skeleton", "version": 1, "width": W, "height": H,
"joints": [{"name": ..., "parent": ... or null, "position": [x, y]}, ...]}``
(width and height are optional: the drawing the joints were placed on).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from toonmotion import limits
from toonmotion.errors import SkeletonError, ToonmotionError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import Int, Joint, Joints, JsonFormat, Model, explained, read_versioned, validate
from toonmotion.rig.skeleton import Skeleton

FORMAT = "toonmotion.skeleton"
VERSION = 1

_Pixels = Annotated[Int, Field(gt=0), explained("width and height must be whole numbers of pixels above 0")]


class SkeletonFile(Model):
    """A skeleton file (see the module docstring)."""

    format: Literal["toonmotion.skeleton"]
    version: Literal[1]
    width: _Pixels | None = None
    height: _Pixels | None = None
    joints: Joints

    @model_validator(mode="after")
    def _width_with_height(self) -> SkeletonFile:
        if (self.width is None) != (self.height is None):
            raise PydanticCustomError("size", "give the drawing's width and height both, or neither")
        return self


SKELETON = JsonFormat(models={FORMAT: SkeletonFile}, version=VERSION, error=SkeletonError,
                      title="toonmotion skeleton file", label="skeleton format")


def skeleton_to_dict(skeleton: Skeleton) -> list[dict[str, Any]]:
    """The ``joints`` list of a skeleton, as JSON-ready dicts, parents first."""
    return [
        {"name": name, "parent": parent, "position": [x, y]}
        for name, parent, (x, y) in skeleton.joints()
    ]


def skeleton_from_joints(joints: Sequence[Joint], *, where: str | Path | None = None,
                         error: type[ToonmotionError] = SkeletonError) -> Skeleton:
    """Build a Skeleton from validated joints.

    Cycles, unknown parents and repeated names raise ``error`` (a :class:`SkeletonError` by
    default), its message starting ``"{where}: "`` when ``where`` (the file) is given.
    """
    try:
        return Skeleton.from_joints((joint.name, joint.parent, joint.position) for joint in joints)
    except SkeletonError as problem:
        raise error(problem.args[0] if where is None else f"{where}: {problem}") from None


def skeleton_from_dict(joints: Any, *, where: str = "skeleton") -> Skeleton:
    """Build a Skeleton from a ``joints`` list as written by :func:`skeleton_to_dict`.

    Raises :class:`SkeletonError` naming ``where`` if the list is malformed.
    """
    return skeleton_from_joints(validate(Joints, joints, where=where, error=SkeletonError))


def load_skeleton_json(path: str | Path) -> tuple[Skeleton, tuple[int, int] | None]:
    """Read a skeleton JSON file; returns ``(skeleton, (width, height) or None)``."""
    path = Path(path)
    model = read_versioned(path, SKELETON)
    size = None if model.width is None or model.height is None else (model.width, model.height)
    return skeleton_from_joints(model.joints, where=path), size


def save_skeleton_json(path: str | Path, skeleton: Skeleton, size: tuple[int, int] | None = None) -> None:
    """Write a skeleton JSON file atomically."""
    data: dict[str, Any] = {"format": FORMAT, "version": VERSION}
    if size is not None:
        data.update(width=int(size[0]), height=int(size[1]))
    data["joints"] = skeleton_to_dict(skeleton)
    write_text(path, json.dumps(data, indent=1) + "\n")


def load_skeleton_file(path: str | Path, *, image_size: tuple[int, int] | None = None) -> Skeleton:
    """Read a skeleton from a char_cfg ``.yaml``/``.yml`` or a toonmotion ``.json`` file.

    Parameters
    ----------
    image_size : (width, height), optional
        The drawing's size; a file annotated on a drawing of another size is an error.
    """
    from toonmotion.io.char_cfg import load_char_cfg

    path = Path(path)
    suffix = path.suffix.lower()
    if path.is_file():  # a missing file is the readers' to tell
        limits.check("skeleton_bytes", path.stat().st_size, f"{path.name}'s size in bytes")
    if suffix in (".yaml", ".yml"):
        skeleton, size = load_char_cfg(path)
    elif suffix == ".json":
        skeleton, size = load_skeleton_json(path)
    else:
        raise SkeletonError(
            f"cannot tell the skeleton format of {path.name}: use a char_cfg .yaml or a .json file"
        )
    if image_size is not None and size is not None and tuple(size) != tuple(image_size):
        raise SkeletonError(
            f"{path.name} was made for a {size[0]}x{size[1]} drawing but this one is "
            f"{image_size[0]}x{image_size[1]}; use the skeleton made for this drawing"
        )
    return skeleton
