"""The drawing's virtual markers (section 3.1.1): named 2D points on every drawn frame.

A :class:`Markers` is what the user annotates (or what tracking or an animation gives): ``N``
named markers over ``T`` frames, drawing pixels, y down, with the drawing's frame rate. It holds
no hierarchy: limbs come from the motion prior's skeleton (:mod:`toonmotion.proxy3d.prior`), so
markers named after joints of any skeleton can be used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion import limits
from toonmotion.animate.motion import Motion
from toonmotion.errors import ProxyError
from toonmotion.geometry.arrays import check_coordinates, frame_rate, frozen_array


@dataclass(frozen=True, eq=False)
class Markers:
    """Named 2D markers over time.

    Attributes
    ----------
    names : tuple of str
        Distinct, non-empty marker names, in column order.
    positions : (T, N, 2) float
        ``(x, y)`` drawing pixels, y down, of every marker at every frame.
    fps : float
        Frames per second of the drawing.

    Construction copies the positions (read-only) and raises :class:`ProxyError` unless the
    names are distinct non-empty strings and the positions finite ``(T, N, 2)`` with
    ``T >= 1``, one column per name, and the fps a number of frames per second.

    Examples
    --------
    >>> m = Markers(("hip", "knee"), np.zeros((3, 2, 2)), fps=12)
    >>> m.frame_count, m.index("knee"), m.fps
    (3, 1, 12.0)
    >>> Markers(("hip", "hip"), np.zeros((3, 2, 2)), fps=12)
    Traceback (most recent call last):
    ...
    toonmotion.errors.ProxyError: marker name 'hip' is used twice; names must be unique
    """

    names: tuple[str, ...]
    positions: NDArray[np.float64]
    fps: float

    def __post_init__(self) -> None:
        if isinstance(self.names, str):
            raise ProxyError("markers' names must be a list of names, not one string")
        names = tuple(self.names)
        if not names:
            raise ProxyError("there are no markers; give at least one named marker")
        if not all(isinstance(n, str) and n.strip() for n in names):
            raise ProxyError("every marker needs a name: a non-empty string")
        if len(set(names)) != len(names):
            twice = next(n for n in names if names.count(n) > 1)
            raise ProxyError(f"marker name {twice!r} is used twice; names must be unique")
        positions = frozen_array(self.positions, dtype=np.float64, name="the markers' positions",
                                 error=ProxyError)
        if positions.ndim != 3 or positions.shape[1:] != (len(names), 2):
            raise ProxyError(f"markers need positions of shape (frames, {len(names)}, 2) for their "
                             f"{len(names)} names, got {positions.shape}")
        if len(positions) == 0:
            raise ProxyError("the markers have no frames; give at least one frame")
        limits.check("frames", len(positions), "the markers' frame count")
        if not np.isfinite(positions).all():
            bad = np.argwhere(~np.isfinite(positions))[0]
            raise ProxyError(f"marker {names[bad[1]]!r} at frame {bad[0]} is not a finite number (NaN or "
                             "infinity); give every marker a position on every frame")
        check_coordinates(positions, "the markers' positions", ProxyError)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "fps", frame_rate(self.fps, name="the markers' fps", error=ProxyError))

    @property
    def frame_count(self) -> int:
        """Number of frames, ``T``."""
        return len(self.positions)

    def index(self, name: str) -> int:
        """Column of the marker called ``name``; :class:`ProxyError` if there is none."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ProxyError(f"no marker is called {name!r}; the markers are: "
                             f"{', '.join(self.names)}") from None

    def select(self, names: tuple[str, ...] | list[str]) -> Markers:
        """These markers only, in the order of ``names``.

        >>> m = Markers(("a", "b"), [[[0, 0], [1, 2]]], fps=24).select(["b"])
        >>> m.names, m.positions.tolist()
        (('b',), [[[1.0, 2.0]]])
        """
        columns = [self.index(n) for n in names]
        return Markers(tuple(names), self.positions[:, columns], self.fps)


def markers_from_motion(motion: Motion) -> Markers:
    """A toonmotion motion's joints as markers: one marker per joint, named after it.

    Parameters
    ----------
    motion : Motion
        From ``track``, an animation, or a motion file (:func:`toonmotion.io.motion_json.load_motion`).

    Returns
    -------
    Markers
        The joints' positions and the motion's fps; the skeleton's hierarchy is not kept (the
        prior's is used).

    Examples
    --------
    >>> from toonmotion.rig.skeleton import Skeleton
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> m = markers_from_motion(Motion(arm, np.zeros((4, 2, 2)), fps=12.0))
    >>> m.names, m.positions.shape, m.fps
    (('shoulder', 'hand'), (4, 2, 2), 12.0)
    """
    return Markers(motion.skeleton.names, motion.positions, motion.fps)
