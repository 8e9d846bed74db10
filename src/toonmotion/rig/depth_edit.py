"""A depth edit (3.5, 6.3b): a bone's region put at a depth layer, as a character's history keeps
it (:mod:`toonmotion.rig.edits` applies it; :class:`~toonmotion.rig.character.Character` holds it)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from toonmotion.errors import EditError
from toonmotion.geometry.arrays import finite_point

# Depths only order regions; a million layers is more than any drawing has parts.
MAX_DEPTH = 1_000_000


@dataclass(frozen=True)
class DepthEdit:
    """Set the depth layer of one bone region (higher is in front).

    Give ``bone`` (a bone's name, i.e. its child joint's) or ``at`` (an ``(x, y)`` drawing
    pixel: the region of the rest-mesh vertex nearest it, like clicking the drawing).
    """

    value: int
    bone: str | None = None
    at: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if isinstance(self.value, bool) or not isinstance(self.value, (int, np.integer)):
            raise EditError(f"a depth must be a whole number, got {self.value!r}")
        if abs(int(self.value)) > MAX_DEPTH:
            raise EditError(f"a depth must be between -{MAX_DEPTH:,} and {MAX_DEPTH:,}, got {self.value}")
        if (self.bone is None) == (self.at is None):
            raise EditError("a depth edit names a bone or gives a point (at), exactly one of them")
        if self.bone is not None and not isinstance(self.bone, str):
            raise EditError(f"a depth edit names its bone by a string, got {self.bone!r}")
        if self.at is not None:
            at = finite_point(self.at, name="a depth edit's point", error=EditError)
            object.__setattr__(self, "at", at)
        object.__setattr__(self, "value", int(self.value))
