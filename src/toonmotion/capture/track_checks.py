"""Checks of the joint tracker's input: each raises :class:`TrackingError` with a one-line message.

Frames are checked as they are read (a lazy sequence is read once), so an odd frame stops
tracking there with an error that names it.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import TrackingError
from toonmotion.rig.kinematics import rotation
from toonmotion.rig.skeleton import Skeleton

Frames = NDArray[np.uint8] | Sequence[NDArray[np.uint8]]


def check_count(frames: Frames) -> int:
    """The number of frames: ``(T, h, w, 3)`` array or a sequence of ``(h, w, 3)`` frames, T >= 1."""
    if isinstance(frames, np.ndarray) and frames.ndim != 4:
        raise TrackingError(
            f"frames have shape {frames.shape}; give a (T, h, w, 3) array or a sequence of (h, w, 3) frames"
        )
    try:
        count = len(frames)
    except TypeError:
        raise TrackingError(
            f"frames must be a (T, h, w, 3) array or a sequence of frames, got {type(frames).__name__}"
        ) from None
    if count == 0:
        raise TrackingError("there are no frames to track; give at least one")
    return count


def is_rgb_frame(image: NDArray[Any]) -> bool:
    """Whether ``image`` is an (h, w, 3) uint8 array with pixels: a frame the tracker can read."""
    return image.ndim == 3 and image.shape[2] == 3 and image.dtype == np.uint8 and 0 not in image.shape


def read_frame(frames: Frames, t: int, shape: tuple[int, ...] | None) -> NDArray[np.uint8]:
    """Frame ``t`` as a contiguous (h, w, 3) uint8 array, checked; ``shape`` that of the first read."""
    image = np.asarray(frames[t])
    if not is_rgb_frame(image):
        raise TrackingError(
            f"frame {t} is a {image.dtype} array of shape {image.shape}; give (h, w, 3) uint8 RGB frames"
        )
    if shape is not None and image.shape != shape:
        raise TrackingError(
            f"frame {t} is {image.shape[1]}x{image.shape[0]} but the first frame read is "
            f"{shape[1]}x{shape[0]}; all frames must be the same size"
        )
    return np.ascontiguousarray(image)


def check_index(value: object, what: str, lowest: int, highest: int, count: int) -> int:
    """``value`` as an int in ``lowest..highest``; ``what`` names it, ``count`` frames are given."""
    index = int(value) if isinstance(value, numbers.Integral) and not isinstance(value, bool) else None
    if index is None or not lowest <= index <= highest:
        raise TrackingError(
            f"{what} is {value!r}; with {count} frames give a whole number {lowest}..{highest}"
        )
    return index


def check_initial(initial: ArrayLike, k: int) -> NDArray[np.float64]:
    """``(k, 2)`` finite float rectangle centres."""
    try:
        xy = np.array(initial, dtype=float)
    except (TypeError, ValueError):
        raise TrackingError(f"initial positions must be numbers, shape ({k}, 2); got {initial!r}") from None
    if xy.shape != (k, 2):
        raise TrackingError(
            f"initial positions have shape {xy.shape}; give one (x, y) per joint, shape ({k}, 2)"
        )
    if not np.all(np.isfinite(xy)):
        raise TrackingError("initial positions include a non-finite value; give finite (x, y) pixels")
    return xy


def check_corrections(corrections: Mapping[str, ArrayLike],
                      skeleton: Skeleton) -> dict[int, NDArray[np.float64]]:
    """``{joint index: (2,) float}`` from ``{name: (x, y)}``."""
    try:
        items = list(corrections.items())
    except AttributeError:
        raise TrackingError(
            f"corrections must map joint names to (x, y), got {type(corrections).__name__}"
        ) from None
    fixed = {}
    for name, xy in items:
        if name not in skeleton.names:
            raise TrackingError(
                f"a correction names joint {name!r}, which is not tracked; "
                f"the joints are: {', '.join(skeleton.names)}"
            )
        try:
            point = np.array(xy, dtype=float)
        except (TypeError, ValueError):
            point = np.empty(0)
        if point.shape != (2,) or not np.all(np.isfinite(point)):
            raise TrackingError(f"the correction of joint {name!r} is {xy!r}; give finite (x, y) pixels")
        fixed[skeleton.index(name)] = point
    return fixed


def check_inside(skeleton: Skeleton, sizes: NDArray[np.float64], centres: NDArray[np.float64],
                 angles: NDArray[np.float64], image: NDArray[np.uint8], t: int, which: Any) -> None:
    """Raise unless the rectangles of joints ``which`` lie inside ``image`` (frame ``t``).

    Rectangle ``m`` is ``sizes[m]`` (width, height) centred on ``centres[m]``, turned by
    ``angles[m]`` radians; the frame spans x ``-0.5..w - 0.5``, y ``-0.5..h - 0.5``.
    """
    H, W = image.shape[:2]
    for m in which:
        (x, y), (w, h) = centres[m], sizes[m]
        # Half the turned rectangle's bounding box: |R| (w, h) / 2.
        hx, hy = np.abs(rotation(angles[m])) @ sizes[m] / 2
        x0, x1, y0, y1 = x - hx, x + hx, y - hy, y + hy
        if x0 < -0.5 - 1e-9 or y0 < -0.5 - 1e-9 or x1 > W - 0.5 + 1e-9 or y1 > H - 0.5 + 1e-9:
            raise TrackingError(
                f"joint {skeleton.names[m]!r} has its {w:g}x{h:g} rectangle at ({x:g}, {y:g}), "
                f"spanning x {x0:g}..{x1:g}, y {y0:g}..{y1:g}, not inside frame {t} ({W}x{H}, "
                f"x -0.5..{W - 0.5:g}, y -0.5..{H - 0.5:g}); move the joint or shrink its rectangle"
            )


def check_number(value: object, what: str, bound: float, rule: str, *, strict: bool = False) -> float:
    """``value`` as a finite float ``>= bound`` (``> bound`` with ``strict``); ``rule`` says which."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TrackingError(f"{what} must be a number {rule}, got {value!r}")
    number = float(value)
    if not math.isfinite(number) or number < bound or (strict and number == bound):
        raise TrackingError(f"{what} must be a finite number {rule}, got {number!r}")
    return number


def whole(default: int, least: int = 1) -> Any:
    """A settings field that is a whole number >= ``least`` (:func:`check_ranges`)."""
    return field(default=default, metadata={"whole": least})


def share(default: float) -> Any:
    """A settings field from 0 to 1, a confidence or a fraction (:func:`check_ranges`)."""
    return field(default=default, metadata={"least": 0.0, "most": 1.0})


def at_least(bound: float, default: float) -> Any:
    """A settings field that is a number >= ``bound`` (:func:`check_ranges`)."""
    return field(default=default, metadata={"least": bound})


def above(bound: float, default: float) -> Any:
    """A settings field that is a number > ``bound`` (:func:`check_ranges`)."""
    return field(default=default, metadata={"least": bound, "strict": True})


def check_ranges(settings: Any) -> None:
    """Check a frozen settings dataclass's fields against the ranges they were declared with
    (:func:`whole`, :func:`share`, :func:`at_least`, :func:`above`), storing each as an ``int``
    or a ``float``; a one-line :class:`TrackingError` names the first out of its range."""
    for item in fields(settings):
        name, value = item.name, getattr(settings, item.name)
        number: int | float
        if "whole" in item.metadata:
            least = item.metadata["whole"]
            if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
                raise TrackingError(f"{name} must be a whole number >= {least}, got {value!r}")
            number = int(value)
        elif "least" in item.metadata:
            least, most = item.metadata["least"], item.metadata.get("most")
            strict = bool(item.metadata.get("strict"))
            bound = f"{'>' if strict else '>='} {least:g}"
            rule = f"from {least:g} to {most:g}" if most is not None else bound
            number = check_number(value, name, least, rule, strict=strict)
            if most is not None and number > most:
                raise TrackingError(f"{name} must be a finite number {rule}, got {number!r}")
        else:
            continue
        object.__setattr__(settings, name, number)


def check_order(settings: Any, low: str, high: str) -> None:
    """Raise a one-line :class:`TrackingError` unless field ``low`` of ``settings`` is at most its
    field ``high`` (the two ends of a range)."""
    if getattr(settings, low) > getattr(settings, high):
        raise TrackingError(
            f"{low} must be at most {high}, got {getattr(settings, low)!r} > {getattr(settings, high)!r}"
        )


@dataclass(frozen=True)
class Tuning:
    """A frozen set of the tracker's tuning values, each declared with its range (:func:`whole`,
    :func:`share`, :func:`at_least`, :func:`above`) and checked when the set is made
    (:func:`check_ranges`). Each subclass documents its values, their units and ranges, and the
    measurement that chose each default.

    Raises
    ------
    TrackingError
        A value out of its range, in one line naming it.
    """

    def __post_init__(self) -> None:
        check_ranges(self)
