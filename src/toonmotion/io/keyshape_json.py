"""Key-shape files (Bregler et al. capture): contour sequences, key-shape models and captured
key-shape motion. JSON, versioned; numbers written in full precision, so a save and a load give
back the same arrays.

Contours (the key-shapes themselves, or the frames to capture), points in correspondence::

    {"format": "toonmotion.contours", "version": 1, "fps": 12, "closed": true,
     "contours": [[[x, y], ...], ...]}

or a CSV table ``contour, point, x, y`` (a header row first; contours and points numbered from
0, in order), or an SVG file whose shapes, in document order, are the contours (resampled by
arc length into correspondence). A model (:func:`toonmotion.api.keyshape_space`)::

    {"format": "toonmotion.keyshapes", "version": 1, "closed": true, "inbetweens": 5,
     "tolerance": 0.5, "error": 0.31, "keys": [...], "mean": [...], "eigen": [[...], ...]}

Captured motion (:func:`toonmotion.api.capture_contours`)::

    {"format": "toonmotion.keymotion", "version": 1, "fps": 12, "space": "extended" | "keys",
     "affine": [[[a1, a2, dx], [a3, a4, dy]], ...], "weights": [[w1, ...], ...],
     "error": [...], "rounds": [...]}

and video capture's report, frame by frame, as CSV (:func:`save_video_report`).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field

from toonmotion.errors import KeyShapeError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import Float, Int, JsonFormat, Model, Point, explained, read_versioned
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.line_of_action import resample_line
from toonmotion.keyshape.model import check_shapes, resample_contour
from toonmotion.keyshape.space import KeyShapeSpace
from toonmotion.keyshape.video import VideoCapture

CONTOURS, MODEL, MOTION = "toonmotion.contours", "toonmotion.keyshapes", "toonmotion.keymotion"
# An SVG shape is sampled at this many points along it, then resampled to SVG_POINTS by arc
# length unless the caller asks for another count.
SVG_SAMPLES, SVG_POINTS = 1024, 100
VERSION = 1

_Shape = Annotated[list[Point], Field(min_length=3),
                   explained("a contour must be a list of at least 3 [x, y] points")]
_Fps = Annotated[Float, Field(gt=0, le=1000),
                 explained("fps must be a number of frames per second, 0 to 1,000")]


class ContoursFile(Model):
    format: Literal["toonmotion.contours"]
    version: Literal[1]
    fps: _Fps = 12.0
    closed: bool = True
    contours: Annotated[list[_Shape], Field(min_length=1),
                        explained("'contours' must list at least one contour")]


class ModelFile(Model):
    format: Literal["toonmotion.keyshapes"]
    version: Literal[1]
    closed: bool
    inbetweens: Int
    tolerance: Float
    error: Float
    keys: list[_Shape]
    mean: _Shape
    eigen: list[_Shape]


class MotionFile(Model):
    format: Literal["toonmotion.keymotion"]
    version: Literal[1]
    fps: _Fps
    space: Literal["extended", "keys"]
    affine: list[tuple[tuple[Float, Float, Float], tuple[Float, Float, Float]]]
    weights: list[list[Float]]
    error: list[Float]
    rounds: list[Int]


def _format(model: type[Model], name: str, title: str) -> JsonFormat:
    return JsonFormat(models={name: model}, version=VERSION, error=KeyShapeError, title=title,
                      label=f"{title} format")


CONTOURS_FORMAT = _format(ContoursFile, CONTOURS, "contours file")
MODEL_FORMAT = _format(ModelFile, MODEL, "key-shape model")
MOTION_FORMAT = _format(MotionFile, MOTION, "key-shape motion")


def load_contours(path: str | Path, *, points: int | None = None, start: ArrayLike | None = None,
                  closed: bool | None = None) -> tuple[NDArray[np.float64], float, bool]:
    """The contours ``(T, N, 2)``, their fps and whether they are closed, from JSON, CSV or SVG.

    With ``points``, every contour (closed; any number of points each) is resampled to that many
    by arc length, counter-clockwise, from its point nearest ``start``
    (:func:`~toonmotion.keyshape.model.resample_contour`). An SVG file's shapes (paths, polygons,
    circles, ...; transforms applied), in document order, are contours, always resampled
    (``SVG_POINTS`` points by default).

    Open lines (``"closed": false`` in JSON, or ``closed=False`` for any file: lines of action)
    are resampled from their first point to their last
    (:func:`~toonmotion.keyshape.line_of_action.resample_line`; ``start`` is refused) and may be
    straight.
    """
    path = Path(path)
    shapes: list[Any]
    if path.suffix.lower() == ".svg":  # SVG nodes are not in correspondence: always resampled
        shapes, fps, is_closed = _contours_svg(path), 12.0, True
        points = SVG_POINTS if points is None else points
    elif path.suffix.lower() == ".csv":
        shapes, fps, is_closed = _contours_csv(path), 12.0, True
    else:
        model = read_versioned(path, CONTOURS_FORMAT)
        shapes, fps, is_closed = model.contours, float(model.fps), model.closed
    is_closed = is_closed if closed is None else closed
    if not is_closed and start is not None:
        raise KeyShapeError(f"{path.name}: a start point is for closed contours; an open line runs from "
                            "its first point")
    if points is not None and is_closed:
        shapes = [resample_contour(shape, points, start=start) for shape in shapes]
    elif points is not None:
        shapes = [resample_line(shape, points) for shape in shapes]
    checked = check_shapes(shapes, what=f"{path.name}: the contours", allow_straight=not is_closed)
    return checked, fps, is_closed


def save_contours(path: str | Path, contours: ArrayLike, *, fps: float = 12.0, closed: bool = True) -> None:
    data = {"format": CONTOURS, "version": VERSION, "fps": fps, "closed": closed,
            "contours": np.asarray(contours, dtype=float).tolist()}
    write_text(path, json.dumps(data) + "\n")


def load_model(path: str | Path) -> KeyShapeSpace:
    """A key-shape model saved by :func:`save_model`."""
    path = Path(path)
    model = read_versioned(path, MODEL_FORMAT)
    keys = check_shapes(model.keys, what=f"{path.name}: the keys")
    mean = np.array(model.mean, dtype=float)
    # A model of one key (or of keys all alike) has no eigen-shapes.
    eigen = (np.array(model.eigen, dtype=float).reshape(len(model.eigen), -1, 2) if model.eigen
             else np.zeros((0, *keys.shape[1:])))
    if mean.shape != keys.shape[1:] or eigen.shape[1:] != keys.shape[1:]:
        raise KeyShapeError(f"{path.name}: the mean and eigen-shapes must have the keys' "
                            f"{keys.shape[1]} points")
    return KeyShapeSpace(keys=keys, closed=model.closed, inbetweens=model.inbetweens,
                         tolerance=model.tolerance, mean=mean, eigen=eigen, error=model.error)


def save_model(path: str | Path, space: KeyShapeSpace) -> None:
    data = {"format": MODEL, "version": VERSION, "closed": space.closed, "inbetweens": space.inbetweens,
            "tolerance": space.tolerance, "error": space.error, "keys": space.keys.tolist(),
            "mean": space.mean.tolist(), "eigen": space.eigen.tolist()}
    write_text(path, json.dumps(data) + "\n")


def save_keymotion(path: str | Path, capture: ContourCapture, *, fps: float, space: str) -> None:
    data = {"format": MOTION, "version": VERSION, "fps": fps, "space": space,
            "affine": capture.affine.tolist(), "weights": capture.weights.tolist(),
            "error": capture.error.tolist(), "rounds": capture.rounds.tolist()}
    write_text(path, json.dumps(data) + "\n")


def save_video_report(path: str | Path, capture: VideoCapture) -> None:
    """Video capture frame by frame, as CSV: ``frame, iterations, residual, a1, a2, dx, a3, a4,
    dy`` and the eigen-image weights ``w1 ..``."""
    L = capture.weights.shape[1]
    lines = [",".join(["frame", "iterations", "residual", "a1", "a2", "dx", "a3", "a4", "dy",
                       *(f"w{k + 1}" for k in range(L))])]
    for t in range(len(capture.affine)):
        numbers = [*capture.affine[t].ravel(), *capture.weights[t]]
        lines.append(",".join([str(t), str(int(capture.iterations[t])), repr(float(capture.residual[t])),
                               *(repr(float(v)) for v in numbers)]))
    write_text(path, "\n".join(lines) + "\n")


def load_keymotion(path: str | Path) -> tuple[ContourCapture, float, str]:
    model = read_versioned(Path(path), MOTION_FORMAT)
    T = len(model.affine)
    if not (len(model.weights) == len(model.error) == len(model.rounds) == T) or T == 0:
        raise KeyShapeError(f"{Path(path).name}: affine, weights, error and rounds need one row per frame")
    weights = np.array(model.weights, dtype=float)
    if weights.ndim != 2:
        raise KeyShapeError(f"{Path(path).name}: every frame needs the same number of weights")
    return (ContourCapture(affine=np.array(model.affine, dtype=float), weights=weights,
                           error=np.array(model.error, dtype=float), rounds=np.array(model.rounds)),
            float(model.fps), model.space)


def _contours_svg(path: Path) -> list[NDArray[np.float64]]:
    try:
        shapes = _svg_shapes(path)
    except KeyShapeError:
        raise
    except Exception as error:  # the SVG library raises many kinds on a malformed file
        raise KeyShapeError(f"cannot read {path.name} as SVG: {type(error).__name__}") from None
    if not shapes:
        raise KeyShapeError(f"{path.name} holds no path or shape to read as a contour")
    return shapes


def _svg_shapes(path: Path) -> list[NDArray[np.float64]]:
    import svgelements

    svg = svgelements.SVG.parse(str(path))
    if not isinstance(svg, svgelements.SVG):
        raise KeyShapeError(f"cannot read {path.name} as SVG: it has no <svg> element")
    shapes = []
    for element in svg.elements():
        if not isinstance(element, svgelements.Shape) or isinstance(element, svgelements.SVG):
            continue
        outline = svgelements.Path(element)
        if len(outline) == 0 or not outline.length() > 0:
            continue
        sampled = np.asarray(outline.npoint(np.linspace(0, 1, SVG_SAMPLES)), dtype=float).reshape(-1, 2)
        shapes.append(sampled[:-1] if np.allclose(sampled[0], sampled[-1]) else sampled)
    return shapes


def _contours_csv(path: Path) -> list[list[tuple[float, float]]]:
    try:
        with path.open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))
    except (OSError, UnicodeDecodeError) as error:
        raise KeyShapeError(f"cannot read {path}: {error}") from None
    if not rows or [c.strip().lower() for c in rows[0]] != ["contour", "point", "x", "y"]:
        raise KeyShapeError(f"{path.name}: the first row must be the header contour, point, x, y")
    table: dict[int, dict[int, tuple[float, float]]] = {}
    for n, row in enumerate(rows[1:], start=2):
        try:
            contour, point, x, y = int(row[0]), int(row[1]), float(row[2]), float(row[3])
        except (ValueError, IndexError):
            raise KeyShapeError(f"{path.name}: row {n} must be contour, point (whole numbers), "
                                "x, y") from None
        table.setdefault(contour, {})[point] = (x, y)
    if sorted(table) != list(range(len(table))):
        raise KeyShapeError(f"{path.name}: contours must be numbered 0, 1, 2, ... with none missing")
    shapes = []
    for contour in range(len(table)):
        points = table[contour]
        if sorted(points) != list(range(len(points))):
            raise KeyShapeError(f"{path.name}: contour {contour}'s points must be numbered 0, 1, 2, "
                                "...")
        shapes.append([points[i] for i in range(len(points))])
    return shapes
