"""Lifting a drawn animation into 3D, end to end (sections 3.1-3.4).

markers + prior (metres, ground at Y = 0) -> time alignment (DTW, 3.1.2) -> orthographic view
(given, or searched: 3.1.3) -> perspective camera per frame (3.3) -> single-point proxies
(3.4.1) -> collision volumes, when drawn frames are given (3.4.2) -> skeleton (3.4.3) ->
:class:`~toonmotion.proxy3d.proxy.Proxy`.

Without a view, the timing and the view depend on each other (DTW compares poses seen through a
camera; the view search compares aligned poses): we align through the front view, search the
view, align again through it and search once more.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import AmbiguousViewError, ProxyError
from toonmotion.progress import Progress
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.camera_fit import CameraWeights, estimate_camera
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import ViewFit, find_view, limb_angle, view_cost
from toonmotion.proxy3d.orthographic import camera as orthographic_camera
from toonmotion.proxy3d.points import point_proxies
from toonmotion.proxy3d.prior import Prior, prior_in_metres
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton import SkeletonWeights, skeleton_proxy
from toonmotion.proxy3d.timewarp import align_prior, warp_prior
from toonmotion.proxy3d.volumes import collision_radii, drawn_widths

# The default image, when neither frames nor a size are given: the markers' extent from the
# origin, plus this fraction.
MARGIN = 0.05
# The quantile, over the frames, of the figure's lowest reach taken as the ground (ground="feet"):
# low enough that a jump's frames in the air do not lift it, above a single stray frame.
GROUND_SHIFT_SHARE = 0.1


@dataclass(frozen=True, eq=False)
class LiftReport:
    """What lifting found and how long it took.

    Attributes
    ----------
    azimuth, elevation : float
        The orthographic view, degrees; ``view_found`` says whether it was searched.
    view_cost : float
        :func:`~toonmotion.proxy3d.orthographic.view_cost` of the view (0 perfect, 4 reversed).
    twin : tuple of float or None
        The searched view's mirror twin ``(azimuth, elevation, cost)``.
    second : tuple of float or None
        The searched view's best rival in another basin of the cost ``(azimuth, elevation,
        cost)`` (:attr:`~toonmotion.proxy3d.orthographic.ViewFit.second`); within
        :data:`~toonmotion.proxy3d.orthographic.AMBIGUOUS` of the view's cost, lifting asks
        for the view instead (:class:`~toonmotion.errors.AmbiguousViewError`).
    units : float
        Metres per unit of the prior.
    prior_frames : (T,) float
        The prior frame (at the drawing's rate) shown at each drawn frame.
    alignment_cost : float
        The DTW path's cost.
    camera_px : float
        Mean distance, pixels, between the drawn markers and the prior's seen through the
        estimated camera (what eq. 2 leaves).
    reproj_px : float
        Largest distance between a point proxy's projection and its drawn marker.
    capped : (T, K) bool or None
        Limb widths whose walk found no boundary (an override may be wanted).
    warped : Prior
        The time-aligned prior in metres.
    times_ms : dict
        Milliseconds per stage: align, camera, points, volumes, skeleton.
    up : float or None
        The picture's up as given (``lift``'s ``up``; None: the camera's roll was fitted).
    figure_px : float
        The drawn figure's size: the median over frames of its markers' bounding-box diagonal.
    left_out : tuple of str
        A motion's joints that were not lifted (no joint of the prior matches them).
    ground_shift : float
        Metres the proxy was raised to stand on its markers' lowest path (``ground="feet"``; 0
        on the prior's floor).
    """

    azimuth: float
    elevation: float
    view_found: bool
    view_cost: float
    twin: tuple[float, float, float] | None
    second: tuple[float, float, float] | None
    units: float
    prior_frames: NDArray[np.float64]
    alignment_cost: float
    camera_px: float
    reproj_px: float
    capped: NDArray[np.bool_] | None
    warped: Prior
    times_ms: dict[str, float] = field(default_factory=dict)
    figure_px: float = 0.0
    up: float | None = 0.0
    left_out: tuple[str, ...] = ()
    ground_shift: float = 0.0


def lift(
    markers: Markers,
    prior: Prior,
    *,
    view: tuple[float, float] | None = None,
    focal: float | None = None,
    size: tuple[int, int] | None = None,
    frames: ArrayLike | None = None,
    widths: Mapping[tuple[int, str], tuple[float, float]] | None = None,
    units: float | str | None = None,
    band: float = 0.1,
    relative: bool = False,
    upper: Sequence[str] | None = None,
    extra: Sequence[Prior] = (),
    camera_weights: CameraWeights | None = None,
    still_camera: bool = False,
    up: float | None = 0.0,
    hold_elevation: bool = False,
    ground: str = "prior",
    skeleton_weights: SkeletonWeights | None = None,
    smooth: float = 1.0,
    progress: Progress | None = None,
) -> tuple[Proxy, LiftReport]:
    """Lift drawn markers into a 3D proxy with a motion-capture prior.

    Parameters
    ----------
    markers : Markers
        The drawn markers, pixels (x right, y down).
    prior : Prior
        Matched to the markers (:func:`~toonmotion.proxy3d.prior.prior_from_bvh`), in its own
        units and frame rate.
    view : (azimuth, elevation), optional
        The orthographic view in degrees (3.1.3); searched when not given.
    focal : float, optional
        Focal length in pixels; default the image's diagonal (a 53-degree diagonal field of
        view, a "normal" lens).
    size : (width, height), optional
        The image size in pixels; default the frames' size, else the markers' extent from the
        origin plus 5 %.
    frames : (T, H, W, 3) uint8, optional
        The drawn frames, for the limbs' widths (collision volumes); without them the proxy has
        no volumes.
    widths : dict, optional
        Width overrides ``(frame, marker) -> (w1, w2)`` pixels
        (:func:`~toonmotion.proxy3d.volumes.drawn_widths`).
    units : float or str, optional
        Metres per prior unit (:func:`~toonmotion.proxy3d.prior.prior_in_metres`).
    band : float
        The DTW band (:func:`~toonmotion.proxy3d.timewarp.dtw`).
    relative : bool
        Relative pose descriptors for the alignment.
    upper : sequence of str, optional
        Upper-body markers, when the skeleton's structure does not tell them.
    extra : sequence of Prior
        Other clips for the skeleton's PCA subspace (same names; their own units are guessed).
    still_camera : bool
        One camera for the whole shot (:func:`~toonmotion.proxy3d.camera_fit.estimate_camera`'s
        ``still``), for drawings made without camera moves.
    up : float or None
        Where the world's up points in the picture, degrees clockwise from the picture's up: 0,
        the default, for a level picture (the camera does not roll, so the proxy, a scene's
        gravity and the exports stand as the drawing does); None fits the camera's roll per frame
        as the paper does, which lets a prior whose posture differs from the drawn figure's (a
        human prior for a four-legged character) tilt the world to match.
    hold_elevation : bool
        The camera keeps the view's elevation (it pans but does not tilt;
        :func:`~toonmotion.proxy3d.camera_fit.estimate_camera`'s ``hold_elevation``): with ``up``
        held, the world's vertical is the picture's everywhere. For a figure unlike its prior (a
        four-legged character lifted with a human clip), whose fitted camera tilts to make the
        prior look like it.
    ground : {"prior", "feet"}
        Where the ground (Y = 0) is: the prior clip's floor, or the drawing's own, the lowest path
        of its markers (:func:`lowest_path`): for a figure unlike its prior, whose markers the
        prior's floor leaves in the air. The whole proxy and its camera move together, so every
        picture stays as it was.
    camera_weights, skeleton_weights : optional
        Eq. 2's and eq. 16's weights.
    smooth : float
        Eq. 5's weight against eq. 4's (:func:`~toonmotion.proxy3d.points.point_proxies`).
    progress : callable, optional
        ``progress(stage, done, total)``.

    Returns
    -------
    proxy : Proxy
    report : LiftReport

    Raises
    ------
    ProxyError
        Markers and prior that do not match, a prior too short to align, frames that do not fit
        the markers, a camera that cannot see them.
    """
    if ground not in ("prior", "feet"):
        raise ProxyError(f"the ground is 'prior' (the clip's floor) or 'feet' (the markers' lowest path), "
                         f"got {ground!r}")
    times: dict[str, float] = {}
    clock = time.perf_counter()
    in_metres, unit = prior_in_metres(prior, units)
    image_frames = None if frames is None else np.asarray(frames)
    if image_frames is not None and (image_frames.ndim != 4 or len(image_frames) != markers.frame_count):
        raise ProxyError(f"the drawn frames must be one image per marker frame ({markers.frame_count}), got "
                         f"{'shape ' + str(image_frames.shape)}")
    if image_frames is not None:
        _markers_on_frames(markers, image_frames.shape[2], image_frames.shape[1])
    width, height = _image_size(markers, size, image_frames)
    f = float(np.hypot(width, height)) if focal is None else float(focal)
    if not (np.isfinite(f) and f > 0):
        raise ProxyError(f"the focal length must be a positive number of pixels, got {focal!r}")

    level = markers if not up else _turned(markers, -float(up))  # the picture with the world's up up
    found = view is None
    twin = second = None
    if view is None:
        fit = search_view(level, in_metres, band=band, relative=relative)
        azimuth, elevation, twin, second = fit.azimuth, fit.elevation, fit.twin, fit.second
        if fit.ambiguous and second is not None:
            raise AmbiguousViewError(
                f"two views explain the drawing about equally: {_angles(fit.azimuth, fit.elevation)} "
                f"(limbs {fit.mean_angle:.0f}° off on average) and {_angles(*second[:2])} "
                f"({limb_angle(second[2]):.0f}° off); give the one it was drawn from (--view AZ,EL)",
                views=((fit.azimuth, fit.elevation, fit.cost), second))
    else:
        azimuth, elevation = (float(v) for v in view)
    R = orthographic_camera(azimuth, elevation)
    alignment = align_prior(level, in_metres, R, band=band, relative=relative)
    warped = warp_prior(in_metres, alignment, markers.fps)
    cost = view_cost(level, warped, azimuth, elevation)
    times["align"] = _since(clock)

    clock = time.perf_counter()
    camera = estimate_camera(markers, warped, azimuth=azimuth, elevation=elevation, focal=f, width=width,
                             height=height, weights=camera_weights, still=still_camera,
                             roll=None if up is None else -float(up), hold_elevation=hold_elevation,
                             progress=progress)
    camera_px = float(np.linalg.norm(camera.project(warped.positions) - markers.positions, axis=-1).mean())
    times["camera"] = _since(clock)

    clock = time.perf_counter()
    points = point_proxies(camera, markers, warped, smooth_weight=smooth)
    reproj = float(np.linalg.norm(camera.project(points) - markers.positions, axis=-1).max())
    times["points"] = _since(clock)

    clock = time.perf_counter()
    limbs = warped.limbs
    radii = capped = None
    if image_frames is not None:
        drawn, capped = drawn_widths(image_frames, markers, limbs, widths=_limb_widths(widths, warped))
        radii = collision_radii(camera, markers, points, limbs, drawn)
    times["volumes"] = _since(clock)

    clock = time.perf_counter()
    chosen_upper = None
    if upper is not None:
        chosen_upper = np.array([n in set(upper) for n in warped.names])
        unknown = sorted(set(upper) - set(warped.names))
        if unknown:
            raise ProxyError(f"upper body names {unknown[0]!r}, which is not a marker")
    others = [prior_in_metres(p)[0] for p in extra]
    skeleton = skeleton_proxy(markers, warped, R, upper=chosen_upper, extra=others, weights=skeleton_weights)
    times["skeleton"] = _since(clock)

    proxy = Proxy(names=markers.names, parents=warped.parents, fps=markers.fps, camera=camera, points=points,
                  radii=radii, skeleton=skeleton.positions, rest=skeleton.rest,
                  limb_rotations=skeleton.rotations)
    lift_by = -lowest_path(proxy) if ground == "feet" else 0.0
    if lift_by:
        proxy = _raised(proxy, lift_by)
    report = LiftReport(azimuth=azimuth, elevation=elevation, view_found=found, view_cost=cost, twin=twin,
                        second=second, units=unit, prior_frames=alignment.frames,
                        alignment_cost=alignment.cost, camera_px=camera_px, reproj_px=reproj, capped=capped,
                        warped=warped, times_ms=times, figure_px=_figure_size(markers), up=up,
                        ground_shift=lift_by)
    return proxy, report


def lowest_path(proxy: Proxy, share: float = GROUND_SHIFT_SHARE) -> float:
    """The height of the ground the proxy stands on: the figure's lowest reach on each frame (its
    lowest marker less its joint sphere's radius, :attr:`Proxy.sphere_radii`), taken at the
    ``share`` quantile over the frames (a jump's frames in the air do not lift it; a stray frame's
    dip does not sink it), metres.

    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> P = np.zeros((10, 2, 3)); P[:, 1, 1] = 1.0; P[:, 0, 1] = 0.2; P[9, 0, 1] = -0.5
    >>> cam = PerspectiveCamera(500.0, 64, 48, [[0, 0, 0, 0, 1, 5]] * 10)
    >>> proxy = Proxy(("foot", "hip"), [-1, 0], 12, cam, P, None, P, [[0.0, 0.8, 0]], [[[0.0, 0, 0, 1]]] * 10)
    >>> round(lowest_path(proxy), 6)
    0.2
    """
    reach = proxy.points[..., 1]
    spheres = proxy.sphere_radii
    if spheres is not None:
        reach = reach - spheres
    return float(np.quantile(reach.min(axis=1), share, method="higher"))


def _raised(proxy: Proxy, by: float) -> Proxy:
    """``proxy`` and its camera moved up by ``by`` metres together: every picture stays as it was."""
    up = np.array([0.0, by, 0.0])
    extrinsics = proxy.camera.extrinsics.copy()
    extrinsics[:, 4] += by
    camera = PerspectiveCamera(proxy.camera.focal, proxy.camera.width, proxy.camera.height, extrinsics)
    return replace(proxy, camera=camera, points=proxy.points + up, skeleton=proxy.skeleton + up)


def search_view(markers: Markers, prior: Prior, *, band: float = 0.1, relative: bool = False) -> ViewFit:
    """The orthographic view (3.1.3) that best shows the prior as drawn, searched.

    The timing and the view depend on each other (DTW compares poses seen through a camera; the
    view search compares aligned poses): the prior is aligned through the front view, the view
    searched, the prior aligned again through it and the view searched once more.

    Parameters
    ----------
    markers : Markers
    prior : Prior
        In metres (:func:`~toonmotion.proxy3d.prior.prior_in_metres`), with the markers' names.
    band, relative
        The alignment's (:func:`~toonmotion.proxy3d.timewarp.align_prior`).

    Returns
    -------
    ViewFit
        With its second basin (:attr:`~toonmotion.proxy3d.orthographic.ViewFit.second`): the
        caller decides what an ambiguous view means.
    """
    azimuth, elevation = 0.0, 0.0
    for _ in range(2):
        alignment = align_prior(markers, prior, orthographic_camera(azimuth, elevation), band=band,
                                relative=relative)
        fit = find_view(markers, warp_prior(prior, alignment, markers.fps))
        azimuth, elevation = fit.azimuth, fit.elevation
    return fit


def _figure_size(markers):
    extent = np.ptp(markers.positions, axis=1)
    return float(np.median(np.hypot(extent[:, 0], extent[:, 1])))


def _turned(markers, degrees):
    """The markers turned clockwise in the picture by ``degrees`` about their centroid."""
    if not np.isfinite(degrees):
        raise ProxyError(f"the picture's up must be a finite angle in degrees, got {degrees!r}")
    a = np.radians(degrees)
    turn = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])  # y down: clockwise on screen
    middle = markers.positions.reshape(-1, 2).mean(axis=0)
    return Markers(markers.names, (markers.positions - middle) @ turn.T + middle, fps=markers.fps)


def _angles(azimuth, elevation):
    return f"{azimuth:.0f},{elevation:.0f}"


def _image_size(markers, size, frames):
    if size is not None:
        w, h = size
        if not all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1 for v in (w, h)):
            raise ProxyError(f"the image size must be two whole numbers of pixels, got {size!r}")
        return int(w), int(h)
    if frames is not None:
        return int(frames.shape[2]), int(frames.shape[1])
    top = markers.positions.max(axis=(0, 1))
    if np.any(top <= 0):
        raise ProxyError("the markers lie left of or above the image's origin; give the image size")
    w, h = np.ceil(top * (1 + MARGIN)).astype(int)
    return int(w), int(h)


def _limb_widths(widths, prior):
    """``(frame, marker) -> widths`` as ``(frame, limb) -> widths``."""
    ending = {prior.names[c]: k for k, (_, c) in enumerate(prior.limbs)}
    out = {}
    for (frame, name), pair in (widths or {}).items():
        if name not in ending:
            raise ProxyError(f"a width override names {name!r}, which ends no limb; limbs end at: "
                             f"{', '.join(ending)}")
        out[int(frame), ending[name]] = pair
    return out


def _since(start):
    return round(1000 * (time.perf_counter() - start), 2)


# Drawn frames belong to the markers when the markers mostly lie on them: at most OFF_FRAMES of
# the marker positions (over all frames) may fall outside the frame enlarged by OFF_MARGIN of its
# size on each side. The margin keeps a joint whose limb is cut by the frame's edge; the share
# lets a hand or a foot leave the shot for part of it. Markers of another picture are off by far
# more (issue 45: markers over 1669 x 384 px on 562 x 379 px frames). Measured: the shared char1
# walking (project-mocap 90,0, retarget, animate), its `--save-motion` file (drawing pixels) on
# its own 1808 x 653 frames: 65 % beyond the enlarged frame; `--save-frame-motion`'s files with
# their frames (that walk, char1 from the front, the bundled demo): none outside the frame itself.
OFF_MARGIN = 0.1
OFF_FRAMES = 0.1


def _markers_on_frames(markers, width, height):
    """Refuse frames the markers do not lie on (:data:`OFF_FRAMES`), naming the farthest reach.

    >>> m = Markers(("a", "b"), [[[10.0, 10], [1669, 300]]], fps=12)
    >>> try:
    ...     _markers_on_frames(m, 562, 379)
    ... except ProxyError as error:
    ...     print(error)
    the markers reach x = 1669 px but the frames are 562×379 px: are these frames of this motion? (--frames)
    """
    P = markers.positions.reshape(-1, 2)
    size = np.array([width, height], dtype=float)
    lo, hi = -OFF_MARGIN * size, (1 + OFF_MARGIN) * size
    off = np.any((P < lo) | (P > hi), axis=1)
    if off.mean() <= OFF_FRAMES:
        return
    beyond = np.maximum(lo - P, P - hi) / size  # how far outside, in frame sizes
    point, axis = np.unravel_index(int(np.argmax(beyond)), beyond.shape)
    raise ProxyError(f"the markers reach {'xy'[axis]} = {P[point, axis]:.0f} px but the frames are "
                     f"{width}×{height} px: are these frames of this motion? (--frames)")
