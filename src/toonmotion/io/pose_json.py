"""Pose and key-frame files: JSON, versioned.

A pose gives every joint a position, by name::

    {"format": "toonmotion.pose", "version": 1, "joints": {"neck": [231, 119], ...}}

A skeleton file (``toonmotion.skeleton``, see ``skeleton_json``) is read as a pose too, so a
skeleton sketched in any editor can be used directly. Key-frames put poses on a timeline::

    {"format": "toonmotion.keyframes", "version": 1, "fps": 12, "ease": "in-out",
     "keys": [{"frame": 0, "joints": {...}}, {"frame": 12, "rest": true}, ...]}

``"rest": true`` stands for the character's rest pose.

A pose or a key may carry fine-tuning edits, applied in order after it is deformed (see
``deform.tuning``); points are drawing pixels::

    "edits": [{"kind": "curve", "points": [[x, y], ...]},
              {"kind": "drag", "from": [[x, y], ...], "to": [[x, y], ...]}]

The file models check types; which joints a pose must name, and how many points an edit
needs, are checked against the skeleton and by the edits themselves.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, StrictBool, StrictStr, model_validator
from pydantic_core import ErrorDetails

from toonmotion.animate.timeline import Keyframe, Timeline, make_timeline
from toonmotion.deform.tuning import CurveEdit, DragEdit, TuningEdit
from toonmotion.errors import EditError, KeyframeError, PoseError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import (
    Float,
    Int,
    JsonFormat,
    Model,
    Point,
    explained,
    location,
    parse_versioned,
    problem,
    read_json,
    read_versioned,
    validate,
)
from toonmotion.io.skeleton_json import FORMAT as SKELETON_FORMAT
from toonmotion.io.skeleton_json import SkeletonFile
from toonmotion.rig.pose import Pose, pose_from_joints, pose_to_joints, rest_pose
from toonmotion.rig.skeleton import Skeleton

POSE_FORMAT = "toonmotion.pose"
KEYS_FORMAT = "toonmotion.keyframes"
VERSION = 1


def _position_problem(value: Any, errors: list[ErrorDetails]) -> str:
    if not isinstance(value, dict):
        return "joints must be a mapping of joint name to [x, y]"
    name = errors[0]["loc"][0]
    finite = "finite " if errors[0]["type"] == "finite_number" else ""
    return f"joint {name!r} has position {value[name]!r}; give two {finite}numbers [x, y]"


# Joint name -> [x, y].
JointPositions = Annotated[dict[str, Point], explained(_position_problem, error=PoseError)]


class CurveEditModel(Model):
    """A sketch curve the outline is pulled onto."""

    kind: Literal["curve"]
    points: list[Point]


class DragEditModel(Model):
    """Outline points dragged from ``from`` to ``to``."""

    kind: Literal["drag"]
    start: list[Point] = Field(alias="from")
    end: list[Point] = Field(alias="to")


_POINTS = {"points": "a sketch curve", "from": "a drag's start points", "to": "a drag's end points"}


def _edit_problem(value: Any, errors: list[ErrorDetails]) -> str:
    first = errors[0]
    loc = first["loc"]
    if first["type"].startswith("union_tag") or not loc:
        kind = value.get("kind") if isinstance(value, dict) else None
        return f"edit {{n}} has kind {kind!r}; use 'curve' or 'drag'"
    if len(loc) > 1 and loc[1] in _POINTS:
        return f"edit {{n}} {_POINTS[str(loc[1])]} must be a list of [x, y] points"
    return f"edit {{n}}: {location(loc[1:])}: {first['msg']}"


# Fine-tuning edits, in the order they apply.
Edits = Annotated[
    list[Annotated[CurveEditModel | DragEditModel, Field(discriminator="kind"),
                   explained(_edit_problem, error=EditError)]],
    explained("'edits' must be a list of curve and drag edits", error=EditError),
]


class PoseFile(Model):
    """A pose file (see the module docstring)."""

    format: Literal["toonmotion.pose"]
    version: Literal[1]
    joints: JointPositions
    edits: Edits = []


def _key_needs(value: Any, errors: list[ErrorDetails]) -> str | None:
    loc = errors[0]["loc"]
    if not loc or (errors[0]["type"] == "missing" and loc == ("frame",)):
        return "key {n} needs a 'frame' number"
    return None


class KeyModel(Model):
    """One key of a key-frames file."""

    frame: Int
    rest: StrictBool = False
    joints: JointPositions | None = None
    edits: Edits = []

    @model_validator(mode="after")
    def _has_a_pose(self) -> KeyModel:
        if not self.rest and self.joints is None:
            raise problem(f"key at frame {self.frame} needs 'joints' (or 'rest': true)")
        return self


class KeyframesFile(Model):
    """A key-frames file (see the module docstring)."""

    format: Literal["toonmotion.keyframes"]
    version: Literal[1]
    fps: Float = 24.0
    ease: StrictStr = "linear"
    keys: Annotated[
        list[Annotated[KeyModel, explained(_key_needs)]],
        explained("'keys' must be a list of {'frame': N, 'joints': {...}}"),
    ]


POSE = JsonFormat[PoseFile | SkeletonFile](
    models={POSE_FORMAT: PoseFile, SKELETON_FORMAT: SkeletonFile}, version=VERSION, error=PoseError,
    title="pose file", label="format",
)
KEYFRAMES = JsonFormat(models={KEYS_FORMAT: KeyframesFile}, version=VERSION, error=KeyframeError,
                       title="key-frames file", label="format")



def load_pose(path: str | Path, skeleton: Skeleton) -> Pose:
    """Read a pose (or skeleton) file for ``skeleton``; returns a :class:`Pose`."""
    path = Path(path)
    model = read_versioned(path, POSE)
    if isinstance(model, SkeletonFile):
        joints = {joint.name: joint.position for joint in model.joints}
    else:
        joints = dict(model.joints)
    return pose_from_joints(skeleton, joints, where=str(path))


def load_pose_edits(path: str | Path) -> tuple[TuningEdit, ...]:
    """The fine-tuning edits of a pose file, a tuple (empty for a skeleton file or none)."""
    path = Path(path)
    data = read_json(path, PoseError)
    if not isinstance(data, dict) or data.get("format") != POSE_FORMAT:
        return ()
    model = parse_versioned(data, path, POSE)
    return _edits(model.edits if isinstance(model, PoseFile) else [], where=str(path))


def save_pose(path: str | Path, skeleton: Skeleton, pose: Pose, edits: Sequence[TuningEdit] = ()) -> None:
    """Write ``pose`` (and its fine-tuning ``edits``) as a pose file."""
    data: dict[str, Any] = {"format": POSE_FORMAT, "version": VERSION,
                            "joints": pose_to_joints(skeleton, pose)}
    if edits:
        data["edits"] = edits_to_json(edits)
    write_text(path, json.dumps(data, indent=1) + "\n")


def edits_to_json(edits: Sequence[TuningEdit]) -> list[dict[str, Any]]:
    """Fine-tuning edits as JSON-ready dicts."""
    out = []
    for edit in edits:
        if isinstance(edit, CurveEdit):
            out.append({"kind": "curve", "points": edit.points.tolist()})
        else:
            out.append({"kind": "drag", "from": edit.start.tolist(), "to": edit.end.tolist()})
    return out


def edits_from_json(items: Any, *, where: str) -> tuple[TuningEdit, ...]:
    """Fine-tuning edits from their JSON dicts; :class:`EditError` naming ``where`` if malformed."""
    return _edits(validate(Edits, items, where=where, error=EditError), where=where)


def _edits(models: Sequence[CurveEditModel | DragEditModel], *, where: str) -> tuple[TuningEdit, ...]:
    out: list[TuningEdit] = []
    for n, m in enumerate(models, start=1):
        try:
            if isinstance(m, CurveEditModel):
                out.append(CurveEdit(points=np.array(m.points, dtype=float)))
            else:
                out.append(DragEdit(start=np.array(m.start, dtype=float), end=np.array(m.end, dtype=float)))
        except EditError as error:
            raise EditError(f"{where}: edit {n} {error}") from None
    return tuple(out)


def load_keyframes(path: str | Path, skeleton: Skeleton, *, fps: float | None = None) -> Timeline:
    """Read a key-frames file for ``skeleton``; returns a :class:`Timeline`.

    ``fps`` overrides the file's frame rate (default 24 when the file gives none).
    """
    path = Path(path)
    model = read_versioned(path, KEYFRAMES)
    out = []
    for key in model.keys:
        where = f"{path}: key at frame {key.frame}"
        if key.rest:
            pose = rest_pose(skeleton)
        else:
            pose = pose_from_joints(skeleton, dict(key.joints or {}), where=where)
        out.append(Keyframe(frame=key.frame, pose=pose, edits=_edits(key.edits, where=where)))
    try:
        return make_timeline(skeleton, out, fps=model.fps if fps is None else fps, ease=model.ease)
    except KeyframeError as error:
        raise KeyframeError(f"{path}: {error}") from None


def save_keyframes(path: str | Path, skeleton: Skeleton, timeline: Timeline) -> None:
    """Write a :class:`Timeline` as a key-frames file."""
    data = {
        "format": KEYS_FORMAT,
        "version": VERSION,
        "fps": timeline.fps,
        "ease": timeline.ease,
        "keys": [_key_to_json(skeleton, k) for k in timeline.keys],
    }
    write_text(path, json.dumps(data, indent=1) + "\n")


def _key_to_json(skeleton: Skeleton, key: Keyframe) -> dict[str, Any]:
    out = {"frame": key.frame, "joints": pose_to_joints(skeleton, key.pose)}
    if key.edits:
        out["edits"] = edits_to_json(key.edits)
    return out
