"""Angles in radians, ``atan2(dy, dx)`` in the image frame (y down)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

# A float or an array of them; numpy gives back its float64 scalar (a float) for 0-d input.
Angles = float | NDArray[np.float64]


def wrap_angle(a: Angles) -> Angles:
    """Angles wrapped into ``[-pi, pi)``.

    >>> float(wrap_angle(3 * np.pi / 2))
    -1.5707963267948966
    """
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def lerp_angle(a: Angles, b: Angles, t: Angles) -> Angles:
    """Interpolate from angle ``a`` to ``b`` the short way round (slerp of 2D directions).

    >>> round(float(np.degrees(lerp_angle(np.radians(170), np.radians(-170), 0.5))), 6)
    180.0
    """
    return a + t * wrap_angle(b - a)
