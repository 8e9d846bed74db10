"""A preview of a 3D proxy: seen from the estimated camera over the drawing, beside a side view.

Left, each drawn frame (or a white canvas of the camera's size) with the proxy seen through that
frame's camera: collision volumes as translucent tapered outlines, the skeleton as lines, the
point proxies as dots (they sit on the drawn markers). Right, the same frame from the side
(orthographic, a quarter turn from the camera's first azimuth, the ground as a line), scaled to
hold the whole clip: the depth the drawing cannot show. 3D is right-handed, +Y up, metres;
pictures are RGB, y down.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.camera import rotations
from toonmotion.proxy3d.proxy import Proxy

SKELETON = (30, 90, 200)
POINTS = (220, 40, 40)
VOLUMES = (40, 160, 90)
GROUND = (150, 150, 150)


def preview_frames(proxy: Proxy, frames: ArrayLike | None = None, *, side_width: int | None = None
                   ) -> list[NDArray[np.uint8]]:
    """One RGB picture per frame: the camera's view over the drawing, and a side view.

    Parameters
    ----------
    proxy : Proxy
    frames : (T, H, W, 3) uint8, optional
        The drawn frames; white canvases of the camera's image size without them.
    side_width : int, optional
        Width of the side view, pixels; default the camera image's height.

    Returns
    -------
    list of (H, W + side_width, 3) uint8

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> cam = PerspectiveCamera(200.0, 80, 60, [[0, 0, 0, 0, 1, 5]])
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 1.5, 0]]])
    >>> q = np.array([[[0.0, 0, 0, 1]]])
    >>> proxy = Proxy(("a", "b"), [-1, 0], 12, cam, pts, None, pts, [[0.0, 0.5, 0]], q)
    >>> [p.shape for p in preview_frames(proxy)]
    [(60, 140, 3)]
    """
    cam = proxy.camera
    T = proxy.frame_count
    if frames is None:
        pictures = np.full((T, cam.height, cam.width, 3), 255, np.uint8)
    else:
        pictures = np.asarray(frames, dtype=np.uint8)
        if pictures.ndim != 4 or len(pictures) != T or pictures.shape[-1] != 3:
            raise ProxyError(f"the preview needs one RGB frame per proxy frame ({T}), got shape "
                             f"{pictures.shape}")
    H = pictures.shape[1]
    side = H if side_width is None else int(side_width)
    seen = cam.project(proxy.skeleton)
    points = cam.project(proxy.points)
    depth = cam.depth(proxy.points)
    side_view = _side_projection(proxy, side, H)
    out = []
    for t in range(T):
        left = np.ascontiguousarray(pictures[t]).copy()
        right = np.full((H, side, 3), 255, np.uint8)
        if proxy.radii is not None:
            radius_px = cam.focal * proxy.radii[t] / depth[t][proxy.limbs]
            _volumes(left, points[t], proxy.limbs, radius_px)
            _volumes(right, side_view.points[t], proxy.limbs, proxy.radii[t] * side_view.scale)
        _ground(right, side_view)
        for image, xy in ((left, seen[t]), (right, side_view.skeleton[t])):
            for p, c in proxy.limbs:
                cv2.line(image, _px(xy[p]), _px(xy[c]), SKELETON, 2, cv2.LINE_AA)
        for xy in points[t]:
            cv2.circle(left, _px(xy), 3, POINTS, -1, cv2.LINE_AA)
        out.append(np.concatenate([left, right], axis=1))
    return out


class _SideView:
    def __init__(self, skeleton, points, scale, ground):
        self.skeleton, self.points, self.scale, self.ground = skeleton, points, scale, ground


def _side_projection(proxy, width, height):
    """Skeleton and points seen orthographically from a quarter turn round, fit to the panel."""
    az = proxy.camera.extrinsics[0, 0] + np.pi / 2
    R = rotations([[az, 0.0, 0.0]])[0][:2]
    every = np.concatenate([proxy.skeleton, proxy.points], axis=1) @ R.T
    ground = np.array([0.0, 0.0, 0.0]) @ R.T
    low, high = every.reshape(-1, 2).min(axis=0), every.reshape(-1, 2).max(axis=0)
    high[1] = max(high[1], ground[1])
    span = np.maximum(high - low, 1e-9)
    scale = 0.9 * min(width / span[0], height / span[1])
    offset = np.array([width, height]) / 2 - scale * (low + high) / 2

    def place(X):
        return scale * (X @ R.T) + offset

    return _SideView(place(proxy.skeleton), place(proxy.points), scale, scale * ground[1] + offset[1])


def _ground(image, view):
    y = int(round(view.ground))
    if 0 <= y < image.shape[0]:
        cv2.line(image, (0, y), (image.shape[1] - 1, y), GROUND, 1, cv2.LINE_AA)


def _volumes(image, xy, limbs, radius):
    """Each limb's tapered outline (its axis with the two radii across it), translucent."""
    layer = image.copy()
    for k, (p, c) in enumerate(limbs):
        a, b = xy[p], xy[c]
        along = b - a
        n = np.hypot(*along)
        if n == 0:
            continue
        normal = np.array([-along[1], along[0]]) / n
        quad = np.array([a + radius[k, 0] * normal, b + radius[k, 1] * normal, b - radius[k, 1] * normal,
                         a - radius[k, 0] * normal])
        cv2.fillConvexPoly(layer, np.rint(quad * 16).astype(np.int32), VOLUMES, cv2.LINE_AA, shift=4)
    cv2.addWeighted(layer, 0.35, image, 0.65, 0, dst=image)


def _px(xy):
    return int(round(float(xy[0]))), int(round(float(xy[1])))
