"""Resource limits: how big an input or an output toonmotion accepts before refusing it.

Every boundary where a file, an option or a computed size could ask for unbounded time or
memory checks one of these limits first and raises a one-line :class:`LimitError` naming the
limit and how to raise it. The defaults serve real drawings, footage and motion capture with
room to spare; a user with bigger work raises one for a run (``toonmotion --limit
canvas_pixels=200000000 show ...``) or a program for a block (``with using(frames=500_000):``).

The limits are process-wide (:func:`current`); :func:`using` changes them for a ``with`` block.
"""

from __future__ import annotations

import dataclasses
import math
import operator
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from toonmotion.errors import LimitError


@dataclass(frozen=True)
class Limits:
    """The limits in force.

    Attributes
    ----------
    image_pixels : int
        Pixels in one drawing, mask or footage frame, checked from the file's header.
    footage_pixels : int
        Pixels in a whole footage sequence, ``frames * width * height`` (it is held in memory).
    footage_frames : int
        Frames in a footage sequence.
    canvas_pixels : int
        Pixels in one picture toonmotion draws (a posed frame, an animation, an overview).
    canvas_side : int
        Width or height of one picture toonmotion draws.
    frames : int
        Frames in an animation or a motion, and the largest key-frame number.
    joints : int
        Joints in a skeleton (a drawing's, a motion's or a BVH file's).
    figure_parts : int
        Separate pieces in a figure's mask (specks of dust or a dithered alpha count).
    mesh_vertices : int
        Vertices in a character's mesh (posing time grows with them).
    held_pixels : int
        Pixels of the frames of a GIF, APNG or WebP written, which are held in memory to write it.
    file_bytes : int
        Size of a JSON, YAML or BVH file read.
    skeleton_bytes : int
        Size of a skeleton file read (a char_cfg YAML or a toonmotion JSON): the joints limit's
        skeleton takes a few hundred kB.
    upload_bytes : int
        Size of a file sent to the editor (footage).
    scene_bodies : int
        Simulated bodies in a 3D scene: rain drops, balls, and the links of every balloon string
        (with its balloon), scarf and skirt strand. A 100-frame scene of 500 at 12 fps takes under a
        minute and under 500 MB (docs/limits.md).
    """

    image_pixels: int = 40_000_000
    footage_pixels: int = 500_000_000
    footage_frames: int = 2_000
    canvas_pixels: int = 64_000_000
    canvas_side: int = 16_384
    frames: int = 100_000
    joints: int = 1_000
    figure_parts: int = 200
    mesh_vertices: int = 50_000
    held_pixels: int = 250_000_000
    file_bytes: int = 256_000_000
    skeleton_bytes: int = 2_000_000
    upload_bytes: int = 500_000_000
    scene_bodies: int = 500

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            whole = f.type == "int"
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise LimitError(f"the limit {f.name} takes a finite number, got {value!r}")
            if value <= 0 or (whole and value != int(value)):
                kind = "positive whole number" if whole else "positive number"
                raise LimitError(f"the limit {f.name} takes a {kind}, got {value!r}")
            object.__setattr__(self, f.name, int(value) if whole else float(value))


NAMES = tuple(f.name for f in dataclasses.fields(Limits))

_current = Limits()


def current() -> Limits:
    """The limits in force."""
    return _current


def set_limits(limits: Limits) -> None:
    """Put ``limits`` in force for the rest of the process."""
    global _current
    if not isinstance(limits, Limits):
        raise TypeError(f"set_limits takes a Limits, got {type(limits).__name__}")
    _current = limits


@contextmanager
def using(**changes: Any) -> Iterator[Limits]:
    """Raise (or lower) some limits inside a ``with`` block.

    >>> with using(frames=500_000) as limits:
    ...     limits.frames
    500000
    >>> current().frames
    100000
    """
    global _current
    before = _current
    _current = replaced(before, changes)
    try:
        yield _current
    finally:
        _current = before


def replaced(limits: Limits, changes: dict[str, Any]) -> Limits:
    """``limits`` with ``changes`` (limit name to value); an unknown name is a :class:`LimitError`."""
    unknown = sorted(set(changes) - set(NAMES))
    if unknown:
        raise LimitError(f"no limit named {unknown[0]!r}; the limits are {', '.join(NAMES)}")
    return dataclasses.replace(limits, **changes)


def check(name: str, amount: float, what: str, *, hint: str = "") -> None:
    """Raise :class:`LimitError` when ``amount`` exceeds the limit ``name``.

    ``what`` says what was measured (``"the picture, 20000x30000 pixels,"``); ``hint`` how to
    stay under the limit, before the reminder of how to raise it.
    """
    limit = operator.attrgetter(name)(_current)
    if not amount <= limit:  # also refuses NaN
        whole = isinstance(amount, int) or (math.isfinite(amount) and amount.is_integer() and amount < 1e15)
        large = math.isfinite(amount) and 1000 <= abs(amount) < 1e15  # pixels worked out: 150,672,000
        shown = f"{int(amount):,}" if whole else f"{amount:,.0f}" if large else f"{amount:g}"
        advice = f"{hint}, or raise" if hint else "raise"
        raise LimitError(
            f"{what} is over the limit {name}={limit:,} (it is {shown}); {advice} the limit with "
            f"--limit {name}=N"
        )
