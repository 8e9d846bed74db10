"""Sketch files: the strokes of a sketched skeleton (thesis 6.2a), in drawing pixels.

``{"format": "toonmotion.sketch", "version": 1, "strokes": [[[x, y], ...], ...]}``, the strokes
in the order drawn, each at least two points. :func:`toonmotion.api.sketch_pose` reads which
bones they are.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from toonmotion.errors import SketchError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import JsonFormat, Model, Point, explained, read_versioned

FORMAT = "toonmotion.sketch"
VERSION = 1

_Stroke = Annotated[list[Point], Field(min_length=2),
                    explained("a stroke must be a list of at least 2 [x, y] points")]


class SketchFile(Model):
    """A sketch file (see the module docstring)."""

    format: Literal["toonmotion.sketch"]
    version: Literal[1]
    strokes: Annotated[list[_Stroke], Field(min_length=1),
                       explained("'strokes' must list at least one stroke")]


SKETCH = JsonFormat(models={FORMAT: SketchFile}, version=VERSION, error=SketchError,
                    title="toonmotion sketch file", label="sketch format")


def load_sketch(path: str | Path) -> list[NDArray[np.float64]]:
    """The strokes of a sketch file, each ``(n, 2)`` float; :class:`SketchError` naming the file
    and the field when it is malformed."""
    return [np.array(stroke, dtype=float) for stroke in read_versioned(path, SKETCH).strokes]


def save_sketch(path: str | Path, strokes: Sequence[ArrayLike]) -> None:
    """Write ``strokes`` as a sketch file atomically."""
    data = {"format": FORMAT, "version": VERSION,
            "strokes": [np.asarray(stroke, dtype=float).round(3).tolist() for stroke in strokes]}
    write_text(path, json.dumps(data) + "\n")
