"""Joint tracking measured on rendered motion capture, where the true joints are known.

A BVH clip is read, its 16 :data:`~toonmotion.capture.mocap.STANDARD_JOINTS` are picked by the
usual naming conventions (CMU, FAIR, Mixamo, Rokoko), projected orthographically from the front,
fitted into the frame (640x480 by default) and resampled to about 30 fps; a leading T-pose frame
that the motion jumps away from (CMU's MotionBuilder files) is dropped. The joints drive a
textured limb figure over a textured background, drawn far to near so that limbs cross and hide
each other (:func:`toonmotion.capture.synthetic.limb_figure_frames`). A tracker starts from the
true frame-0 rectangles (squares of the joint disc's diameter) and its joint centres are scored
against the true ones.

Points are ``(x, y)`` pixels, x right, y down. ``benchmarks/track.py`` runs this on every shared
clip against OpenCV's trackers; ``tests/capture/test_track_benchmark.py`` on a short clip.

>>> found = np.zeros((3, 2, 2))
>>> truth = found + [[[0.0, 0.0]], [[3.0, 4.0]], [[0.0, 30.0]]]  # frame 0 is not scored
>>> tracking_scores(found, truth)
{'mean_px': 17.5, 'median_px': 17.5, 'pck5': 0.5, 'lost': 0.5}
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics
from toonmotion.capture.foreground import flat_figure_masks
from toonmotion.capture.mocap import (
    STANDARD_JOINTS,
    fit_to_frame,
    pick_joints,
    project_orthographic,
    standard_skeleton_parents,
)
from toonmotion.capture.synthetic import limb_figure_frames
from toonmotion.capture.track_settings import TrackSettings, TrackSetup
from toonmotion.capture.tracker import track
from toonmotion.io.bvh import load_bvh
from toonmotion.rig.skeleton import Skeleton

SIZE = (640, 480)
FPS = 30.0
# Grey levels of Gaussian noise on a clip drawn on twos, unless asked otherwise: a held frame is
# then alike but not identical to the one before, as a scan or a video makes it.
TWOS_NOISE = 1.5
# An error of at most this many pixels counts as found (PCK), of more than LOST_PX as lost.
PCK_PX = 5.0
LOST_PX = 20.0
# A first frame is a T-pose the motion jumps away from when its jump is this many times the
# median jump between frames.
_TPOSE_JUMP = 5.0


@dataclass(frozen=True, eq=False)
class RenderedClip:
    """A motion-capture clip rendered as a textured figure, with its true joints.

    Attributes
    ----------
    images : (T, h, w, 3) uint8
        The frames, RGB.
    truth : (T, 16, 2) float
        True joint centres, pixels, in ``skeleton.names`` order.
    skeleton : Skeleton
        The 16 standard joints (``hips`` the root), placed at frame 0's true joints.
    side : float
        Side of a joint's square tracking rectangle: the joint disc's diameter, pixels.
    fps : float
        Frames per second after resampling.
    style : str
        ``"textured"`` or ``"flat"`` (:func:`~toonmotion.capture.synthetic.limb_figure_frames`).
    twos : bool
        Each drawing is held two frames (animation "on twos").
    noise : float
        The standard deviation of the Gaussian noise on every frame, grey levels.
    """

    images: NDArray[np.uint8]
    truth: NDArray[np.float64]
    skeleton: Skeleton
    side: float
    fps: float
    style: str = "textured"
    twos: bool = False
    noise: float = 0.0


def render_bvh_clip(path: str | Path, *, frames: int | None = None, fps: float = FPS,
                    size: tuple[int, int] = SIZE, seed: int = 0, style: str = "textured",
                    twos: bool = False, noise: float | None = None) -> RenderedClip:
    """Read a BVH file and render it with :func:`render_mocap`."""
    return render_mocap(load_bvh(path), frames=frames, fps=fps, size=size, seed=seed, style=style,
                        twos=twos, noise=noise)


def render_mocap(clip: BvhClip, *, frames: int | None = None, fps: float = FPS,
                 size: tuple[int, int] = SIZE, seed: int = 0, style: str = "textured",
                 twos: bool = False, noise: float | None = None) -> RenderedClip:
    """Render a motion-capture clip as a limb figure seen from the front.

    Parameters
    ----------
    clip : BvhClip
        Its joint names must follow a convention :func:`~toonmotion.capture.mocap.pick_joints`
        reads.
    frames : int, optional
        Keep only the first ``frames`` frames after resampling.
    fps : float
        Target frame rate: every ``round(clip.fps / fps)``-th frame is kept (at least every one).
    size : (width, height)
        The frame, pixels; the whole clip is fitted inside it with a 10% margin.
    seed : int
        Seed of the figure's and background's textures (or colours).
    style : {"textured", "flat"}
        A textured figure over a textured background, or a flat-coloured outlined one over a
        plain background (a cel cartoon).
    twos : bool
        Hold each drawing two frames, as animation "on twos": frame ``t`` shows (and its truth is)
        the pose of frame ``t - t % 2``.
    noise : float, optional
        Gaussian noise added to every frame, its standard deviation in grey levels (rounded to
        whole levels, clipped to 0-255; drawn from ``seed``). Default: :data:`TWOS_NOISE` on twos,
        so held frames are alike but not identical, as a scan or a video makes them; else none.

    Returns
    -------
    RenderedClip
    """
    X = forward_kinematics(clip)
    jumps = np.linalg.norm(np.diff(X, axis=0), axis=2).max(axis=1)
    if len(jumps) > 2 and jumps[0] > _TPOSE_JUMP * np.median(jumps):
        X = X[1:]
    step = max(1, round(clip.fps / fps))
    X = X[::step][:frames]
    picks = pick_joints(clip.names, clip.parents)
    X = X[:, [picks[n] for n in STANDARD_JOINTS]]
    points, depth = project_orthographic(X, with_depth=True)
    truth = fit_to_frame(points, size)
    if twos:
        held = np.arange(len(truth)) // 2 * 2
        truth, depth = truth[held], depth[held]
    parents_by_name = standard_skeleton_parents()
    parents = np.array([-1 if parents_by_name[n] is None else STANDARD_JOINTS.index(parents_by_name[n])
                        for n in STANDARD_JOINTS])
    images, radius = limb_figure_frames(truth, parents, depth=depth, size=size, seed=seed, style=style)
    noise = (TWOS_NOISE if twos else 0.0) if noise is None else float(noise)
    if noise < 0 or not np.isfinite(noise):
        raise ValueError(f"noise must be a finite number of grey levels >= 0, not {noise}")
    if noise > 0:
        grain = np.random.default_rng(seed + 1).normal(0.0, noise, images.shape)
        images = np.clip(np.rint(images + grain), 0, 255).astype(np.uint8)
    skeleton = Skeleton.from_joints(
        [(n, parents_by_name[n], tuple(truth[0, i])) for i, n in enumerate(STANDARD_JOINTS)]
    )
    order = [STANDARD_JOINTS.index(n) for n in skeleton.names]
    return RenderedClip(images=images, truth=truth[:, order], skeleton=skeleton, side=2 * radius,
                        fps=clip.fps / step, style=style, twos=twos, noise=noise)


def track_from_truth(rendered: RenderedClip, *, settings: TrackSettings | None = None, figure: bool = True,
                     restart: int | None = None) -> tuple[NDArray[np.float64], float]:
    """Track every joint of a rendered clip with toonmotion's tracker from the true frame-0 rectangles.

    With ``figure`` the tracker holds joints to the figure's masks where the figure is drawn on
    a flat colour, as ``toonmotion track`` does
    (:func:`~toonmotion.capture.foreground.flat_figure_masks`, with the settings' ``cutout``); the
    time includes making them.

    With ``restart``, tracking starts again from the true centres every ``restart`` frames
    (frames 0, ``restart``, ``2 restart``, ...), each stretch tracked on its own as if it were
    the whole clip: a joint lost in one stretch cannot carry its loss into the next. Scored
    with the same ``restart`` (:func:`tracking_scores`), the restart frames are left out.

    Returns
    -------
    positions : (T, 16, 2) float
        Tracked joint centres, pixels, in ``rendered.skeleton.names`` order.
    seconds : float
        Wall-clock time of the tracking alone.
    """
    count = len(rendered.images)
    step = _restart_step(restart, count)
    sizes = np.full((len(rendered.skeleton), 2), rendered.side)
    setup = TrackSetup(skeleton=rendered.skeleton, sizes=sizes)
    start = time.perf_counter()
    cutout = None if settings is None else settings.cutout
    masks = flat_figure_masks(rendered.images, tuning=cutout) if figure else None
    positions = np.empty_like(rendered.truth)
    for begin in range(0, count, step):
        stop = min(count, begin + step)
        if stop - begin < 2:  # a last stretch of one frame is its own start
            positions[begin] = rendered.truth[begin]
            continue
        result = track(rendered.images, setup, settings=settings, masks=masks, start=begin, stop=stop,
                       initial=rendered.truth[begin])
        positions[begin:stop] = result.positions[begin:stop]
    return positions, time.perf_counter() - start


def _restart_step(restart: int | None, count: int) -> int:
    """The frames between restarts: ``restart``, or the whole clip for None."""
    if restart is None:
        return max(count, 1)
    if isinstance(restart, bool) or not isinstance(restart, int) or restart < 2:
        raise ValueError(f"restart must be a whole number of frames >= 2 or None, not {restart!r}")
    return restart


def tracking_errors(found: NDArray[np.float64], truth: NDArray[np.float64], *, restart: int | None = None
                    ) -> NDArray[np.float64]:
    """Distance of every tracked joint from its true centre, over every frame tracking did not
    start from.

    Parameters
    ----------
    found, truth : (T, J, 2) float
        Pixels.
    restart : int, optional
        Tracking started again from the truth every ``restart`` frames
        (:func:`track_from_truth`).

    Returns
    -------
    (n * J,) float
        Pixels, frame by frame. Frame 0 is where tracking starts, so it is left out, as is every
        ``restart``-th frame.

    >>> found = np.zeros((5, 1, 2)); truth = found + np.arange(5.0)[:, None, None]
    >>> tracking_errors(found, truth, restart=2).round(3).tolist()  # frames 1 and 3
    [1.414, 4.243]
    """
    found, truth = np.asarray(found, dtype=float), np.asarray(truth, dtype=float)
    if found.shape != truth.shape or found.ndim != 3 or found.shape[2] != 2:
        raise ValueError(f"found and truth must both be (frames, joints, 2), got {found.shape} and "
                         f"{truth.shape}")
    scored = np.arange(len(found)) % _restart_step(restart, len(found)) != 0
    return np.hypot(*(found[scored] - truth[scored]).reshape(-1, 2).T)


def tracking_scores(found: NDArray[np.float64], truth: NDArray[np.float64], *, restart: int | None = None
                    ) -> dict[str, float]:
    """The benchmark's figures for tracked joints against the true ones (frame 0 left out, and
    with ``restart`` every frame tracking started again from, as :func:`tracking_errors`).

    Returns
    -------
    dict
        ``mean_px`` and ``median_px``, the error in pixels (rounded to 0.001); ``pck5``, the
        fraction of joint-frames within :data:`PCK_PX`, and ``lost``, more than :data:`LOST_PX`
        off (rounded to 0.0001).
    """
    error = tracking_errors(found, truth, restart=restart)
    return {
        "mean_px": round(float(error.mean()), 3),
        "median_px": round(float(np.median(error)), 3),
        "pck5": round(float((error <= PCK_PX).mean()), 4),
        "lost": round(float((error > LOST_PX).mean()), 4),
    }
