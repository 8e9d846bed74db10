"""What every rig export of an animated drawing writes, in the exported file's own frame.

Game engines and 3D tools measure y up; drawings measure y down in pixels. Exports put their
origin on the ground under the figure, at the bottom centre of the rest mesh, with y up, and
measure in units of ``unit`` pixels (100 for glTF, whose unit is a metre: a 300-pixel figure is
3 m tall; 1 for Spine, whose unit is a pixel)::

    X = (x - origin_x) / unit,    Y = (origin_y - y) / unit

:func:`to_pixels` takes exported points back to the drawing's pixels. The skin itself is
:mod:`toonmotion.animate.skin_tracks`'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.animate.animation import Animation
from toonmotion.animate.skin_tracks import SkinTracks, skin_tracks, vertex_bones
from toonmotion.deform.deformer import DeformSettings
from toonmotion.deform.depth import draw_order
from toonmotion.errors import ExportError
from toonmotion.rig.character import Character


@dataclass(frozen=True, eq=False)
class DrawingRig:
    """An animated drawing as a skinned rig, in an export's frame (module docstring).

    Attributes
    ----------
    joint_names, bone_names : tuple of str
        The skeleton's joints, and each bone's name (its end joint's).
    tracks : SkinTracks
        Joint and bone frames at rest and per frame.
    V : (n, 2) float
        Rest vertices.
    bone, weight : (n, K) int, float
        The bones each vertex follows and their weights (K = 1 for one-bone skinning).
    U : (T, n, 2) float
        Every frame's deformed vertices: the positions an export must reproduce.
    F : (m, 3) int
        Triangles back to front (the character's depth layers), counter-clockwise with y up.
    uv : (n, 2) float
        Each vertex's place in ``page``: (0, 0) its top-left corner, (1, 1) its bottom-right.
    page : (h, w, 4) uint8
        The drawing cropped round the mesh, transparent off the figure.
    fps : float
    origin : (2,) float
        The export's origin in the drawing's pixels.
    unit : float
        Pixels per export unit.
    """

    joint_names: tuple[str, ...]
    bone_names: tuple[str, ...]
    tracks: SkinTracks
    V: NDArray[np.float64]
    bone: NDArray[np.int64]
    weight: NDArray[np.float64]
    U: NDArray[np.float64]
    F: NDArray[np.int64]
    uv: NDArray[np.float64]
    page: NDArray[np.uint8]
    fps: float
    origin: NDArray[np.float64]
    unit: float

    @property
    def frame_count(self) -> int:
        return len(self.U)


def drawing_rig(character: Character, animation: Animation, *, settings: DeformSettings | None = None,
                unit: float = 1.0) -> DrawingRig:
    """``animation`` of ``character`` as a skinned rig in an export's frame.

    Parameters
    ----------
    character : Character
    animation : Animation
        Made with ``settings`` (its skinning and area preservation are the skin's).
    settings : DeformSettings, optional
    unit : float
        Pixels per export unit.

    Raises
    ------
    ExportError
        The animation is for another character, or a bone is squashed to a point.

    Examples
    --------
    >>> from toonmotion.sample_animation import sample_animated
    >>> hero, animation = sample_animated()
    >>> rig = drawing_rig(hero, animation)
    >>> rig.U.shape[1:] == hero.mesh.V.shape, bool(rig.V[:, 1].min() == 0)  # standing on y = 0
    (True, True)
    """
    settings = settings or DeformSettings()
    mesh, skeleton = character.mesh, character.skeleton
    if not animation.meshes or animation.meshes[0][1].shape != mesh.V.shape:
        raise ExportError("the animation is for another character (its meshes do not match the rig); "
                          "animate this project again")
    origin = np.array([(mesh.V[:, 0].min() + mesh.V[:, 0].max()) / 2, mesh.V[:, 1].max()])

    def frame(points):
        return (points - origin) * np.array([1.0, -1.0]) / unit

    tracks = skin_tracks(skeleton, frame(animation.motion.positions), preserve_area=settings.preserve_area,
                         rest=frame(skeleton.positions))
    bone, weight = vertex_bones(character, skinning=settings.skinning)
    V = frame(mesh.V)
    F = np.asarray(mesh.F)[draw_order(mesh, character.binding, character.depth)]
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    clockwise = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0  # with y up
    F = np.where(clockwise[:, None], F[:, ::-1], F)
    page, uv = _page(character)
    return DrawingRig(joint_names=skeleton.names, bone_names=skeleton.bone_names, tracks=tracks, V=V,
                      bone=bone, weight=weight, U=np.stack([frame(U) for _, U in animation.meshes]), F=F,
                      uv=uv, page=page, fps=float(animation.motion.fps), origin=origin, unit=float(unit))


def to_pixels(points: NDArray[np.float64], rig: DrawingRig) -> NDArray[np.float64]:
    """Points ``(..., 2)`` in ``rig``'s export frame, in the drawing's pixels (y down)."""
    return np.asarray(points, dtype=float) * rig.unit * np.array([1.0, -1.0]) + rig.origin


def _page(character):
    """The drawing cropped round the mesh (transparent off the figure) and each vertex's uv."""
    V = character.mesh.V
    h, w = character.mask.shape
    x0, y0 = (max(int(np.floor(c)) - 1, 0) for c in V.min(axis=0))
    x1, y1 = min(int(np.ceil(V[:, 0].max())) + 2, w), min(int(np.ceil(V[:, 1].max())) + 2, h)
    page = np.array(character.texture[y0:y1, x0:x1])
    page[..., 3] = np.where(character.mask[y0:y1, x0:x1], page[..., 3], 0)
    # Pixel centres are at whole coordinates: pixel x0's left edge is at x0 - 0.5.
    uv = (V - np.array([x0, y0]) + 0.5) / np.array([x1 - x0, y1 - y0])
    return page, uv
