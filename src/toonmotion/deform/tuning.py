"""Fine-tuning edits on a deformed pose, kept as data (thesis 3.5, 6.3c).

An edit records what the animator did, in drawing pixels, not which vertices moved: a sketch
curve is its points, a drag is where it started and where it ended. So the edits of a pose or
key-frame can be saved, undone one by one, and replayed on a re-meshed character (a drag picks
the vertex nearest its start in whatever mesh it meets). :func:`apply_tuning` replays them in
order on a :class:`~toonmotion.deform.deformer.Deformation`; the geometry is in
:mod:`toonmotion.deform.fine_tune`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.deform.deformer import Deformation, Deformer
from toonmotion.deform.fine_tune import drag_points, tune_with_curve
from toonmotion.errors import EditError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.rig.pose import Pose


@dataclass(frozen=True, eq=False)
class CurveEdit:
    """Pull the outline between the points nearest the curve's ends onto the curve (fig. 3.11).

    Attributes
    ----------
    points : (k, 2) float
        The sketched polyline, k >= 2, drawing pixels.

    Construction copies the points (read-only) and raises :class:`EditError` unless they are
    at least two finite ``[x, y]`` points.
    """

    points: NDArray[np.float64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", _points(self.points, "a sketch curve", minimum=2))


@dataclass(frozen=True, eq=False)
class DragEdit:
    """Drag the vertices nearest ``start`` to ``end`` (fig. 3.12b).

    Attributes
    ----------
    start, end : (k, 2) float
        Where each drag began and ended, drawing pixels.

    Construction copies the points (read-only) and raises :class:`EditError` unless they are
    finite ``[x, y]`` points, at least one, as many ends as starts.
    """

    start: NDArray[np.float64]
    end: NDArray[np.float64]

    def __post_init__(self) -> None:
        start = _points(self.start, "a drag's start points", minimum=1)
        end = _points(self.end, "a drag's end points", minimum=1)
        if start.shape != end.shape:
            raise EditError(f"a drag has {len(start)} start points but {len(end)} end points; "
                            "give one end per start")
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "end", end)


EDIT_TYPES = {"curve": CurveEdit, "drag": DragEdit}

TuningEdit: TypeAlias = CurveEdit | DragEdit
"""A fine-tuning edit."""


def apply_tuning(
    deformer: Deformer, pose: Pose, deformation: Deformation, edits: Sequence[TuningEdit]
) -> Deformation:
    """``deformation`` with ``edits`` applied in order to its mesh.

    Returns the same :class:`Deformation` when there are no edits, else a copy whose ``U`` is
    the tuned mesh (``stage_one`` and the solve's figures are kept).
    """
    if not edits:
        return deformation
    U = deformation.U
    for n, edit in enumerate(edits, start=1):
        try:
            if isinstance(edit, CurveEdit):
                U = tune_with_curve(deformer, pose, U, edit.points)
            elif isinstance(edit, DragEdit):
                U = drag_points(deformer, U, edit.start, edit.end)
            else:
                raise EditError(f"unknown fine-tuning edit {type(edit).__name__}")
        except EditError as error:
            raise EditError(f"edit {n} ({_kind(edit)}): {error}") from None
    return dataclasses.replace(deformation, U=U)


def describe(edit: TuningEdit) -> str:
    """One line for listings: ``curve of 12 points from (10, 20) to (40, 22)``."""
    if isinstance(edit, CurveEdit):
        (x0, y0), (x1, y1) = edit.points[0], edit.points[-1]
        return f"curve of {len(edit.points)} points from ({x0:.0f}, {y0:.0f}) to ({x1:.0f}, {y1:.0f})"
    moves = ", ".join(f"({a:.0f}, {b:.0f}) -> ({c:.0f}, {d:.0f})"
                      for (a, b), (c, d) in zip(edit.start, edit.end, strict=True))
    return f"drag {moves}"


def _kind(edit):
    return "curve" if isinstance(edit, CurveEdit) else "drag"


def _points(value: ArrayLike, what: str, *, minimum: int) -> NDArray[np.float64]:
    try:
        P = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise EditError(f"{what} must be a list of [x, y] points") from None
    if P.ndim == 1 and P.size == 0:
        P = P.reshape(0, 2)
    if P.ndim != 2 or P.shape[1] != 2:
        raise EditError(f"{what} must be a list of [x, y] points")
    if len(P) < minimum:
        raise EditError(f"{what} needs at least {minimum} point{'s' if minimum > 1 else ''}, got {len(P)}")
    return frozen_array(P, dtype=np.float64, name=what, error=EditError, coordinates=True)
