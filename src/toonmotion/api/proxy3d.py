"""3D proxies for hand-drawn characters (Jain et al. 2012): the calls behind ``lift``,
``proxy-preview`` and ``project-mocap`` (docs/proxy3d.md)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.animation import Animation
from toonmotion.animate.motion import Motion
from toonmotion.api.animation import motion_in_frames
from toonmotion.capture.bvh_kinematics import BvhClip
from toonmotion.capture.mocap import find_joints, fit_to_frame
from toonmotion.errors import MotionError, ProxyError
from toonmotion.geometry.arrays import frame_rate
from toonmotion.io.frames import lay_on
from toonmotion.progress import Progress
from toonmotion.proxy3d.camera_fit import CameraWeights
from toonmotion.proxy3d.lift import LiftReport, lift
from toonmotion.proxy3d.markers import Markers, markers_from_motion
from toonmotion.proxy3d.orthographic import camera, limb_angle
from toonmotion.proxy3d.prior import prior_from_bvh, resample_prior
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton import SkeletonWeights
from toonmotion.render.proxy_preview import preview_frames
from toonmotion.render.sequence import render_animation
from toonmotion.rig.character import Character
from toonmotion.rig.skeleton import Skeleton


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
    up: float | None = 0.0,
    hold_elevation: bool = False,
    ground: str = "prior",
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
    focal, size, frames, widths, units, camera_weights, still_camera, up, hold_elevation, ground
        As :func:`toonmotion.proxy3d.lift.lift` (``up``: the world's up in the picture, degrees
        clockwise; 0 a level picture, None the camera's roll fitted; ``hold_elevation``: the
        camera keeps the view's elevation, for a figure unlike its prior; ``ground``: "prior",
        the clip's floor, or "feet", the markers' lowest path).
    skeleton_weights : SkeletonWeights, optional
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
                         still_camera=still_camera, up=up, hold_elevation=hold_elevation, ground=ground,
                         skeleton_weights=skeleton_weights, progress=progress)
    return proxy, replace(report, left_out=left_out)



def lift_animation(character: Character, animation: Animation, prior: BvhClip, *,
                   size: tuple[int, int] | None = None, **options: Any) -> tuple[Proxy, LiftReport]:
    """Lift a rigged character's animation into a 3D proxy: its joints in its frames are the markers,
    and its frames, on white, give the collision volumes.

    What ``animate --save-frame-motion`` and ``animate -o FRAMES`` write, then ``lift --frames``
    reads, in one call (``lift --project --keys`` and the editor's 3D panel); ``scene --project``
    then composites into the same frames (:func:`toonmotion.api.animation_frames`).

    Parameters
    ----------
    character : Character
    animation : Animation
        From :func:`toonmotion.api.animate_character`.
    prior : BvhClip
        The motion prior.
    size : (int, int), optional
        The frames' ``(width, height)``, as :func:`toonmotion.api.motion_in_frames`'s.
    **options
        :func:`lift_proxy`'s keywords (``view``, ``ground``, ``hold_elevation``, ``up``, ...), but
        ``frames`` and ``size``, which the animation gives.

    Returns
    -------
    proxy : Proxy
    report : LiftReport

    Examples
    --------
    See :func:`lift_proxy`, whose example lifts markers with a clip built in place; a rigged
    character's animation needs a clip with its joints (``tests/proxy3d/test_lift_animation.py``
    lifts the bundled character with a CMU jump, and checks the result is :func:`lift_proxy`'s on
    the same motion and frames).
    """
    for given in ("frames", "markers"):
        if given in options:
            raise ProxyError(f"an animation gives its own {given}; lift them with lift_proxy instead")
    motion = motion_in_frames(character, animation, size=size)
    frames = lay_on(np.stack(list(render_animation(character, animation, size=size))))
    height, width = frames.shape[1:3]
    return lift_proxy(motion, prior, frames=frames, size=(width, height), **options)

# Beyond these, a lift's result deserves a second look (lift_warnings).
POOR_MATCH_DEG = 12.0  # limbs this far apart on average between the drawing and its aligned prior
CAMERA_FIT_SHARE = 0.1  # the camera fit's mean residual, as a share of the figure's size
ROLL_DEG = 20.0  # a fitted camera roll (up=None) beyond this tilts the world visibly
TILT_DEG = 20.0  # a camera tilted this far from the view's elevation leans the world's vertical


# What lift_warnings asks the user to give, in the command line's words (the editor has its own).
LIFT_REMEDIES = {"view": "give --view AZ,EL", "hold": "give --hold-elevation (with --view AZ,EL)",
                 "level": "give --up 0"}


def lift_warnings(proxy: Proxy, report: LiftReport, *,
                  remedies: Mapping[str, str] | None = None) -> list[str]:
    """One-line warnings about a lift that deserves a second look, each saying what to give.

    - the prior moves unlike the drawing (its limbs :data:`POOR_MATCH_DEG` apart on average once
      aligned): a view searched with such a prior was more than 10 degrees off in about half of
      ``benchmarks/view_search.py``'s cases with another clip as the prior;
    - no camera explains the drawing well (a mean residual over :data:`CAMERA_FIT_SHARE` of the
      figure's size): proportions or a posture unlike the prior's;
    - a fitted roll (``up=None``) beyond :data:`ROLL_DEG`: the world tilts with it;
    - a camera tilted beyond :data:`TILT_DEG` from the view's elevation: the world's vertical leans.

    Parameters
    ----------
    proxy : Proxy
    report : LiftReport
        What :func:`lift_proxy` returned.
    remedies : dict, optional
        How each remedy is asked for, by key (``view``, ``hold``, ``level``), in place of
        :data:`LIFT_REMEDIES`' command-line words (the editor asks for its gizmo).

    Returns
    -------
    list of str
        One line each, none when the lift looks sound.

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> from types import SimpleNamespace
    >>> report = SimpleNamespace(view_found=True, view_cost=0.1, azimuth=30.0, elevation=10.0,
    ...                          camera_px=2.0, figure_px=200.0, up=0.0)
    >>> proxy = SimpleNamespace(camera=PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5]]))
    >>> lift_warnings(proxy, report)  # doctest: +ELLIPSIS
    ['the prior moves unlike the drawing (limbs 18° apart on average once aligned): the view ...']
    """
    ask = {**LIFT_REMEDIES, **(remedies or {})}
    said = []
    angle = limb_angle(report.view_cost)
    if report.view_found and angle > POOR_MATCH_DEG:
        said.append(f"the prior moves unlike the drawing (limbs {angle:.0f}° apart on average once "
                    f"aligned): the view searched, {report.azimuth:.0f},{report.elevation:.0f}, may be off; "
                    f"check the preview, or {ask['view']} or a prior that moves more like it")
    if report.camera_px > CAMERA_FIT_SHARE * report.figure_px:
        said.append(f"no camera sees the prior as drawn: the fit leaves {report.camera_px:.0f} px on a "
                    f"figure {report.figure_px:.0f} px across (proportions or a posture unlike the prior's); "
                    "the points stay on the drawing, the skeleton and volumes follow the prior")
    tilt = float(np.degrees(np.abs(proxy.camera.extrinsics[:, 1] - np.radians(report.elevation))).max())
    if tilt > TILT_DEG:
        said.append(f"the camera tilts up to {tilt:.0f}° from the view's elevation to fit the prior, so the "
                    f"world's vertical leans in the picture; {ask['hold']} to keep it level")
    roll = float(np.degrees(np.abs(proxy.camera.extrinsics[:, 2])).max())
    if report.up is None and roll > ROLL_DEG:
        said.append(f"the camera rolls up to {roll:.0f}° to fit the prior, tilting the world; {ask['level']} "
                    "to keep it level")
    return said


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


def project_mocap(
    clip: BvhClip,
    *,
    view: tuple[float, float],
    joint_map: Mapping[str, str] | None = None,
    segment: tuple[int, int | None] = (0, None),
    fps: float | None = None,
    size: tuple[int, int] = (640, 480),
    margin: float = 0.1,
) -> Motion:
    """A motion-capture clip seen from a view, as a drawn 2D motion (for ``retarget``).

    The clip's joints are seen through the orthographic camera of ``view``
    (:func:`toonmotion.proxy3d.orthographic.camera`, the same angles as ``lift --view``, after
    the clip is turned +Y up as :func:`~toonmotion.proxy3d.prior.prior_from_bvh` does), and the
    whole clip is fitted into the picture with one scale and one offset
    (:func:`toonmotion.capture.mocap.fit_to_frame`), so the motion itself is unchanged.

    The motion's joints are the clip's standard joints under their standard names (``hips``,
    ``spine``, ``left_elbow``, ..., :func:`toonmotion.capture.mocap.find_joints`, as far as the
    clip has them) and the joints ``joint_map`` names. A mapped joint carries the map's name
    instead of its standard one, so a drawing's own joints (a pig's ``front_left_foot`` from
    ``LeftHand``) can be named after it. Each joint's parent is its nearest ancestor in the clip
    that is also a joint of the motion.

    Parameters
    ----------
    clip : BvhClip
        From :func:`toonmotion.io.bvh.load_bvh`; 3D right-handed, its own units and up axis.
    view : (azimuth, elevation)
        Degrees: azimuth about +Y from +Z towards +X (0: the front of a figure facing +Z, 90: its
        left side), elevation above the horizontal, in [-90, 90].
    joint_map : dict, optional
        The motion's joint name -> the clip's joint name.
    segment : (start, stop)
        The clip's frames to use, as a slice (CMU clips open with a T-pose frame: ``(1, None)``
        leaves it out).
    fps : float, optional
        The motion's frame rate (positions interpolated linearly); default the clip's.
    size : (width, height)
        The picture the whole motion is fitted into, pixels.
    margin : float
        Space kept clear on each side, a fraction of the width and the height.

    Returns
    -------
    Motion
        ``(T, J, 2)`` pixels, x right and y down; its skeleton's rest pose is the first frame.

    Raises
    ------
    ProxyError
        The map names a joint the clip lacks (with the closest name, if any) or one joint twice,
        the clip has no joint to show, the segment is empty, an angle or the fps is out of range.

    Examples
    --------
    An arm hanging down, then raised towards the front (+Z), seen from the front and from its side:

    >>> clip = BvhClip(names=("Hips", "LeftArm", "LeftHand", "LeftHand_end"),
    ...                parents=np.array([-1, 0, 1, 2]),
    ...                offsets=np.array([[0.0, 0, 0], [10, 0, 0], [0, -20, 0], [0, -5, 0]]),
    ...                channels=(("Xposition", "Yposition", "Zposition"), ("Xrotation",), (), ()),
    ...                motion=np.array([[0.0, 90, 0, 0], [0, 90, 0, -90]]), frame_time=1 / 30)
    >>> front = project_mocap(clip, view=(0, 0), joint_map={"base": "Hips"}, size=(100, 100), margin=0)
    >>> front.skeleton.names, front.skeleton.parents.tolist()
    (('base', 'left_shoulder', 'left_hand'), [-1, 0, 1])
    >>> front.positions[1].round(6).tolist()  # the raised arm points at the camera
    [[25.0, 0.0], [75.0, 0.0], [75.0, 0.0]]
    >>> side = project_mocap(clip, view=(90, 0), joint_map={"base": "Hips"}, size=(100, 100), margin=0)
    >>> side.positions[:, 2].round(6).tolist()  # seen from +X, the front (+Z) is the picture's left
    [[100.0, 100.0], [0.0, 0.0]]
    """
    try:
        azimuth, elevation = view
    except (TypeError, ValueError):
        raise ProxyError(f"the view is two angles in degrees (azimuth, elevation), got {view!r}") from None
    R = camera(azimuth, elevation)
    names, mapping = _mocap_joints(clip, dict(joint_map or {}))
    start, stop = segment
    if not range(clip.frame_count)[start:stop]:
        raise ProxyError(f"the segment {start}:{'' if stop is None else stop} holds none of the clip's "
                         f"{clip.frame_count} frames")
    seen = prior_from_bvh(clip, names, joint_map=mapping, start=start, stop=stop)
    if fps is not None:
        seen = resample_prior(seen, frame_rate(fps, name="the motion's fps", error=ProxyError))
    points = fit_to_frame(seen.positions @ R.T, size, margin=margin)
    skeleton = Skeleton.from_joints(
        (n, None if p < 0 else names[p], points[0, j])
        for j, (n, p) in enumerate(zip(names, seen.parents, strict=True))
    )
    order = [names.index(n) for n in skeleton.names]
    return Motion(skeleton=skeleton, positions=points[:, order], fps=seen.fps)


def _mocap_joints(clip, joint_map):
    """The motion's joint names, in the clip's order, and each one's clip joint: the standard
    joints found, those the map names taking the map's names instead."""
    picks = _roles(clip.names, clip.parents)
    joints = list(joint_map.values())
    twice = next((j for j in joints if joints.count(j) > 1), None)
    if twice is not None:
        both = [n for n, j in joint_map.items() if j == twice]
        raise ProxyError(f"the joint map names the clip's joint {twice!r} for both {both[0]!r} and "
                         f"{both[1]!r}; map each name to its own joint")
    mapping = {role: clip.names[j] for role, j in picks.items()
               if role not in joint_map and clip.names[j] not in joint_map.values()}
    mapping.update(joint_map)
    if not mapping:
        raise ProxyError("none of the clip's joints has a standard name (hips, left_elbow, ...); name the "
                         "joints to show with a joint map (--map NAME=JOINT)")
    where = {j: i for i, j in enumerate(clip.names)}
    names = sorted(mapping, key=lambda n: where.get(mapping[n], len(where)))
    return names, mapping
