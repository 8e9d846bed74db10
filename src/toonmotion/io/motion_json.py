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

The file model checks types (numbers, names, points); shapes (every frame has every joint,
confidence matches the frames) are checked by :class:`~toonmotion.animate.motion.Motion`.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Literal

import numpy as np

from toonmotion.animate.motion import Motion
from toonmotion.errors import MotionError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import Float, Joints, JsonFormat, Model, Point, read_json, read_versioned
from toonmotion.io.skeleton_json import skeleton_from_joints, skeleton_to_dict

FORMAT = "toonmotion.motion"
VERSION = 1


class MotionFile(Model):
    """A motion file (see the module docstring)."""

    format: Literal["toonmotion.motion"]
    version: Literal[1]
    fps: Float
    joints: Joints
    frames: list[list[Point]]
    confidence: list[list[Float]] | None = None


MOTION = JsonFormat(models={FORMAT: MotionFile}, version=VERSION, error=MotionError,
                    title="motion file", label="motion format")


def is_motion_file(path: str | Path) -> bool:
    """True when ``path`` is a readable JSON file whose format is a motion (not validated)."""
    try:
        data = read_json(path, MotionError)
    except MotionError:
        return False
    return isinstance(data, dict) and data.get("format") == FORMAT


def load_motion(path: str | Path) -> Motion:
    """Read a motion file; returns a :class:`Motion`."""
    path = Path(path)
    model = read_versioned(path, MOTION)
    skeleton = skeleton_from_joints(model.joints, where=path, error=MotionError)
    try:
        positions = np.array(model.frames, dtype=float)
    except ValueError:
        raise MotionError(f"{path}: 'frames' must be a list of frames of [x, y] per joint") from None
    confidence = None
    if model.confidence is not None:
        try:
            confidence = np.array(model.confidence, dtype=float)
        except ValueError:
            raise MotionError(f"{path}: 'confidence' must be a list of rows of numbers") from None
    if positions.ndim == 3 and positions.shape[1] == len(skeleton):
        # Columns follow the file's joint order; the skeleton lists parents first.
        order = np.argsort([skeleton.index(joint.name) for joint in model.joints])
        positions = positions[:, order]
        if confidence is not None and confidence.ndim == 2 and confidence.shape[1] == len(order):
            confidence = confidence[:, order]
    try:
        return Motion(skeleton=skeleton, positions=positions, fps=model.fps, confidence=confidence)
    except MotionError as error:
        raise MotionError(f"{path}: {error}") from None


def save_motion(path: str | Path, motion: Motion) -> None:
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


def save_motion_csv(path: str | Path, motion: Motion) -> None:
    """Write a :class:`Motion` as CSV: a row per frame, two columns per joint (and confidence).

    Numbers are written in full (``repr``), so reading them back gives the same floats.
    """
    sure = motion.confidence is not None
    header = ["frame", "time"]
    for name in motion.skeleton.names:
        header += [f"{name}_x", f"{name}_y"] + ([f"{name}_confidence"] if sure else [])
    out = io.StringIO()
    table = csv.writer(out, lineterminator="\n")
    table.writerow(header)
    for f, frame in enumerate(motion.positions):
        row = [str(f), repr(f / motion.fps)]
        for j, (x, y) in enumerate(frame):
            row += [repr(float(x)), repr(float(y))]
            if motion.confidence is not None:
                row.append(repr(float(motion.confidence[f, j])))
        table.writerow(row)
    write_text(path, out.getvalue())
