"""Motion files: JSON, versioned, one frame per line.

::

    {"format": "toonmotion.motion", "version": 1, "fps": 12,
     "joints": [{"name": "root", "parent": null, "position": [264, 397]}, ...],
     "frames": [
      [[264, 397], [264, 397], ...],
      ...]}

``joints`` is the skeleton (its positions the rest pose); each frame lists every joint's
``[x, y]`` in that order. A captured motion also has ``"confidence"``: a row per frame of each
joint's tracking confidence in [0, 1]. Numbers are written with full precision, so a save
followed by a load gives back the same arrays. :func:`save_motion_csv` writes a table for
spreadsheets and other tools: ``frame, time, <joint>_x, <joint>_y[, <joint>_confidence]...``.
"""

import json
from pathlib import Path

import numpy as np

from toonmotion.animate.motion import Motion
from toonmotion.errors import MotionError, ToonmotionError
from toonmotion.io.atomic import write_text
from toonmotion.io.json_file import read_json
from toonmotion.io.skeleton_json import skeleton_from_dict, skeleton_to_dict

FORMAT = "toonmotion.motion"
VERSION = 1


def is_motion_file(path):
    """True when ``path`` is a readable JSON file whose format is a motion (not validated)."""
    try:
        data = read_json(path, MotionError)
    except MotionError:
        return False
    return isinstance(data, dict) and data.get("format") == FORMAT


def load_motion(path):
    """Read a motion file; returns a :class:`Motion`."""
    path = Path(path)
    data = read_json(path, MotionError)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise MotionError(f"{path} is not a motion file (format {FORMAT!r})")
    if data.get("version") != VERSION:
        raise MotionError(
            f"{path} is motion format version {data.get('version')!r}; this toonmotion reads "
            f"version {VERSION}"
        )
    try:
        skeleton = skeleton_from_dict(data.get("joints"), where=str(path))
    except ToonmotionError as error:
        raise MotionError(str(error)) from None
    frames = data.get("frames")
    try:
        positions = np.array(frames, dtype=float)
    except (TypeError, ValueError):
        raise MotionError(f"{path}: 'frames' must be a list of frames of [x, y] per joint") from None
    confidence = data.get("confidence")
    if confidence is not None:
        try:
            confidence = np.array(confidence, dtype=float)
        except (TypeError, ValueError):
            raise MotionError(f"{path}: 'confidence' must be a list of rows of numbers") from None
    if positions.ndim == 3 and positions.shape[1] == len(skeleton):
        # Columns follow the file's joint order; the skeleton lists parents first.
        order = np.argsort([skeleton.index(j["name"]) for j in data["joints"]])
        positions = positions[:, order]
        if confidence is not None and confidence.ndim == 2 and confidence.shape[1] == len(order):
            confidence = confidence[:, order]
    try:
        return Motion(skeleton=skeleton, positions=positions, fps=data.get("fps"), confidence=confidence)
    except MotionError as error:
        raise MotionError(f"{path}: {error}") from None


def save_motion(path, motion):
    """Write a :class:`Motion` atomically."""
    head = json.dumps({"format": FORMAT, "version": VERSION, "fps": motion.fps})[:-1]
    joints = json.dumps(skeleton_to_dict(motion.skeleton))
    rows = ",\n".join(" " + json.dumps(frame.tolist(), separators=(",", ":"))
                      for frame in motion.positions)
    text = f'{head},\n "joints": {joints},\n "frames": [\n{rows}]'
    if motion.confidence is not None:
        rows = ",\n".join(" " + json.dumps(row.tolist(), separators=(",", ":")) for row in motion.confidence)
        text += f',\n "confidence": [\n{rows}]'
    write_text(path, text + "}\n")


def save_motion_csv(path, motion):
    """Write a :class:`Motion` as CSV: a row per frame, two columns per joint (and confidence)."""
    names = motion.skeleton.names
    header = ["frame", "time"]
    sure = motion.confidence is not None
    for name in names:
        header += [f"{name}_x", f"{name}_y"] + ([f"{name}_confidence"] if sure else [])
    lines = [",".join(header)]
    for f, frame in enumerate(motion.positions):
        row = [str(f), repr(f / motion.fps)]
        for j, (x, y) in enumerate(frame):
            row += [repr(float(x)), repr(float(y))]
            if sure:
                row.append(repr(float(motion.confidence[f, j])))
        lines.append(",".join(row))
    write_text(path, "\n".join(lines) + "\n")
