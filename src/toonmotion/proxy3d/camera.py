"""The artist's camera as a perspective camera per frame (section 3.3).

A :class:`PerspectiveCamera` has zero skew, square pixels, the principal point at the image's
centre and one focal length (pixels) for the whole shot; its six extrinsic parameters per frame
are ``(azimuth, elevation, roll, cx, cy, cz)``: three angles in radians and the camera's centre
in the world (metres). 3D is right-handed, +Y up, metres; 2D is drawing pixels, x right, y down.

The angles extend :func:`~toonmotion.proxy3d.orthographic.camera`'s: at azimuth 0 the camera
looks along -Z, azimuth turns it about +Y from +Z towards +X, elevation tilts it to look down,
and roll turns the image about the viewing axis (positive: the picture turns clockwise on
screen, y down). The camera frame's rows are the image's x axis (right), its y axis (down) and
the viewing direction (forward); a world point ``X`` is seen at
``(f x_c / z_c + w / 2, f y_c / z_c + h / 2)`` with ``(x_c, y_c, z_c) = R (X - c)``, and
``z_c`` is its depth (eq. 4's ``m_3^T X``, up to the camera's scale).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import ProxyError
from toonmotion.geometry.arrays import finite_float, frozen_array

# Points nearer the camera than this (metres, along its axis) count as not seen.
MIN_DEPTH = 1e-6


@dataclass(frozen=True, eq=False)
class PerspectiveCamera:
    """A perspective camera per frame.

    Attributes
    ----------
    focal : float
        Focal length in pixels (the same for x and y; zero skew).
    width, height : int
        Image size in pixels; the principal point is the centre ``(width / 2, height / 2)``.
    extrinsics : (T, 6) float
        Per frame ``(azimuth, elevation, roll, cx, cy, cz)``: radians, then the camera's centre
        in metres (module docstring).

    Examples
    --------
    A camera 5 m in front of the origin, 1 m up, looking along -Z:

    >>> cam = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5]])
    >>> cam.project([[[0.0, 1.0, 0.0], [1.0, 2.0, 0.0]]]).tolist()
    [[[320.0, 240.0], [420.0, 140.0]]]
    >>> cam.depth([[[0.0, 1.0, 0.0]]]).tolist()
    [[5.0]]
    """

    focal: float
    width: int
    height: int
    extrinsics: NDArray[np.float64]

    def __post_init__(self) -> None:
        focal = finite_float(self.focal, name="the focal length", error=ProxyError)
        if focal <= 0:
            raise ProxyError(f"the focal length must be a positive number of pixels, got {self.focal!r}")
        for name in ("width", "height"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ProxyError(f"the image {name} must be a whole number of pixels, at least 1, got "
                                 f"{value!r}")
            object.__setattr__(self, name, int(value))
        ext = frozen_array(self.extrinsics, dtype=np.float64, name="the camera's extrinsics",
                           error=ProxyError,
                           finite=True)
        if ext.ndim != 2 or ext.shape[1] != 6 or len(ext) == 0:
            raise ProxyError(f"a camera needs extrinsics of shape (frames, 6), got {ext.shape}")
        object.__setattr__(self, "focal", focal)
        object.__setattr__(self, "extrinsics", ext)

    @property
    def frame_count(self) -> int:
        """Number of frames, ``T``."""
        return len(self.extrinsics)

    @property
    def centres(self) -> NDArray[np.float64]:
        """The camera's centre per frame, ``(T, 3)`` metres."""
        return self.extrinsics[:, 3:]

    @property
    def rotations(self) -> NDArray[np.float64]:
        """World-to-camera rotations per frame, ``(T, 3, 3)``; rows: image x, image y, forward."""
        return rotations(self.extrinsics[:, :3])

    @property
    def intrinsics(self) -> NDArray[np.float64]:
        """The 3x3 intrinsic matrix ``K``."""
        return np.array([[self.focal, 0, self.width / 2], [0, self.focal, self.height / 2], [0, 0, 1.0]])

    def matrices(self) -> NDArray[np.float64]:
        """The projection matrices ``M_i = K R_i [I | -c_i]``, ``(T, 3, 4)``."""
        R = self.rotations
        Rt = np.concatenate([R, -(R @ self.centres[:, :, None])], axis=2)
        return self.intrinsics @ Rt

    def to_camera(self, points: ArrayLike) -> NDArray[np.float64]:
        """World points ``(T, N, 3)`` in each frame's camera frame (x right, y down, forward)."""
        X = _points(points, self.frame_count)
        return np.einsum("tij,tnj->tni", self.rotations, X - self.centres[:, None])

    def depth(self, points: ArrayLike) -> NDArray[np.float64]:
        """Each point's depth along the camera's axis, ``(T, N)`` metres."""
        return self.to_camera(points)[..., 2]

    def project(self, points: ArrayLike) -> NDArray[np.float64]:
        """World points ``(T, N, 3)`` to pixels ``(T, N, 2)`` (x right, y down).

        Raises :class:`ProxyError` when a point is not in front of the camera.
        """
        C = self.to_camera(points)
        if np.any(C[..., 2] <= MIN_DEPTH):
            t, n = np.argwhere(C[..., 2] <= MIN_DEPTH)[0]
            raise ProxyError(f"point {n} on frame {t} is behind the camera; the camera cannot see it")
        return self.focal * C[..., :2] / C[..., 2:] + [self.width / 2, self.height / 2]

    def rays(self, pixels: ArrayLike) -> NDArray[np.float64]:
        """World directions through pixels ``(T, N, 2)``, scaled to unit depth, ``(T, N, 3)``.

        ``centre + d * ray`` is the point at depth ``d`` seen at the pixel.

        >>> cam = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5]])
        >>> cam.rays([[[420.0, 140.0]]]).tolist()
        [[[0.2, 0.2, -1.0]]]
        """
        p = np.asarray(pixels, dtype=float)
        if p.ndim != 3 or p.shape[0] != self.frame_count or p.shape[2] != 2:
            raise ProxyError(f"pixels must be (frames={self.frame_count}, points, 2), got {p.shape}")
        local = np.concatenate([(p - [self.width / 2, self.height / 2]) / self.focal,
                                np.ones(p.shape[:2] + (1,))], axis=2)
        return np.einsum("tji,tnj->tni", self.rotations, local)

    def at(self, pixels: ArrayLike, depths: ArrayLike) -> NDArray[np.float64]:
        """World points seen at ``pixels`` ``(T, N, 2)`` at ``depths`` ``(T, N)``: back-projection."""
        return self.centres[:, None] + np.asarray(depths, dtype=float)[..., None] * self.rays(pixels)


def rotations(angles: ArrayLike) -> NDArray[np.float64]:
    """World-to-camera rotations ``(T, 3, 3)`` for ``(azimuth, elevation, roll)`` radians ``(T, 3)``.

    Rows: the image's x axis, its y axis (down) and the viewing direction, in the world.

    >>> (rotations([[0.0, 0.0, 0.0]]).round(12)[0] + 0.0).tolist()
    [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]
    """
    a = np.asarray(angles, dtype=float).reshape(-1, 3)
    az, el, roll = a[:, 0], a[:, 1], a[:, 2]
    ca, sa, ce, se = np.cos(az), np.sin(az), np.cos(el), np.sin(el)
    zero = np.zeros_like(az)
    right = np.stack([ca, zero, -sa], axis=-1)
    down = np.stack([se * sa, -ce, se * ca], axis=-1)
    forward = np.stack([-ce * sa, -se, -ce * ca], axis=-1)
    cr, sr = np.cos(roll)[:, None], np.sin(roll)[:, None]
    # Rolling the camera by +roll turns the picture by -roll: the axes turn by +roll about forward.
    return np.stack([cr * right + sr * down, -sr * right + cr * down, forward], axis=1)


def angles(R: ArrayLike) -> NDArray[np.float64]:
    """``(azimuth, elevation, roll)`` radians ``(T, 3)`` of world-to-camera rotations ``(T, 3, 3)``.

    The inverse of :func:`rotations` for elevations strictly between -90 and 90 degrees.

    >>> a = np.array([[0.3, -0.2, 0.1]])
    >>> angles(rotations(a)).round(12).tolist()
    [[0.3, -0.2, 0.1]]
    """
    M = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    forward = M[:, 2]
    el = np.arcsin(np.clip(-forward[:, 1], -1, 1))
    az = np.arctan2(-forward[:, 0], -forward[:, 2])
    base = rotations(np.stack([az, el, np.zeros_like(az)], axis=1))
    roll = np.arctan2(np.einsum("ti,ti->t", M[:, 0], base[:, 1]), np.einsum("ti,ti->t", M[:, 0], base[:, 0]))
    return np.stack([az, el, roll], axis=1)


def _points(points, frames):
    X = np.asarray(points, dtype=float)
    if X.ndim != 3 or X.shape[0] != frames or X.shape[2] != 3:
        raise ProxyError(f"points must be (frames={frames}, points, 3), got {X.shape}")
    return X
