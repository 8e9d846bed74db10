"""Capturing motion from footage: the call behind ``track``."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from toonmotion.animate.motion import Motion
from toonmotion.capture.footage import Capture, capture_motion, correct_motion, suggest_joints
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.errors import SettingsError
from toonmotion.progress import Progress
from toonmotion.rig.skeleton import Skeleton


def track_footage(
    frames: NDArray[np.uint8],
    *,
    joints: tuple[Skeleton, NDArray[np.float64]] | None = None,
    start: int = 0,
    fps: float = 24.0,
    background: tuple[int, int, int] | None = None,
    settings: TrackSettings | None = None,
    earlier: Motion | None = None,
    corrections: Mapping[str, tuple[float, float]] | None = None,
    at: int | None = None,
    progress: Progress | None = None,
) -> Capture:
    """Track a character's joints through footage (thesis ch. 4).

    Parameters
    ----------
    frames : (T, H, W, 3) uint8
        RGB frames (:func:`toonmotion.io.frames.load_frames` reads videos, GIFs and folders).
    joints : (Skeleton, (k, 2) float), optional
        Each joint's position at frame ``start`` and its rectangle's (width, height). Without it,
        joints are suggested from the first frame's figure (:func:`suggest_joints`).
    start : int
        The frame ``joints`` are placed on; tracking runs forwards from it.
    fps : float
        The footage's frame rate, carried into the motion.
    background : (int, int, int), optional
        A flat background colour, to find the figure by: joints are suggested on it and held to
        it (``settings.figure``). Default: the first frame's border colour, when that is flat.
    settings : TrackSettings, optional
        How to track; its ``cutout`` is also how the figure is found to suggest joints on.
    earlier : Motion, optional
        A tracking to correct: give the ``corrections`` (joint name to true ``(x, y)``) at frame
        ``at``; tracking resumes there and the frames before it are kept.
    corrections : mapping of str to (float, float), optional
    at : int, optional
    progress : callable, optional
        ``progress(stage, index, count)`` after each frame.

    Returns
    -------
    Capture
        The motion (with each joint's confidence per frame), its first frame and the rectangles'
        angles.

    Raises
    ------
    SettingsError
        ``earlier`` without ``corrections`` or ``at``.
    TrackingError
        No figure to suggest joints from, or joints outside the frame.

    Examples
    --------
    >>> from toonmotion.samples import sample_character_on
    >>> picture, skeleton = sample_character_on("white", scale=0.5)
    >>> frames = np.stack([np.roll(picture, 2 * t, axis=1) for t in range(4)])  # walks right
    >>> sizes = np.full((len(skeleton), 2), 16.0)
    >>> capture = track_footage(frames, joints=(skeleton, sizes))
    >>> np.round(capture.motion.positions[-1, 0] - capture.motion.positions[0, 0]).tolist()
    [6.0, 0.0]
    """
    cutout = None if settings is None else settings.cutout
    skeleton, sizes = suggest_joints(frames, colour=background, tuning=cutout) if joints is None else joints
    if earlier is None:
        return capture_motion(frames, skeleton, sizes, fps=fps, start=start, settings=settings,
                              background=background, progress=progress)
    if at is None or not corrections:
        raise SettingsError("correcting an earlier tracking needs the corrections and the frame they are at")
    return correct_motion(earlier, frames, skeleton, sizes, at, corrections, fps=fps, start=start,
                          settings=settings, background=background, progress=progress)
