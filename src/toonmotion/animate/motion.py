"""Motion: a pose for every frame, as one array (captured, filtered or sampled from key-frames).

A motion is ``(frames, joints, 2)`` joint positions plus a frame rate, for a skeleton whose
joint names and parents say what the columns are. It is what the cartoon filter reads and
writes, what motion capture produces, and what ``toonmotion animate`` plays frame by frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion import limits
from toonmotion.animate.timeline import Timeline, pose_at
from toonmotion.errors import MotionError
from toonmotion.geometry.arrays import check_coordinates, frame_rate, frozen_array
from toonmotion.rig.pose import Pose
from toonmotion.rig.skeleton import Skeleton


@dataclass(frozen=True, eq=False)
class Motion:
    """Joint positions over time.

    Attributes
    ----------
    skeleton : Skeleton
        Joint names and parents; its positions are the rest pose the motion was made for.
    positions : (T, k, 2) float
        (x, y) pixels, y down, of every joint at every frame.
    fps : float
        Frames per second.
    confidence : (T, k) float in [0, 1], optional
        How sure motion capture was of each joint at each frame (None when not captured).

    Construction copies the arrays (read-only) and raises :class:`MotionError` unless the
    positions are finite ``(T, k, 2)`` with ``T >= 1``, the fps a finite number > 0 and the
    confidence ``(T, k)`` in [0, 1].
    """

    skeleton: Skeleton
    positions: NDArray[np.float64]
    fps: float
    confidence: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.skeleton, Skeleton):
            raise TypeError(f"a motion's skeleton must be a Skeleton, got {type(self.skeleton).__name__}")
        try:
            positions = np.asarray(self.positions, dtype=float)
        except (TypeError, ValueError):
            raise MotionError("a motion's positions must be an array of numbers") from None
        k = len(self.skeleton)
        if positions.ndim != 3 or positions.shape[1:] != (k, 2) or len(positions) == 0:
            raise MotionError(
                f"a motion needs positions of shape (frames, {k}, 2) for its {k} joints, "
                f"got {positions.shape}"
            )
        if not np.all(np.isfinite(positions)):
            frame = int(np.flatnonzero(~np.isfinite(positions).all(axis=(1, 2)))[0])
            raise MotionError(f"frame {frame} of the motion has a non-finite joint position")
        limits.check("frames", len(positions), "the motion's frame count")
        check_coordinates(positions, "the motion's positions", MotionError)
        object.__setattr__(self, "fps", frame_rate(self.fps, name="the motion's fps", error=MotionError))
        if self.confidence is not None:
            confidence = frozen_array(self.confidence, dtype=np.float64, name="the motion's confidence",
                                      error=MotionError)
            if confidence.shape != positions.shape[:2]:
                raise MotionError(f"the motion's confidence must have shape {positions.shape[:2]}, "
                                  f"got {confidence.shape}")
            if not np.all((confidence >= 0) & (confidence <= 1)):
                raise MotionError("the motion's confidence values must lie between 0 and 1")
            object.__setattr__(self, "confidence", confidence)
        object.__setattr__(self, "positions", frozen_array(positions, dtype=np.float64))
        object.__setattr__(self, "fps", float(self.fps))

    @property
    def frame_count(self) -> int:
        """Number of frames, ``T``."""
        return len(self.positions)

    def pose(self, frame: int) -> Pose:
        """The pose at ``frame`` (an index)."""
        return Pose(self.positions[frame])


def motion_from_timeline(skeleton: Skeleton, timeline: Timeline) -> Motion:
    """Sample key-frames and their in-betweens into a :class:`Motion`, one pose per frame."""
    frames = [pose_at(skeleton, timeline, f).positions for f in range(timeline.frame_count)]
    return Motion(skeleton=skeleton, positions=np.stack(frames), fps=timeline.fps)


def motion_for(skeleton: Skeleton, motion: Motion, *, where: str = "the motion") -> NDArray[np.float64]:
    """``motion``'s positions in ``skeleton``'s joint order, ``(T, k, 2)``.

    The motion must name every joint of ``skeleton`` (it may have more); retargeting a motion
    made for a differently built skeleton is a separate step.
    """
    names = motion.skeleton.names
    missing = [n for n in skeleton.names if n not in names]
    if missing:
        raise MotionError(
            f"{where} has no joint {missing[0]!r}"
            + (f" (and {len(missing) - 1} more are missing)" if len(missing) > 1 else "")
            + f"; its joints are: {', '.join(names)}"
        )
    return motion.positions[:, [names.index(n) for n in skeleton.names]]
