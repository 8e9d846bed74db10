"""Markers files: the drawing's named 2D markers over time, as JSON or CSV.

JSON, versioned, one frame per line::

    {"format": "toonmotion.markers", "version": 1, "fps": 12,
     "names": ["hips", "left_knee", ...],
     "frames": [
      [[x, y], [x, y], ...],
      ...]}

Each frame lists every marker's ``[x, y]`` (drawing pixels, y down) in the order of ``names``.
CSV is a table with the header ``frame,marker,x,y`` and a row per marker per frame; frames are
numbered from 0, markers keep the order in which they first appear, and every frame must give
every marker once. A CSV file has no frame rate: the caller gives it (12 by default).

Numbers are written in full precision (``repr``), so a save followed by a load gives back the
same arrays, in either format. The file model checks types; shapes (every frame has every
marker, names distinct, values finite) are checked by :class:`~toonmotion.proxy3d.markers.Markers`.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field

from toonmotion import limits
from toonmotion.errors import ProxyError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import Float, JsonFormat, Model, Name, Point, explained, read_versioned
from toonmotion.proxy3d.markers import Markers

FORMAT = "toonmotion.markers"
VERSION = 1
CSV_HEADER = ("frame", "marker", "x", "y")
# The frame rate of a CSV file, which does not say its own.
CSV_FPS = 12.0


class MarkersFile(Model):
    """A markers file (see the module docstring)."""

    format: Literal["toonmotion.markers"]
    version: Literal[1]
    fps: Annotated[Float, Field(gt=0, le=1000),
                   explained("fps must be a number of frames per second, 0 to 1,000")]
    names: Annotated[list[Name], Field(min_length=1), explained("'names' must list at least one marker name")]
    frames: Annotated[list[list[Point]], Field(min_length=1),
                      explained("'frames' must list at least one frame of [x, y] per marker")]


MARKERS = JsonFormat(models={FORMAT: MarkersFile}, version=VERSION, error=ProxyError,
                     title="markers file", label="markers format")


def load_markers(path: str | Path, *, fps: float | None = None) -> Markers:
    """Read a markers file, JSON or (by its ``.csv`` suffix) CSV.

    Parameters
    ----------
    path : str or Path
    fps : float, optional
        The drawing's frame rate: for a CSV file (default :data:`CSV_FPS`); for a JSON file it
        replaces the file's own.

    Returns
    -------
    Markers

    Raises
    ------
    ProxyError
        The file is missing or unreadable, is another format or version, or does not hold a
        position for every marker on every frame; the message names the file.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> m = Markers(("hip", "knee"), [[[1.5, 2.0], [3.0, 4.25]]], fps=24)
    >>> save_markers(folder / "m.csv", m)
    >>> print((folder / "m.csv").read_text().strip())
    frame,marker,x,y
    0,hip,1.5,2.0
    0,knee,3.0,4.25
    >>> load_markers(folder / "m.csv", fps=24).positions.tolist()
    [[[1.5, 2.0], [3.0, 4.25]]]
    """
    path = Path(path)
    if path.suffix.lower() == ".csv":
        names, positions = _read_csv(path)
        rate = CSV_FPS if fps is None else fps
    else:
        model = read_versioned(path, MARKERS)
        names, rate = tuple(model.names), (model.fps if fps is None else fps)
        if any(len(frame) != len(names) for frame in model.frames):
            bad = next(t for t, frame in enumerate(model.frames) if len(frame) != len(names))
            raise ProxyError(f"{path}: frame {bad} has {len(model.frames[bad])} points for the "
                             f"{len(names)} names; give one [x, y] per marker on every frame")
        positions = np.array(model.frames, dtype=float).reshape(len(model.frames), len(names), 2)
    try:
        return Markers(names, positions, rate)
    except ProxyError as error:
        raise ProxyError(f"{path}: {error}") from None


def save_markers(path: str | Path, markers: Markers) -> None:
    """Write markers atomically: CSV when ``path`` ends in ``.csv`` (no fps kept), else JSON.

    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "m.json"
    >>> save_markers(path, Markers(("hip",), [[[0.1, 0.2]], [[0.3, 1e-17]]], fps=12))
    >>> back = load_markers(path)
    >>> back.names, back.positions.tolist(), back.fps
    (('hip',), [[[0.1, 0.2]], [[0.3, 1e-17]]], 12.0)
    """
    if Path(path).suffix.lower() == ".csv":
        out = io.StringIO()
        table = csv.writer(out, lineterminator="\n")
        table.writerow(CSV_HEADER)
        for t, frame in enumerate(markers.positions):
            for name, (x, y) in zip(markers.names, frame, strict=True):
                table.writerow([str(t), name, repr(float(x)), repr(float(y))])
        write_text(path, out.getvalue())
        return
    head = json.dumps({"format": FORMAT, "version": VERSION, "fps": markers.fps})[:-1]
    rows = ",\n".join(" " + json.dumps(frame.tolist(), separators=(",", ":")) for frame in markers.positions)
    write_text(path, f'{head},\n "names": {json.dumps(list(markers.names))},\n "frames": [\n{rows}]}}\n')


def _read_csv(path: Path) -> tuple[tuple[str, ...], np.ndarray]:
    try:
        limits.check("file_bytes", path.stat().st_size, f"{path.name}'s size in bytes")
        with path.open(newline="", encoding="utf-8") as file:
            rows = list(csv.reader(file))
    except FileNotFoundError:
        raise ProxyError(f"cannot read {path}: no such file") from None
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ProxyError(f"cannot read {path}: {error}") from None
    if not rows or tuple(c.strip().lower() for c in rows[0]) != CSV_HEADER:
        raise ProxyError(f"{path.name}: the first row must be the header {','.join(CSV_HEADER)}")
    table: dict[int, dict[str, tuple[float, float]]] = {}
    names: dict[str, None] = {}  # insertion-ordered
    for n, row in enumerate(rows[1:], start=2):
        if not row:
            continue
        try:
            if len(row) != 4:
                raise ValueError
            frame, name, x, y = int(row[0]), row[1], float(row[2]), float(row[3])
        except ValueError:
            raise ProxyError(f"{path.name}: row {n} must be frame (a whole number), marker, x, y") from None
        if not name.strip():
            raise ProxyError(f"{path.name}: row {n} has an empty marker name")
        if name in table.setdefault(frame, {}):
            raise ProxyError(f"{path.name}: row {n} gives marker {name!r} a second time on frame {frame}")
        table[frame][name] = (x, y)
        names.setdefault(name, None)
        limits.check("frames", len(table), f"{path.name}'s frame count")
    if not table:
        raise ProxyError(f"{path.name} has no rows of markers; give frame,marker,x,y rows")
    if sorted(table) != list(range(len(table))):
        raise ProxyError(f"{path.name}: frames must be numbered 0, 1, 2, ... with none missing")
    order = tuple(names)
    for frame in range(len(table)):
        missing = [m for m in order if m not in table[frame]]
        if missing:
            raise ProxyError(f"{path.name}: frame {frame} has no row for marker {missing[0]!r}; every "
                             "frame must give every marker")
    positions = np.array([[table[t][m] for m in order] for t in range(len(table))], dtype=float)
    return order, positions
