"""Frames of a posed character: the textured mesh in depth order, with optional overlays.

A *view* is the rectangle of the drawing's plane that a frame shows, ``(x0, y0, x1, y1)`` in
drawing pixels (edges, so the drawing's own canvas is ``(-0.5, -0.5, w - 0.5, h - 0.5)``). It is
fitted into the output size keeping its aspect ratio.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from numpy.typing import NDArray

from toonmotion.deform.depth import draw_order
from toonmotion.errors import SettingsError
from toonmotion.render.overlay import draw_mesh, draw_reference, draw_skeleton
from toonmotion.render.raster import check_canvas, check_size, render_mesh
from toonmotion.rig.character import Character
from toonmotion.rig.pose import Pose
from toonmotion.rig.skeleton import Skeleton

View = tuple[float, float, float, float]

OVERLAYS = ("mesh", "skeleton", "rest")


def check_overlays(overlays: Iterable[str]) -> tuple[str, ...]:
    """``overlays`` as a tuple, each one of :data:`OVERLAYS`."""
    overlays = tuple(overlays)
    unknown = [o for o in overlays if o not in OVERLAYS]
    if unknown:
        raise SettingsError(f"unknown overlay {unknown[0]!r}; choose from {', '.join(OVERLAYS)}")
    return overlays


def canvas_view(character: Character) -> View:
    """The drawing's own canvas as a view."""
    w, h = character.size
    return (-0.5, -0.5, w - 0.5, h - 0.5)


def fit_view(character: Character, meshes: Iterable[NDArray[np.float64]], *, margin: float = 8.0) -> View:
    """A view holding the drawing's canvas and every deformed mesh in ``meshes``, plus a margin."""
    x0, y0, x1, y1 = canvas_view(character)
    for U in meshes:
        lo, hi = U.min(axis=0) - margin, U.max(axis=0) + margin
        x0, y0 = min(x0, lo[0]), min(y0, lo[1])
        x1, y1 = max(x1, hi[0]), max(y1, hi[1])
    return (float(x0), float(y0), float(x1), float(y1))


def natural_size(view: Sequence[float], *, size: Sequence[int] | None = None) -> tuple[int, int]:
    """The output size: ``size`` if given (checked), else one output pixel per drawing pixel."""
    if size is not None:
        return check_size(size)
    x0, y0, x1, y1 = view
    w, h = max(1.0, float(np.ceil(x1 - x0))), max(1.0, float(np.ceil(y1 - y0)))
    check_canvas(w, h, why="a joint or a vertex is far outside the drawing (check the pose) or give a size")
    return int(w), int(h)


def reference_bones(skeleton: Skeleton,
                    positions: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.int_]]:
    """Each rest bone drawn from its posed start joint (thesis fig. 6.2a's red lines).

    Returns ``(points (2b, 2), pairs (b, 2))``: the rest direction and length of every bone,
    placed at the start joint of the sketched one, so the two differ by the bone's turn and
    stretch.
    """
    bones = skeleton.bones
    start = positions[bones[:, 0]]
    end = start + skeleton.positions[bones[:, 1]] - skeleton.positions[bones[:, 0]]
    points = np.concatenate([start, end])
    pairs = np.stack([np.arange(len(bones)), np.arange(len(bones)) + len(bones)], axis=1)
    return points, pairs


def render_frame(character: Character, U: NDArray[np.float64], *, pose: Pose | None = None,
                 size: Sequence[int] | None = None, view: Sequence[float] | None = None,
                 background: Sequence[int] | None = None, overlays: Iterable[str] = (),
                 order: NDArray[np.int_] | None = None) -> NDArray[np.uint8]:
    """Render the character deformed to vertices ``U``.

    Parameters
    ----------
    character : Character
    U : (n, 2) float
        Deformed vertices.
    pose : Pose, optional
        The joint positions, needed for the ``"skeleton"`` and ``"rest"`` overlays.
    size : (W, H) int, optional
        Output size; default one pixel per drawing pixel of the view.
    view : (x0, y0, x1, y1), optional
        Default: the drawing's canvas.
    background : (r, g, b) or None
        None leaves the background transparent.
    overlays : sequence of str
        Any of :data:`OVERLAYS`: the deformed mesh, the posed skeleton, and the rest bones as
        red reference lines.
    order : (m,) int, optional
        Triangle draw order; default from the character's depth layers.

    Returns
    -------
    (H, W, 4) uint8
    """
    overlays = check_overlays(overlays)
    if pose is None and {"skeleton", "rest"} & set(overlays):
        raise SettingsError("the skeleton and rest overlays need the pose")
    view = canvas_view(character) if view is None else view
    size = natural_size(view, size=size)
    mesh = character.mesh
    if order is None:
        order = draw_order(mesh, character.binding, character.depth)
    frame = render_mesh(character.texture, mesh.V, U, mesh.F, size=size, view=view, order=order,
                        background=background, mask=character.mask)
    if "mesh" in overlays:
        frame = draw_mesh(frame, U, mesh.F, view=view)
    skeleton = character.skeleton
    if "rest" in overlays:
        assert pose is not None  # checked above
        points, pairs = reference_bones(skeleton, pose.positions)
        frame = draw_reference(frame, points, pairs, view=view)
    if "skeleton" in overlays:
        assert pose is not None  # checked above
        frame = draw_skeleton(frame, pose.positions, skeleton.bones, view=view)
    return frame
