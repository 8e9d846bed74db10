"""Where stage two works and what holds it there (thesis 3.4.3): the joint areas, the triangles
round each joint that the solve may move (:func:`joint_area`, as wide as :func:`joint_radii`
says), and the anchors that hold the drawing at each joint where the skeleton puts it
(:class:`Anchors`, the ``E4`` term of :mod:`toonmotion.deform.joint_solve`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import SettingsError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.geometry.coordinates import (
    barycentric,
)
from toonmotion.rig.binding import Binding, bone_half_thickness
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton
from toonmotion.shape.mesh import Mesh


@dataclass(frozen=True, eq=False)
class Anchors:
    """Points of the rest mesh that stage two holds where stage one puts them: a term ``E4``,
    ``weight`` times the squared distance of each point from there, beside eq. 3.8's.

    The thesis' stage two frees the joint areas and lets them settle as their outline, inner
    shape and edges ask (eq. 3.8); nothing keeps the joint itself where the skeleton puts it.
    Where a joint area is wide and stiff (knees in wide trousers), it settles as a block, and
    the drawn knee ended 20-24 px from the skeleton's knee on the bundled character's crouch.
    Stage one puts every point at a joint at that joint (both bones' needles turn about it), so
    anchoring the joints' own points there keeps the drawing on the skeleton the animator drew.

    Attributes
    ----------
    points : (a,) int
        Which of the points asked for (:func:`joint_anchors`) each anchor is.
    corners : (a, 3) int
        The rest triangle holding each point.
    barycentric : (a, 3) float
        Each point's weights on its triangle's corners.
    weight : float
        ``w4``, >= 0; 0 leaves the thesis' energy alone.

    Construction copies the arrays (read-only) and raises :class:`SettingsError` for a weight
    that is not a finite number >= 0.
    """

    points: NDArray[np.int64]
    corners: NDArray[np.int64]
    barycentric: NDArray[np.float64]
    weight: float

    def __post_init__(self) -> None:
        corners = frozen_array(self.corners, dtype=np.int64, shape=(None, 3), name="anchor corners")
        object.__setattr__(self, "points", frozen_array(self.points, dtype=np.int64, shape=(len(corners),),
                                                        name="anchored points"))
        object.__setattr__(self, "corners", corners)
        object.__setattr__(self, "barycentric", frozen_array(self.barycentric, dtype=np.float64,
                                                             shape=corners.shape, name="anchor weights"))
        if not (np.isfinite(self.weight) and self.weight >= 0):
            raise SettingsError(f"the joint anchor weight must be a finite number >= 0, got {self.weight}")
        object.__setattr__(self, "weight", float(self.weight))

    def subset(self, keep: NDArray[np.bool_]) -> Anchors:
        """The anchors where ``keep`` (``(a,) bool``) is True."""
        keep = np.asarray(keep, dtype=bool)
        return Anchors(self.points[keep], self.corners[keep], self.barycentric[keep], self.weight)


def joint_anchors(mesh: Mesh, points: NDArray[np.float64], weight: float) -> Anchors:
    """:class:`Anchors` for the rest ``points`` (``(p, 2)``, the skeleton's joints) that lie in
    ``mesh``; a joint drawn outside the figure is not anchored."""
    triangle, bary = barycentric(mesh.V, mesh.F, points)
    inside = np.flatnonzero(triangle >= 0)
    return Anchors(inside, np.asarray(mesh.F)[triangle[inside]].reshape(-1, 3), bary[inside], weight)


def joint_area(
    mesh: Mesh, skeleton: Skeleton, binding: Binding, mask: NDArray[np.bool_], *, width: float = 1.5,
    radius: NDArray[np.float64] | None = None,
) -> NDArray[np.bool_]:
    """Vertices that stage two moves: the joint areas, ``(n,) bool``.

    The thesis' joint area is the vertices of joint triangles (those spanning two bones), a
    band about one triangle wide. On a sharply bent elbow the two limb regions overlap on the
    inside of the bend by about the limb's half-thickness, and a one-triangle band cannot
    unfold that. So around every joint where two or more bones meet we also free the vertices
    of those bones within ``width`` times the thinner bone's half-thickness (the figure's
    distance to its outline along the bone's middle; :func:`joint_radii`, or ``radius`` when
    the caller has them already). ``width=0`` gives the thesis' band alone.
    The default, 1.5, is also :class:`~toonmotion.deform.deformer.DeformSettings`'s
    ``joint_width``, which :class:`~toonmotion.deform.deformer.Deformer` passes.
    """
    if not (np.isfinite(width) and width >= 0):
        raise SettingsError(f"the joint area width must be a finite number >= 0, got {width}")
    free = binding.joint_area.copy()
    if width == 0 or len(mesh.V) == 0:
        return free
    if radius is None:
        radius = joint_radii(skeleton, mask, width=width, floor=mesh.spacing)
    for j, meeting in enumerate(meeting_bones(skeleton)):
        if radius[j] > 0:
            joint = skeleton.positions[j]
            near = np.hypot(mesh.V[:, 0] - joint[0], mesh.V[:, 1] - joint[1]) < radius[j]
            free |= near & np.isin(binding.bone, meeting)
    return free


def joint_radii(skeleton: Skeleton, mask: NDArray[np.bool_], *, width: float, floor: float
                ) -> NDArray[np.float64]:
    """How far round each joint :func:`joint_area` frees vertices, ``(j,)`` pixels: ``width``
    times the thinnest half-thickness of the bones meeting there (each at least ``floor``), 0
    where fewer than two bones meet."""
    thickness = bone_half_thickness(skeleton, mask, floor=floor)
    return np.array([width * thickness[meeting].min() if len(meeting) >= 2 else 0.0
                     for meeting in meeting_bones(skeleton)])


def meeting_bones(skeleton):
    """The bones of length that meet at each joint; joints at one place (AD's root and hip)
    count as one."""
    bones = skeleton.bones
    usable = skeleton.bone_lengths > MIN_BONE_LENGTH
    out = []
    for joint in skeleton.positions:
        here = np.flatnonzero(np.hypot(*(skeleton.positions - joint).T) <= MIN_BONE_LENGTH)
        out.append(np.flatnonzero(usable & (np.isin(bones[:, 0], here) | np.isin(bones[:, 1], here))))
    return out
