"""3D proxies for hand-drawn characters (Jain et al. 2012): the calls behind ``lift`` and
``proxy-preview`` (docs/proxy3d.md)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.motion import Motion
from toonmotion.capture.bvh_kinematics import BvhClip
from toonmotion.capture.mocap import find_joints
from toonmotion.errors import MotionError
from toonmotion.progress import Progress
from toonmotion.proxy3d.camera_fit import CameraWeights
from toonmotion.proxy3d.lift import LiftReport, lift
from toonmotion.proxy3d.markers import Markers, markers_from_motion
from toonmotion.proxy3d.prior import prior_from_bvh
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton import SkeletonWeights
from toonmotion.render.proxy_preview import preview_frames


def lift_proxy(
    markers: Markers | Motion,
    prior: BvhClip,
    *,
    joint_map: Mapping[str, str] | None = None,
    segment: tuple[int, int | None] = (0, None),
    view: tuple[float, float] | None = None,
    focal: float | None = None,
    size: tuple[int, int] | None = None,
    frames: ArrayLike | None = None,
    widths: Mapping[tuple[int, str], tuple[float, float]] | None = None,
    units: float | str | None = None,
    extra: Sequence[BvhClip] = (),
    camera_weights: CameraWeights | None = None,
    still_camera: bool = False,
    skeleton_weights: SkeletonWeights | None = None,
    progress: Progress | None = None,
) -> tuple[Proxy, LiftReport]:
    """Lift drawn markers into a 3D proxy, with a motion-capture clip as the prior.

    The clip's joints are matched to the markers by name (standard joint names through the CMU,
    FAIR, Mixamo and Rokoko conventions, or the clip's own) or by ``joint_map``; then
    :func:`toonmotion.proxy3d.lift.lift` aligns it in time, finds the view (unless given), the
    camera per frame, the point trajectories, the collision volumes (with ``frames``) and the
    skeleton.

    Parameters
    ----------
    markers : Markers or Motion
        Named 2D markers per drawn frame (:func:`toonmotion.io.markers_json.load_markers`), or a
        motion (from tracking, an animation or a motion file), whose joints become the markers:
        a joint whose role in its skeleton is a standard one (hips, spine, left elbow, ...,
        :func:`toonmotion.capture.mocap.find_joints`) is matched to the clip's joint of that role
        whatever either is called; a joint with neither a role nor a namesake in the clip (a
        root on the hips, a hat) is left out and listed in ``report.left_out``.
    prior : BvhClip
        The motion prior (:func:`toonmotion.io.bvh.load_bvh`).
    joint_map : dict, optional
        Marker name -> the clip's joint name, for markers named otherwise.
    segment : (start, stop)
        The clip's frames to use, as a slice.
    view : (azimuth, elevation), optional
        Degrees; searched when not given.
    focal, size, frames, widths, units, camera_weights, still_camera, skeleton_weights
        As :func:`toonmotion.proxy3d.lift.lift`.
    extra : sequence of BvhClip
        Further clips for the skeleton's PCA subspace, matched the same way.
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    proxy : Proxy
        3D right-handed, +Y up, metres; its camera maps it to drawing pixels (y down).
    report : LiftReport

    Raises
    ------
    ProxyError
        Markers the clip lacks, a clip too short (or long) to align, frames that do not fit, a
        camera that cannot see the markers.

    Examples
    --------
    A figure drawn from the front, lifted with itself as the prior:

    >>> clip = BvhClip(names=("hips", "neck", "hand", "hand_end"), parents=np.array([-1, 0, 1, 2]),
    ...                offsets=np.array([[0.0, 90, 0], [0, 50, 0], [20, 0, 0], [25, 0, 0]]),
    ...                channels=(("Xposition", "Yposition", "Zposition", "Zrotation"), (),
    ...                          ("Zrotation",), ()),
    ...                motion=np.array([[0.0, 90, 0, 0, 10 * i] for i in range(12)]), frame_time=1 / 12)
    >>> from toonmotion.proxy3d.prior import prior_in_metres
    >>> names = ("hips", "neck", "hand", "hand_end")
    >>> truth = prior_in_metres(prior_from_bvh(clip, names), "cm")[0].positions
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> cam = PerspectiveCamera(800.0, 640, 480, [[0, 0, 0, 0, 1, 4]] * 12)
    >>> drawn = Markers(names, cam.project(truth), fps=12)
    >>> proxy, report = lift_proxy(drawn, clip, view=(0, 0), focal=800.0, size=(640, 480), units="cm")
    >>> float(np.abs(proxy.points - truth).max()) < 1e-6, report.reproj_px < 1e-6
    (True, True)
    """
    start, stop = segment
    left_out: tuple[str, ...] = ()
    if isinstance(markers, Motion):
        drawn, joint_map, left_out = _motion_markers(markers, prior, joint_map)
    else:
        drawn = markers
    matched = prior_from_bvh(prior, drawn.names, joint_map=joint_map, start=start, stop=stop)
    others = [prior_from_bvh(c, drawn.names, joint_map=joint_map) for c in extra]
    proxy, report = lift(drawn, matched, view=view, focal=focal, size=size, frames=frames, widths=widths,
                         units=units, extra=others, camera_weights=camera_weights,
                         still_camera=still_camera,
                         skeleton_weights=skeleton_weights, progress=progress)
    return proxy, replace(report, left_out=left_out)


def _motion_markers(motion, clip, joint_map):
    """A motion's joints as markers, matched to the clip by role; ``(markers, map, left out)``."""
    skeleton = motion.skeleton
    roles = _roles(skeleton.names, skeleton.parents)
    clip_roles = _roles(clip.names, clip.parents)
    mapping = {skeleton.names[j]: clip.names[clip_roles[role]]
               for role, j in roles.items() if role in clip_roles}
    mapping.update(joint_map or {})
    keep = [n for n in skeleton.names if n in mapping or n in clip.names]
    left_out = tuple(n for n in skeleton.names if n not in keep)
    return markers_from_motion(motion).select(keep), mapping, left_out


def _roles(names, parents):
    """Standard role -> joint index, for the roles found (a figure without a head has no head)."""
    try:
        return {role: j for role, j in find_joints(names, parents).items() if j is not None}
    except MotionError:
        return {}


def preview_proxy(proxy: Proxy, frames: ArrayLike | None = None) -> list[NDArray[np.uint8]]:
    """Pictures of a proxy per frame: seen from its camera over the drawing, beside a side view.

    Parameters
    ----------
    proxy : Proxy
    frames : (T, H, W, 3) uint8, optional
        The drawn frames; white canvases of the camera's size without them.

    Returns
    -------
    list of (H, W + H, 3) uint8
        RGB pictures (:func:`toonmotion.render.proxy_preview.preview_frames`).

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> cam = PerspectiveCamera(200.0, 80, 60, [[0, 0, 0, 0, 1, 5]] * 2)
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 1.5, 0]]] * 2)
    >>> proxy = Proxy(("a", "b"), [-1, 0], 12, cam, pts, None, pts, [[0.0, 0.5, 0]], [[[0.0, 0, 0, 1]]] * 2)
    >>> [p.shape for p in preview_proxy(proxy)]
    [(60, 140, 3), (60, 140, 3)]
    """
    return preview_frames(proxy, frames)
