"""Read-only copies of arrays, for the fields of the core types.

The core types (``Mesh``, ``Skeleton``, ``Binding``, ``Pose``, ``Motion`` ...) are frozen
dataclasses, and their arrays must not change either. Each one's ``__post_init__`` passes every
array field through :func:`frozen_array`, which copies the value (the caller's array stays the
caller's, and writeable), converts it to the field's dtype, checks its shape and marks the copy
read-only. It always copies, even an array that is already read-only: a writeable view of it
may be held elsewhere. (Copying the ``(1500, 2)`` vertices of a mesh takes about a microsecond.)

Examples
--------
>>> mine = np.zeros((3, 2))
>>> V = frozen_array(mine, dtype=np.float64, shape=(None, 2), name="V")
>>> mine[0, 0] = 5.0
>>> float(V[0, 0]), V.flags.writeable, mine.flags.writeable
(0.0, False, True)
>>> frozen_array(V, dtype=np.float64) is V
False
>>> frozen_array([[1, 2, 3]], dtype=np.float64, shape=(None, 2), name="V")
Traceback (most recent call last):
...
ValueError: V must have shape (n, 2), got (1, 3)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, TypedDict, Unpack

import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

# Kinds of input dtype each kind of target accepts: b bool, i/u integers, f floats.
_ACCEPTS = {"b": "b", "i": "biuf", "u": "biuf", "f": "biuf"}
_LETTERS = "nmkl"


# No coordinate in drawing pixels lies further out than this: ten million pixels is far beyond any
# picture toonmotion may draw (toonmotion.limits canvas_side), and beyond it floating-point
# geometry (areas, intersections, solves) loses all its precision.
MAX_COORDINATE = 10_000_000.0


def check_coordinates(values: NDArray[Any], name: str, error: type[Exception]) -> None:
    """Raise ``error`` unless every value is finite and within :data:`MAX_COORDINATE` of 0."""
    if not np.isfinite(values).all():
        raise error(f"{name} has a non-finite value (NaN or infinity)")
    if values.size and np.abs(values).max() > MAX_COORDINATE:
        raise error(f"{name} has a coordinate beyond {MAX_COORDINATE:,.0f} pixels from the origin "
                    f"({float(np.abs(values).max()):.3g}); nothing toonmotion draws reaches that far")


def frozen_array(
    value: ArrayLike,
    *,
    dtype: DTypeLike,
    shape: Sequence[int | None] | None = None,
    name: str = "array",
    error: type[Exception] = ValueError,
    finite: bool = False,
    coordinates: bool = False,
) -> NDArray[Any]:
    """A read-only, C-contiguous copy of ``value`` as ``dtype``.

    Parameters
    ----------
    value : array_like
        The data. Not modified; an ndarray stays writeable if it was.
    dtype : dtype
        A bool, integer or float dtype. Floats become integers only when they are whole
        numbers, and integers only fit an integer dtype whose range holds them.
    shape : sequence of int or None, optional
        The shape pattern: ``(None, 2)`` accepts ``(n, 2)`` for any ``n``.
    name : str
        What the value is, for the error message (``"a mesh's V"``).
    error : exception class
        Raised, with a one-line message naming ``name``, when the value does not fit.
    finite : bool
        Also refuse NaN and infinite values.
    coordinates : bool
        The values are drawing pixels: also refuse NaN, infinity and values beyond
        :data:`MAX_COORDINATE` (:func:`check_coordinates`).

    Returns
    -------
    ndarray
        A new, read-only array.
    """
    out = _converted(value, np.dtype(dtype), name, error)
    if shape is not None and (
        out.ndim != len(shape) or any(s not in (None, d) for s, d in zip(shape, out.shape, strict=False))
    ):
        raise error(f"{name} must have shape {_pattern(shape)}, got {out.shape}")
    if finite and out.dtype.kind == "f" and not np.isfinite(out).all():
        raise error(f"{name} has a non-finite value (NaN or infinity)")
    if coordinates:
        check_coordinates(out, name, error)
    out.setflags(write=False)
    return out


class _Checks(TypedDict, total=False):
    """:func:`frozen_array`'s checks, passed on by :func:`frozen_arrays`."""

    shape: Sequence[int | None] | None
    finite: bool
    coordinates: bool


def frozen_arrays(values: Iterable[ArrayLike], *, dtype: DTypeLike, name: str = "array",
                  error: type[Exception] = ValueError, **checks: Unpack[_Checks]) -> tuple[NDArray[Any], ...]:
    """:func:`frozen_array` of every item (``shape``, ``finite`` and ``coordinates`` as there), as a
    tuple; messages name ``name[i]``."""
    if isinstance(values, np.ndarray) and values.ndim == 0 or not isinstance(values, Iterable):
        raise error(f"{name} must be a sequence of arrays, got {type(values).__name__}")
    return tuple(frozen_array(v, dtype=dtype, name=f"{name}[{i}]", error=error, **checks)
                 for i, v in enumerate(values))


def finite_float(
    value: object, *, name: str, error: type[Exception] = ValueError, minimum: float | None = None,
    strict: bool = False,
) -> float:
    """``value`` as a finite float, at least ``minimum`` (above it when ``strict``).

    Raises ``error`` with a one-line message naming ``name`` otherwise; ``True`` and ``False``
    are not numbers here.

    >>> finite_float(3, name="spacing", minimum=0, strict=True)
    3.0
    """
    number = float("nan")
    if not isinstance(value, bool | str | bytes):
        try:
            number = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            pass
    low = minimum if minimum is not None else -np.inf
    if not (np.isfinite(number) and (number > low if strict else number >= low)):
        bound = "" if minimum is None else f" {'>' if strict else '>='} {minimum:g}"
        raise error(f"{name} must be a finite number{bound}, got {value!r}")
    return number


# Frame rates toonmotion reads and writes: from a frame every 100 s to a thousand a second (GIF
# stores a frame's time in hundredths of a second, up to 655 s).
FPS_RANGE = (0.01, 1000.0)


def frame_rate(value: object, *, name: str = "fps", error: type[Exception] = ValueError) -> float:
    """``value`` as frames per second within :data:`FPS_RANGE`; ``error`` otherwise.

    >>> frame_rate(24)
    24.0
    """
    low, high = FPS_RANGE
    number = finite_float(value, name=name, error=error, minimum=0, strict=True)
    if not low <= number <= high:
        raise error(f"{name} must be between {low:g} and {high:g} frames per second, got {number:g}")
    return number


def finite_point(value: object, *, name: str, error: type[Exception] = ValueError) -> tuple[float, float]:
    """``value`` as an ``(x, y)`` pair of finite floats; ``error`` naming ``name`` otherwise.

    >>> finite_point([3, 4.5], name="joint 'neck'")
    (3.0, 4.5)
    """
    try:
        x, y = (float(v) for v in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise error(f"{name} has position {value!r}; give two numbers [x, y]") from None
    if not (np.isfinite(x) and np.isfinite(y)):
        raise error(f"{name} has a non-finite position ({x}, {y})")
    if max(abs(x), abs(y)) > MAX_COORDINATE:
        raise error(f"{name} has position ({x:.3g}, {y:.3g}), over {MAX_COORDINATE:,.0f} px from the origin")
    return x, y


def _converted(value: ArrayLike, target: np.dtype[Any], name: str, error: type[Exception]) -> NDArray[Any]:
    try:
        source = np.asarray(value)
    except (TypeError, ValueError):
        raise error(f"{name} must be an array of numbers of one shape") from None
    if source.dtype.kind not in _ACCEPTS.get(target.kind, target.kind):
        what = "true/false values" if target.kind == "b" else "numbers"
        raise error(f"{name} must hold {what}, got {source.dtype} values")
    narrowing = target.kind in "iu" and source.size > 0 and not np.can_cast(source.dtype, target)
    if narrowing and source.dtype.kind == "f" and not np.isfinite(source).all():
        raise error(f"{name} must hold whole numbers that fit {target}")
    out = source.astype(target, order="C", copy=True)
    if narrowing and not np.array_equal(out, source):
        raise error(f"{name} must hold whole numbers that fit {target}")
    return out


def _pattern(shape: Sequence[int | None]) -> str:
    letters = iter(_LETTERS)
    parts = [str(s) if s is not None else next(letters, "n") for s in shape]
    return f"({parts[0]},)" if len(parts) == 1 else f"({', '.join(parts)})"
