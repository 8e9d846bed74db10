"""The joints file that starts tracking (``toonmotion track --joints JOINTS.json``): JSON, versioned.

``{"format": "toonmotion.joints", "version": 1, "frame": 0, "size": [w, h],
"joints": [{"name": ..., "parent": ... or null, "position": [x, y], "size": [w, h]}, ...]}``

``frame`` (optional, default 0) is the frame the positions are given for. Each joint's
``size`` is the width and height of the rectangle tracked around it, in pixels; a joint
without one takes the file's ``size``, or 16 x 16 when the file has none either. Joints are
as in the skeleton file (:mod:`toonmotion.io.skeleton_json`). Sizes are returned in the
skeleton's joint order (parents first), which need not be the file's order.

Problems with the file (missing, not JSON, wrong format or version, wrong types, bad sizes or
frame) are :class:`TrackingError`; problems with the skeleton the joints make (a joint without
a name or position, unknown parents, cycles, repeated names) are :class:`SkeletonError`.
"""

from __future__ import annotations

import json
from numbers import Integral, Real
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field
from pydantic_core import ErrorDetails

from toonmotion.errors import SkeletonError, ToonmotionError, TrackingError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import (
    Float,
    Int,
    Joint,
    JsonFormat,
    Model,
    explained,
    joint_needs,
    read_versioned,
)
from toonmotion.io.skeleton_json import skeleton_from_joints, skeleton_to_dict
from toonmotion.rig.skeleton import Skeleton

FORMAT = "toonmotion.joints"
VERSION = 1
DEFAULT_SIZE = (16.0, 16.0)

_SIZE_HINT = "give [width, height] in pixels, both above 0"

# Width and height of a rectangle, pixels; the explaining validator names its owner.
_Size = tuple[Annotated[Float, Field(gt=0)], Annotated[Float, Field(gt=0)]]


def _joint_problem(value: Any, errors: list[ErrorDetails]) -> tuple[str, type[ToonmotionError]] | None:
    loc = errors[0]["loc"]
    if loc and loc[0] == "size" and isinstance(value.get("name"), str):
        return f"the 'size' of joint {value['name']!r} is {value['size']!r}; {_SIZE_HINT}", TrackingError
    if joint_needs(value, errors):
        return "joint {n} needs a 'name' and a 'position: [x, y]'", SkeletonError
    return None


def _frame_problem(value: Any, errors: list[ErrorDetails]) -> str:
    return f"'frame' must be a whole number >= 0, got {value!r}"


def _size_problem(value: Any, errors: list[ErrorDetails]) -> str:
    return f"the file's 'size' is {value!r}; {_SIZE_HINT}"


class JointWithSize(Joint):
    """A joint and the size of the rectangle tracked around it."""

    size: _Size | None = None


class JointsFile(Model):
    """A joints file (see the module docstring)."""

    format: Literal["toonmotion.joints"]
    version: Literal[1]
    frame: Annotated[Int, Field(ge=0), explained(_frame_problem)] = 0
    size: Annotated[_Size, explained(_size_problem)] | None = None
    joints: Annotated[
        list[Annotated[JointWithSize, explained(_joint_problem)]],
        explained("'joints' must be a list of {name, parent, position, size} objects", error=SkeletonError),
    ]


JOINTS = JsonFormat(models={FORMAT: JointsFile}, version=VERSION, error=TrackingError,
                    title="toonmotion joints file", label="joints format", what="joints file ")


def load_joints(path: str | Path) -> tuple[Skeleton, NDArray[np.float64], int]:
    """Read a joints file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    skeleton : Skeleton
        The joints at their positions in frame ``frame``.
    sizes : (k, 2) float
        Width and height of each joint's rectangle, in skeleton joint order.
    frame : int
        The frame the positions are given for.
    """
    path = Path(path)
    model = read_versioned(path, JOINTS)
    skeleton = skeleton_from_joints(model.joints, where=path)
    default = DEFAULT_SIZE if model.size is None else model.size
    size_of = {joint.name: default if joint.size is None else joint.size for joint in model.joints}
    sizes = np.array([size_of[name] for name in skeleton.names], dtype=float).reshape(-1, 2)
    return skeleton, sizes, model.frame


def save_joints(path: str | Path, skeleton: Skeleton, sizes: ArrayLike, frame: int = 0) -> None:
    """Write a joints file atomically, every joint with its own size.

    Parameters
    ----------
    path : str or Path
    skeleton : Skeleton
    sizes : (k, 2) float
        Width and height of each joint's rectangle, in skeleton joint order.
    frame : int
        The frame the positions are given for.
    """
    sizes = np.asarray(sizes, dtype=float)
    if sizes.shape != (len(skeleton), 2):
        raise TrackingError(
            f"give a (width, height) for each of the {len(skeleton)} joints; got sizes of shape {sizes.shape}"
        )
    if isinstance(frame, bool) or not isinstance(frame, Integral) or frame < 0:
        raise TrackingError(f"the frame must be a whole number >= 0, got {frame!r}")
    joints = skeleton_to_dict(skeleton)
    for joint, size in zip(joints, sizes, strict=True):
        joint["size"] = list(_size(size.tolist(), f"the size of joint {joint['name']!r}"))
    data = {"format": FORMAT, "version": VERSION, "frame": int(frame), "joints": joints}
    write_text(path, json.dumps(data, indent=1) + "\n")


def _size(value: list[float], what: str) -> tuple[float, float]:
    """``(w, h)`` floats; TrackingError unless two finite numbers above 0."""
    if len(value) != 2 or not all(isinstance(v, Real) and np.isfinite(v) and v > 0 for v in value):
        raise TrackingError(f"{what} is {value!r}; {_SIZE_HINT}")
    return float(value[0]), float(value[1])
