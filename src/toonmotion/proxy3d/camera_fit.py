"""Camera estimation (section 3.3, eq. 2): the artist's perspective camera, frame by frame.

The drawing alone cannot tell a moving camera from a moving character. The paper's answer: the
character's root moves as the time-aligned motion prior moves, and whatever the drawn markers do
beyond that is the camera. For each frame ``i`` the camera's six extrinsic parameters
``rho_i = (azimuth, elevation, roll, cx, cy, cz)`` (:mod:`~toonmotion.proxy3d.camera`) minimise

    w1 e_g + w2 e_l + w3 e_o + w4 e_s

- ``e_g``: the squared pixel distances between the drawn markers and the prior's markers seen
  through the camera, over a window of frames around ``i`` (robust to a badly drawn frame);
- ``e_l``: the camera's height below ``ground`` (metres above the ground plane Y = 0), squared;
  zero above it. The paper writes ``t_z - mu``; read as a penalty that pulls the camera towards
  height ``mu`` even when it is well above the ground, it would bend every camera's path, so we
  take it as the constraint the text states ("above ground level") -- a one-sided penalty;
- ``e_o``: the roll, squared (beyond the paper, the roll is held at 0 by default instead, so that
  the world's up stays the picture's: ``estimate_camera``'s ``roll``);
- ``e_s``: ``|rho_i - rho_{i-1}|^2``, smoothness (the previous frame's solution is fixed).

All terms are squared (nonlinear least squares; SciPy's Levenberg-Marquardt), with the paper's
weights by default: ``w1 = 1``, ``w2 = w3 = w4 = 0.0005``, ``ground = 1`` m. The intrinsics are
fixed: the given focal length, zero skew, the principal point at the image's centre.

Initialisation (the paper: yaw and pitch from the orthographic angles, roll zero, the centre so
that the first pose fits the image): the first frame's camera looks along the orthographic view
from the distance at which the prior appears as large as drawn (``focal / scale``, with the
orthographic fit's pixels per metre), shifted so the prior's centroid falls on the drawn one;
each later frame starts from the previous frame's camera.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from toonmotion.errors import ProxyError
from toonmotion.progress import Progress
from toonmotion.proxy3d.camera import PerspectiveCamera, rotations
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import fit_scale_translation, view_direction
from toonmotion.proxy3d.prior import Prior


@dataclass(frozen=True)
class CameraWeights:
    """The weights and constants of eq. 2 (defaults: the paper's).

    Attributes
    ----------
    projection, ground, roll, smooth : float
        ``w1`` .. ``w4``.
    height : float
        ``mu``: the lowest height above the ground (metres) the camera may take unpenalised.
    window : int
        Frames in the moving window of ``e_g`` (odd; the frame and ``window // 2`` either side).
    """

    projection: float = 1.0
    ground: float = 0.0005
    roll: float = 0.0005
    smooth: float = 0.0005
    height: float = 1.0
    window: int = 1

    def __post_init__(self) -> None:
        for name in ("projection", "ground", "roll", "smooth", "height"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ProxyError(f"the camera's {name} weight must be a number >= 0, got {value!r}")
        if self.projection <= 0:
            raise ProxyError("the camera's projection weight must be positive")
        if not (isinstance(self.window, int) and self.window >= 1 and self.window % 2 == 1):
            raise ProxyError(f"the camera's window must be an odd number of frames, got {self.window!r}")


def initial_camera(
    markers: Markers, prior: Prior, azimuth: float, elevation: float, focal: float, width: int, height: int
) -> NDArray[np.float64]:
    """The first frame's extrinsics ``(6,)`` from the orthographic view (module docstring).

    ``azimuth``, ``elevation`` in degrees; the prior in metres, aligned to the markers.

    Examples
    --------
    >>> prior = Prior(("a", "b"), [-1, 0], [[[0.0, 1, 0], [0, 2, 0]]], fps=12)
    >>> drawn = Markers(("a", "b"), [[[320.0, 240], [320, 140]]], fps=12)
    >>> initial_camera(drawn, prior, 0, 0, 500.0, 640, 480).round(9).tolist()
    [0.0, 0.0, 0.0, 0.0, 1.0, 5.0]
    """
    R = rotations(np.radians([[azimuth, elevation, 0.0]]))[0]
    scale, translation = fit_scale_translation(markers.positions[:1], prior.positions[:1] @ R[:2].T)
    if not scale > 0:
        raise ProxyError("the prior seen from the given view is drawn mirrored (its fit to the drawing has a "
                         "negative scale); check the camera angles")
    centroid = prior.positions[0].mean(axis=0)
    drawn = markers.positions[0].mean(axis=0)
    distance = focal / scale
    shift = (drawn - [width / 2, height / 2]) / scale
    centre = centroid + distance * view_direction(azimuth, elevation) - shift[0] * R[0] - shift[1] * R[1]
    return np.concatenate([np.radians([azimuth, elevation, 0.0]), centre])


def estimate_camera(
    markers: Markers,
    prior: Prior,
    *,
    azimuth: float,
    elevation: float,
    focal: float,
    width: int,
    height: int,
    weights: CameraWeights | None = None,
    still: bool = False,
    roll: float | None = 0.0,
    hold_elevation: bool = False,
    progress: Progress | None = None,
) -> PerspectiveCamera:
    """The artist's camera per frame by eq. 2.

    Parameters
    ----------
    markers : Markers
        The drawn markers, pixels.
    prior : Prior
        Time-aligned to the markers (same frames and names), in metres with the ground at Y = 0.
    azimuth, elevation : float
        The orthographic view (degrees) to start from.
    focal : float
        Focal length, pixels.
    width, height : int
        Image size, pixels.
    weights : CameraWeights, optional
        The paper's by default.
    still : bool
        Beyond the paper: one camera for the whole shot, fitted to every frame at once (its
        ground and roll terms as above; no window or smoothness). For a drawing made without
        camera moves it is far better posed than a camera per frame, which, where the prior
        explains the drawing badly (cartoon proportions), can wander off between frames.
    roll : float or None
        Beyond the paper: the camera's roll, degrees, held (not fitted): 0, the default, keeps
        the world's up the picture's up, as drawings are made. The paper fits it, with the small
        penalty ``e_o``; that lets a prior whose posture differs from the drawn figure's (a
        human prior for a pig) tilt the whole world to match it. None fits it as the paper does.
    hold_elevation : bool
        Beyond the paper: the camera's elevation held at ``elevation`` (not fitted), as a camera
        on a tripod pans but does not tilt. With the roll held too, the world's vertical stays
        the picture's everywhere in it, whatever the prior: for a figure unlike its prior (a pig
        lifted with a human clip), whose fitted camera would tilt to make the prior look like it.
    progress : callable, optional
        ``progress("camera", done, total)`` per frame.

    Returns
    -------
    PerspectiveCamera

    Raises
    ------
    ProxyError
        The prior is not aligned to the markers, or some prior marker ends behind the camera.

    Examples
    --------
    A still camera seeing a still figure is found again:

    >>> P = np.array([[[0.0, 1, 0], [0, 2, 0], [0.5, 1.5, 0.2]]] * 3)
    >>> true = PerspectiveCamera(500.0, 640, 480, [[0.1, -0.05, 0, 0.6, 1.3, 5.0]] * 3)
    >>> prior = Prior(("a", "b", "c"), [-1, 0, 1], P, fps=12)
    >>> drawn = Markers(prior.names, true.project(P), fps=12)
    >>> cam = estimate_camera(drawn, prior, azimuth=0, elevation=0, focal=500.0, width=640, height=480,
    ...                       weights=CameraWeights(ground=0, roll=0, smooth=0))
    >>> float(np.abs(cam.project(P) - drawn.positions).max()) < 1e-6
    True
    """
    w = weights or CameraWeights()
    if tuple(prior.names) != tuple(markers.names) or prior.frame_count != markers.frame_count:
        raise ProxyError("the prior must be aligned to the markers (the same names and frames) before the "
                         "camera can be estimated")
    T = markers.frame_count
    X, x = prior.positions, markers.positions
    half = w.window // 2
    rho = np.empty((T, 6))
    previous = initial_camera(markers, prior, azimuth, elevation, focal, width, height)
    centre = np.array([width / 2, height / 2])
    near = 1e-3  # metres: a marker nearer the camera than this is treated as out of sight

    held = {}  # extrinsic index -> its value, radians: those not fitted
    if hold_elevation:
        held[1] = float(np.radians(elevation))
    if roll is not None:
        held[2] = float(np.radians(roll))
    free = np.array([k for k in range(6) if k not in held])
    for k, value in held.items():
        previous[k] = value

    def full(q):
        """The six extrinsics from the fitted ones (the held ones put back)."""
        p = np.empty(6)
        p[free] = q
        for k, value in held.items():
            p[k] = value
        return p

    def fitted(p):
        return p[free]

    def residuals(q, i, frames, anchor):
        p = full(q)
        R = rotations(p[None, :3])[0]
        local = (X[frames] - p[3:]) @ R.T
        depth = local[..., 2:]
        seen = focal * local[..., :2] / np.maximum(depth, near) + centre
        behind = np.minimum(depth[..., 0] - near, 0.0) * focal  # pushes hidden markers back in front
        parts = [np.sqrt(w.projection) * (seen - x[frames]).ravel(), behind.ravel(),
                 [np.sqrt(w.ground) * max(0.0, w.height - p[4]), np.sqrt(w.roll) * p[2]]]
        if anchor is not None:
            parts.append(np.sqrt(w.smooth) * (p - anchor))
        return np.concatenate(parts)

    if still:
        found = least_squares(residuals, fitted(previous), args=(0, np.arange(T), None), method="lm",
                              x_scale="jac")
        rho[:] = full(found.x)
        if progress is not None:
            progress("camera", T, T)
    for i in range(0 if still else T):
        frames = np.arange(max(0, i - half), min(T, i + half + 1))
        anchor = None if i == 0 else previous
        found = least_squares(residuals, fitted(previous), args=(i, frames, anchor), method="lm",
                              x_scale="jac")
        rho[i] = previous = full(found.x)
        if progress is not None:
            progress("camera", i + 1, T)
    camera = PerspectiveCamera(focal, width, height, rho)
    depth = camera.depth(X)
    if np.any(depth <= near):
        t, n = np.argwhere(depth <= near)[0]
        raise ProxyError(f"the estimated camera cannot see the marker {markers.names[n]!r} on frame {t} (it "
                         "is "
                         "behind the camera); check the camera angles, the focal length and the image size")
    return camera
