"""The joints file that starts tracking (``toonmotion track --joints JOINTS.json``): JSON, versioned.

``{"format": "toonmotion.joints", "version": 1, "frame": 0, "size": [w, h],
"joints": [{"name": ..., "parent": ... or null, "position": [x, y], "size": [w, h]}, ...]}``

``frame`` (optional, default 0) is the frame the positions are given for. Each joint's
``size`` is the width and height of the rectangle tracked around it, in pixels; a joint
without one takes the file's ``size``, or 16 x 16 when the file has none either. Joints are
as in the skeleton file (:mod:`toonmotion.io.skeleton_json`). Sizes are returned in the
skeleton's joint order (parents first), which need not be the file's order.

Problems with the file (missing, not JSON, wrong format or version, bad sizes or frame) are
:class:`TrackingError`; problems with the joints themselves are :class:`SkeletonError`.
"""

import json
from numbers import Real
from pathlib import Path

import numpy as np

from toonmotion.errors import SkeletonError, TrackingError
from toonmotion.io.atomic import write_text
from toonmotion.io.json_file import read_json
from toonmotion.io.skeleton_json import skeleton_from_dict, skeleton_to_dict

FORMAT = "toonmotion.joints"
VERSION = 1
DEFAULT_SIZE = (16.0, 16.0)


def load_joints(path):
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
    data = read_json(path, TrackingError, what="joints file ")
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise TrackingError(
            f"{path} is not a toonmotion joints file (it needs \"format\": {FORMAT!r}); "
            "write one with save_joints or by hand"
        )
    if data.get("version") != VERSION:
        raise TrackingError(
            f"{path} is joints format version {data.get('version')!r}; "
            f"this toonmotion reads version {VERSION}"
        )
    frame = data.get("frame", 0)
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
        raise TrackingError(f"{path}: 'frame' must be a whole number >= 0, got {frame!r}")
    default = _size(data["size"], f"{path}: the file's 'size'") if "size" in data else DEFAULT_SIZE
    joints = data.get("joints")
    try:
        skeleton = skeleton_from_dict(joints, where=str(path))
    except SkeletonError as error:
        message = str(error)
        raise SkeletonError(message if str(path) in message else f"{path}: {message}") from None
    size_of = {
        str(joint["name"]): _size(joint["size"], f"{path}: joint {joint['name']!r}'s 'size'")
        if "size" in joint else default
        for joint in joints
    }
    sizes = np.array([size_of[name] for name in skeleton.names], dtype=float).reshape(-1, 2)
    return skeleton, sizes, frame


def save_joints(path, skeleton, sizes, frame=0):
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
    if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)) or frame < 0:
        raise TrackingError(f"the frame must be a whole number >= 0, got {frame!r}")
    joints = skeleton_to_dict(skeleton)
    for joint, size in zip(joints, sizes, strict=True):
        joint["size"] = list(_size(size.tolist(), f"joint {joint['name']!r}'s size"))
    data = {"format": FORMAT, "version": VERSION, "frame": int(frame), "joints": joints}
    write_text(path, json.dumps(data, indent=1) + "\n")


def _size(value, what):
    """``(w, h)`` floats from a JSON value; TrackingError unless two finite numbers above 0."""
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 2
        or not all(isinstance(v, Real) and not isinstance(v, bool) for v in value)
        or not all(np.isfinite(v) and v > 0 for v in value)
    ):
        raise TrackingError(f"{what} is {value!r}; give [width, height] in pixels, both above 0")
    return float(value[0]), float(value[1])
