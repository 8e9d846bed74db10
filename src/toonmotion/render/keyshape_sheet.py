"""A preview sheet of key-shapes and their in-betweens: one row per pair of keys, the first key,
its in-betweens and the second key side by side, drawn as outlines (keys dark, in-betweens blue)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from PIL import Image, ImageDraw

CELL = 160  # pixels per shape, square
MARGIN = 12


def inbetween_sheet(rows: Sequence[ArrayLike], *, closed: bool = True) -> NDArray[np.uint8]:
    """RGB sheet of ``rows``, each (count, N, 2): the shapes of one pair, keys at both ends.

    Every shape is scaled by one factor (the sheet's largest shape fits a cell), so sizes
    compare across the sheet.

    Examples
    --------
    >>> square = np.array([(0.0, 0), (10, 0), (10, 10), (0, 10)])
    >>> inbetween_sheet([np.stack([square, square * 1.5, square * 2])]).shape
    (160, 480, 3)
    """
    shapes = [np.asarray(row, dtype=float) for row in rows]
    span = max(float(np.ptp(row, axis=1).max()) for row in shapes)
    scale = (CELL - 2 * MARGIN) / max(span, 1e-9)
    columns = max(len(row) for row in shapes)
    sheet = Image.new("RGB", (columns * CELL, len(shapes) * CELL), (255, 255, 255))
    pen = ImageDraw.Draw(sheet)
    for r, row in enumerate(shapes):
        for c, shape in enumerate(row):
            centre = (shape.max(axis=0) + shape.min(axis=0)) / 2
            xy = (shape - centre) * scale + [c * CELL + CELL / 2, r * CELL + CELL / 2]
            points = [tuple(p) for p in xy] + ([tuple(xy[0])] if closed else [])
            key = c in (0, len(row) - 1)
            pen.line(points, fill=(30, 30, 30) if key else (49, 110, 190), width=2 if key else 1)
    return np.asarray(sheet)
