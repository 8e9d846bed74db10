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
"""

import json
from pathlib import Path

from toonmotion.animate.timeline import Keyframe, make_timeline
from toonmotion.deform.tuning import CurveEdit, DragEdit
from toonmotion.errors import EditError, KeyframeError, PoseError
from toonmotion.io.atomic import write_text
from toonmotion.io.json_file import read_json
from toonmotion.rig.pose import pose_from_joints, pose_to_joints, rest_pose

POSE_FORMAT = "toonmotion.pose"
KEYS_FORMAT = "toonmotion.keyframes"
VERSION = 1


def load_pose(path, skeleton):
    """Read a pose (or skeleton) file for ``skeleton``; returns a :class:`Pose`."""
    path = Path(path)
    data = read_json(path, PoseError)
    kind = data.get("format") if isinstance(data, dict) else None
    if kind == "toonmotion.skeleton":
        _check_version(data, path, PoseError)
        joints = data.get("joints")
        if not isinstance(joints, list) or not all(isinstance(j, dict) and "name" in j for j in joints):
            raise PoseError(f"{path}: 'joints' must be a list of {{'name', 'position'}} objects")
        return pose_from_joints(skeleton, {j["name"]: j.get("position") for j in joints}, where=str(path))
    if kind != POSE_FORMAT:
        raise PoseError(f"{path} is not a pose file (format {POSE_FORMAT!r} or 'toonmotion.skeleton')")
    _check_version(data, path, PoseError)
    return pose_from_joints(skeleton, data.get("joints"), where=str(path))


def load_pose_edits(path):
    """The fine-tuning edits of a pose file, a tuple (empty for a skeleton file or none)."""
    path = Path(path)
    data = read_json(path, PoseError)
    if not isinstance(data, dict) or data.get("format") != POSE_FORMAT:
        return ()
    return edits_from_json(data.get("edits", []), where=str(path))


def save_pose(path, skeleton, pose, edits=()):
    """Write ``pose`` (and its fine-tuning ``edits``) as a pose file."""
    data = {"format": POSE_FORMAT, "version": VERSION, "joints": pose_to_joints(skeleton, pose)}
    if edits:
        data["edits"] = edits_to_json(edits)
    write_text(path, json.dumps(data, indent=1) + "\n")


def edits_to_json(edits):
    """Fine-tuning edits as JSON-ready dicts."""
    out = []
    for edit in edits:
        if isinstance(edit, CurveEdit):
            out.append({"kind": "curve", "points": edit.points.tolist()})
        else:
            out.append({"kind": "drag", "from": edit.start.tolist(), "to": edit.end.tolist()})
    return out


def edits_from_json(items, *, where):
    """Fine-tuning edits from their JSON dicts; :class:`EditError` naming ``where`` if malformed."""
    if not isinstance(items, list):
        raise EditError(f"{where}: 'edits' must be a list")
    out = []
    for n, item in enumerate(items, start=1):
        kind = item.get("kind") if isinstance(item, dict) else None
        try:
            if kind == "curve":
                out.append(CurveEdit(points=item.get("points")))
            elif kind == "drag":
                out.append(DragEdit(start=item.get("from"), end=item.get("to")))
            else:
                raise EditError(f"has kind {kind!r}; use 'curve' or 'drag'")
        except EditError as error:
            raise EditError(f"{where}: edit {n} {error}") from None
    return tuple(out)


def load_keyframes(path, skeleton, *, fps=None):
    """Read a key-frames file for ``skeleton``; returns a :class:`Timeline`.

    ``fps`` overrides the file's frame rate (default 24 when the file gives none).
    """
    path = Path(path)
    data = read_json(path, KeyframeError)
    if not isinstance(data, dict) or data.get("format") != KEYS_FORMAT:
        raise KeyframeError(f"{path} is not a key-frames file (format {KEYS_FORMAT!r})")
    _check_version(data, path, KeyframeError)
    keys = data.get("keys")
    if not isinstance(keys, list):
        raise KeyframeError(f"{path}: 'keys' must be a list of {{'frame': N, 'joints': {{...}}}}")
    out = []
    for n, key in enumerate(keys, start=1):
        if not isinstance(key, dict) or "frame" not in key:
            raise KeyframeError(f"{path}: key {n} needs a 'frame' number")
        where = f"{path}: key at frame {key['frame']}"
        if key.get("rest") is True:
            pose = rest_pose(skeleton)
        elif "joints" in key:
            pose = pose_from_joints(skeleton, key["joints"], where=where)
        else:
            raise KeyframeError(f"{where} needs 'joints' (or 'rest': true)")
        edits = edits_from_json(key.get("edits", []), where=where)
        out.append(Keyframe(frame=key["frame"], pose=pose, edits=edits))
    try:
        return make_timeline(skeleton, out, fps=data.get("fps", 24) if fps is None else fps,
                             ease=data.get("ease", "linear"))
    except KeyframeError as error:
        raise KeyframeError(f"{path}: {error}") from None


def save_keyframes(path, skeleton, timeline):
    """Write a :class:`Timeline` as a key-frames file."""
    data = {
        "format": KEYS_FORMAT,
        "version": VERSION,
        "fps": timeline.fps,
        "ease": timeline.ease,
        "keys": [_key_to_json(skeleton, k) for k in timeline.keys],
    }
    write_text(path, json.dumps(data, indent=1) + "\n")


def _key_to_json(skeleton, key):
    out = {"frame": key.frame, "joints": pose_to_joints(skeleton, key.pose)}
    if key.edits:
        out["edits"] = edits_to_json(key.edits)
    return out


def _check_version(data, path, error):
    if data.get("version") != VERSION:
        raise error(
            f"{path} is format version {data.get('version')!r}; this toonmotion reads version {VERSION}"
        )
