"""The cartoon animation filter over time (Wang et al. 2005; thesis 5.1 and 5.2.2, eq. 5.1-5.4, 5.6).

A motion signal ``x(t)`` is filtered as

    x*(t) = x(t) - x''(t) (*) A exp(-((t - shift) / sigma)^2)

so the motion dips back before it starts (anticipation) and overshoots where it stops
(follow-through). :func:`cartoon_filter` filters any signal; :func:`filter_trajectories`
filters chosen joints' 2D paths and carries their subtrees along; :func:`filter_bones` filters
a captured motion the thesis' way, every bone's length and angle as separate signals.

Choices where the paper leaves them open:

- Time is in frames (the thesis' ``tau`` is one frame), so ``sigma`` and ``shift`` are frames.
  ``shift`` is Wang's ``Delta t`` times ``sigma``.
- The second derivative is the central difference ``x[t+1] - 2 x[t] + x[t-1]``. The thesis'
  backward differences (eq. 5.6) give the same numbers one frame late, which would put the dip
  and the overshoot a frame after the velocity changes; central ones are centred on the change.
- The convolution is a discrete sum over whole frame offsets ``tau`` of
  ``A exp(-((tau - shift) / sigma)^2)``, *not* normalised (eq. 5.4 literally), so ``A`` is a
  number of frames: a ball that starts moving at ``v`` px/frame with no easing dips back by
  ``A v`` px at the frame it starts from, and overshoots by ``A v`` px where it stops dead.
  (A normalised kernel would make the dip shrink as ``sigma`` grows.)
  The sum runs over ``|tau - shift| <= 3 sigma``: the kernel radius is ``ceil(3 sigma + |shift|)``.
- The shift's sign: frame ``t`` subtracts ``sum_tau x''(t - tau) k(tau)`` with the kernel
  ``k`` centred at ``tau = shift``, so a change of velocity at frame ``t0`` pulls hardest at
  frame ``t0 + shift``. ``shift > 0`` delays the response: the dip comes ``shift`` frames after
  the motion starts (a drag, the figure lags behind its own start) and the overshoot ``shift``
  frames after it stops; ``shift < 0`` brings them forward, so the anticipation begins earlier
  and the follow-through settles sooner. Different shifts on different parts give squash and
  stretch (Wang et al.).
- Ends of the clip: the signal is taken to carry on past each end at its end velocity (linear
  extrapolation from the first or last two frames). Then ``x''`` is 0 at the first and last
  frames and everywhere beyond them, so nothing happens at an end that the motion itself does
  not do: a signal moving at constant velocity is unchanged, ends included, and the filter adds
  no jump at the first or last frame. The code writes those zeros directly rather than
  differencing the extension (the same numbers without its rounding). The thesis instead starts
  filtering at the second frame.
- :func:`filter_bones` unwraps each bone's angle along time (``np.unwrap``) before filtering, so
  a bone turning through +-pi is a smooth signal, not a 2 pi jump. A filtered bone length is kept
  at least :data:`MIN_LENGTH_FRACTION` of that bone's longest length in the clip: a strong filter
  squashes a bone but never collapses it or flips it through its parent. A bone of zero length
  has no direction (its angle reads 0); one that passes through zero length mid-clip gets an
  arbitrary jump in angle there, which the filter then exaggerates.
"""

from __future__ import annotations

import math
import numbers
import sys
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import convolve1d

from toonmotion.errors import FilterError
from toonmotion.rig.kinematics import bone_angles, positions_from_bones
from toonmotion.rig.skeleton import Skeleton

# A filtered bone keeps at least this fraction of its longest length in the clip.
MIN_LENGTH_FRACTION = 0.1

# The kernel is summed out to this many sigmas from its centre.
KERNEL_SIGMAS = 3.0


@dataclass(frozen=True)
class FilterSettings:
    """How strongly and how widely the cartoon filter acts.

    Attributes
    ----------
    strength : float
        ``A`` (eq. 5.3), >= 0; 0 leaves the motion as it is. A ball starting at ``v`` px/frame
        dips back by ``A v`` px.
    sigma : float
        Width of the Gaussian, frames, > 0.
    shift : float
        Time shift of the Gaussian, frames (Wang's ``Delta t`` times ``sigma``); > 0 delays
        the anticipation and follow-through, < 0 advances them.
    """

    strength: float
    sigma: float = 3.0
    shift: float = 0.0

    def __post_init__(self) -> None:
        # Kept as plain floats.
        object.__setattr__(self, "strength", _number(self.strength, "the filter strength", ">= 0"))
        object.__setattr__(self, "sigma", _number(self.sigma, "the filter width sigma (frames)", "> 0"))
        object.__setattr__(self, "shift", _number(self.shift, "the filter time shift (frames)"))

    @property
    def radius(self) -> int:
        """How many frames either side of its centre the kernel reaches: ``ceil(3 sigma + |shift|)``."""
        return math.ceil(min(KERNEL_SIGMAS * self.sigma + abs(self.shift), sys.float_info.max))


def cartoon_filter(signal: ArrayLike, settings: FilterSettings) -> NDArray[np.float64]:
    """Filter a motion signal: ``x*(t) = x(t) - x''(t) (*) A exp(-((t - shift)/sigma)^2)``.

    Eq. 5.1, 5.3 and 5.4, with time in frames; see the module notes for the differences, the
    kernel and the ends of the clip.

    Parameters
    ----------
    signal : (T, ...) float
        Time along axis 0, one row per frame; trailing axes (joints, x and y) are filtered
        independently.
    settings : FilterSettings

    Returns
    -------
    (T, ...) float
        A new array. One frame comes back as a copy.

    Examples
    --------
    A ball waits at x = 10, moves at 1 px/frame, stops: it dips back by ``A v`` = 1 px before
    it starts and overshoots by 1 px where it stops.

    >>> x = np.array([10, 10, 10, 11, 12, 13, 13, 13], float)
    >>> np.round(cartoon_filter(x, FilterSettings(strength=1.0, sigma=0.5)), 2).tolist()
    [10.0, 9.98, 9.0, 10.98, 12.02, 14.0, 13.02, 13.0]
    """
    _check_settings(settings)
    x = _check_signal(signal)
    if len(x) == 1 or settings.strength == 0:
        return x.copy()
    with np.errstate(over="ignore", invalid="ignore"):
        out = x - _smoothed_second_derivative(x, settings)
    if not np.all(np.isfinite(out)):
        raise FilterError(
            f"the filter strength {settings.strength:g} throws the motion beyond any finite position; "
            "use a strength of about 0.5 to 3"
        )
    return out


def filter_trajectories(
    skeleton: Skeleton, positions: ArrayLike, settings: FilterSettings, *, joints: Sequence[str]
) -> NDArray[np.float64]:
    """Filter the 2D paths of some joints; everything below a filtered joint follows it.

    Every other joint moves by the change of its nearest filtered ancestor-or-self, so the
    whole body follows a filtered root, and a hand's subtree (fingers) follows a filtered hand.
    Joints with no filtered ancestor stay where they are.

    Parameters
    ----------
    skeleton : Skeleton
    positions : (T, k, 2) float
        The motion: every joint's (x, y) pixels, y down, in every frame.
    settings : FilterSettings
    joints : sequence of str
        Names of the joints whose paths are filtered.

    Returns
    -------
    (T, k, 2) float
    """
    _check_settings(settings)
    P = _check_positions(skeleton, positions)
    chosen = joint_indices(skeleton, joints, what="joints to filter")
    out = P.copy()
    if not chosen:
        return out
    filtered = cartoon_filter(P[:, chosen], settings)
    change = np.zeros_like(P)
    change[:, chosen] = filtered - P[:, chosen]
    carrier = _nearest_chosen_ancestor(skeleton, chosen)
    carried = carrier >= 0
    out[:, carried] += change[:, carrier[carried]]
    out[:, chosen] = filtered  # exactly, not P + (filtered - P)
    return out


def filter_bones(skeleton: Skeleton, positions: ArrayLike, settings: FilterSettings) -> NDArray[np.float64]:
    """Filter a captured motion the thesis' way (5.2.2, eq. 5.6): roots, bone lengths, bone angles.

    Every root joint's path, every bone's length and every bone's angle are filtered as
    separate signals (angles unwrapped along time first), then the poses are rebuilt parents
    first from the roots: ``child = parent + length (cos angle, sin angle)``. A filtered length
    is kept at least :data:`MIN_LENGTH_FRACTION` of that bone's longest length in the clip, so
    a strong filter squashes a bone but never collapses or flips it.

    Parameters
    ----------
    skeleton : Skeleton
    positions : (T, k, 2) float
        Every joint's (x, y) pixels, y down, in every frame.
    settings : FilterSettings

    Returns
    -------
    (T, k, 2) float
    """
    _check_settings(settings)
    P = _check_positions(skeleton, positions)
    roots = cartoon_filter(P[:, skeleton.parents < 0], settings)
    angle, length = bone_angles(skeleton, P)  # (T, b) each
    angle = cartoon_filter(np.unwrap(angle, axis=0), settings)
    floor = MIN_LENGTH_FRACTION * length.max(axis=0)
    length = np.maximum(cartoon_filter(length, settings), floor)
    return positions_from_bones(skeleton, roots, angle, length)


def joint_indices(skeleton: Skeleton, names: Sequence[str], *, what: str = "joints") -> list[int]:
    """Indices of the joints called ``names`` (a sequence of str), in the given order, unrepeated.

    Raises :class:`FilterError` on unknown names, listing the skeleton's joints.
    """
    if isinstance(names, str) or not _is_sequence(names):
        raise FilterError(f"{what} must be a sequence of joint names such as ['root'], got {names!r}")
    names = list(names)
    unknown = [n for n in names if n not in skeleton.names]
    if unknown:
        raise FilterError(
            f"{what}: unknown joint {unknown[0]!r}; the skeleton's joints are: {', '.join(skeleton.names)}"
        )
    return list(dict.fromkeys(skeleton.names.index(n) for n in names))


# --- helpers -----------------------------------------------------------------------------------


def _smoothed_second_derivative(x, settings):
    """``x'' (*) k`` over frames, ``x''`` zero at the first and last frame and beyond (see notes)."""
    d2 = np.zeros_like(x)
    d2[1:-1] = x[2:] - 2 * x[1:-1] + x[:-2]
    # Past the clip's length the kernel only meets zeros: a very wide filter costs no more.
    reach = min(settings.radius, len(x))
    offsets = np.arange(-reach, reach + 1)
    with np.errstate(over="ignore", under="ignore"):  # far from its centre the kernel is 0
        kernel = settings.strength * np.exp(-(((offsets - settings.shift) / settings.sigma) ** 2))
    # out[t] = sum over tau of kernel(tau) d2[t - tau], d2 zero beyond the clip.
    return convolve1d(d2, kernel, axis=0, mode="constant", cval=0.0)


def _nearest_chosen_ancestor(skeleton, chosen):
    """For each joint, the nearest of ``chosen`` at or above it, -1 when there is none; ``(k,)``."""
    carrier = np.full(len(skeleton), -1)
    is_chosen = np.zeros(len(skeleton), dtype=bool)
    is_chosen[chosen] = True
    for j, parent in enumerate(skeleton.parents):  # parents come first
        carrier[j] = j if is_chosen[j] else (carrier[parent] if parent >= 0 else -1)
    return carrier


def _check_settings(settings):
    if not isinstance(settings, FilterSettings):
        raise FilterError(f"settings must be a FilterSettings, got {type(settings).__name__}")


def _check_signal(signal):
    try:
        x = np.array(signal, dtype=float)
    except (TypeError, ValueError):
        raise FilterError("the signal must be an array of numbers with time along axis 0") from None
    if x.ndim == 0:
        raise FilterError("the signal has no time axis; give an array of shape (frames, ...)")
    if len(x) == 0:
        raise FilterError("the signal has no frames; give at least one")
    if not np.all(np.isfinite(x)):
        frame = int(np.flatnonzero(~np.isfinite(x.reshape(len(x), -1)).all(axis=1))[0])
        raise FilterError(f"the signal has a non-finite value at frame {frame}; give finite numbers")
    return x


def _check_positions(skeleton, positions):
    try:
        P = np.array(positions, dtype=float)
    except (TypeError, ValueError):
        raise FilterError("positions must be an array of numbers of shape (frames, joints, 2)") from None
    if P.ndim != 3 or P.shape[1:] != (len(skeleton), 2) or len(P) == 0:
        raise FilterError(
            f"positions must have shape (frames, {len(skeleton)}, 2) for this skeleton's "
            f"{len(skeleton)} joints, got {P.shape}"
        )
    return _check_signal(P)


def _number(value, what, bound=""):
    """``value`` as a float: a finite real number (not a bool), ``>= 0`` or ``> 0`` if ``bound`` says."""
    rule = f"a finite number {bound}".rstrip()
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise FilterError(f"{what} must be {rule}, got {value!r}")
    value = float(value)
    within = {"": True, ">= 0": value >= 0, "> 0": value > 0}[bound]
    if not (math.isfinite(value) and within):
        raise FilterError(f"{what} must be {rule}, got {value}")
    return value


def _is_sequence(value):
    try:
        iter(value)
    except TypeError:
        return False
    return True
