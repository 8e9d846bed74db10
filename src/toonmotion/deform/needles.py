"""Stage one: the variable-length needle model (thesis 3.4.1-3.4.2, fig. 3.7-3.8).

Every vertex hangs off its bone on a *needle*: it is written in the bone's frame as ``t``, the
fraction of the way from the bone's start joint to its end, and ``s``, its signed distance
across the bone. A posed bone carries its needles along: it rotates them, moves their roots with
``t`` (so they stretch and squash with the bone), and, with area preservation, shortens each
needle by the reciprocal of the bone's stretch (fig. 3.8), so a region stretched 1.5x along its
bone is 1/1.5x as thick and keeps its area.

For a vertex beside a bone the needle meets the bone at a right angle, exactly the thesis'
model. Past a bone's ends (a hand past the wrist joint) the thesis' needle starts at the end
joint at a fixed angle and shortens by the reciprocal stretch, which would shrink that cap's
area by the square of the stretch; we extend the same affine map there instead, so every bone
region keeps its area, and the map is continuous across the bone's end. Vertices on a bone of
zero rest length (a correction may put them there) only follow its start joint's translation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.geometry.arrays import frozen_array
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton


@dataclass(frozen=True, eq=False)
class NeedleModel:
    """Each vertex's needle in its bone's rest frame; built once per character.

    Attributes
    ----------
    bones : (b, 2) int
        ``(parent, child)`` joints of each bone (``skeleton.bones``).
    bone : (n,) int
        Bone of each vertex.
    t : (n,) float
        Position along the bone, 0 at its start joint and 1 at its end.
    s : (n,) float
        Signed needle length across the bone, pixels.
    rest_length : (b,) float
    rest_direction : (b, 2) float
        Unit vector along each bone at rest, ``(1, 0)`` for rigid bones.
    rigid : (b,) bool
        Bones of zero rest length: their vertices translate only.
    offset : (n, 2) float
        For vertices of rigid bones, their offset from the bone's start joint.

    Construction copies the arrays (read-only) and raises ``ValueError`` unless their shapes
    agree and every vertex's bone exists.
    """

    bones: NDArray[np.int64]
    bone: NDArray[np.int64]
    t: NDArray[np.float64]
    s: NDArray[np.float64]
    rest_length: NDArray[np.float64]
    rest_direction: NDArray[np.float64]
    rigid: NDArray[np.bool_]
    offset: NDArray[np.float64]

    def __post_init__(self) -> None:
        bones = frozen_array(self.bones, dtype=np.int64, shape=(None, 2), name="a needle model's bones")
        bone = frozen_array(self.bone, dtype=np.int64, shape=(None,), name="a needle model's bone")
        b, n = len(bones), len(bone)
        if n and (bone.min() < 0 or bone.max() >= b):
            raise ValueError(f"a needle model's vertices name bones outside 0..{b - 1}")
        object.__setattr__(self, "bones", bones)
        object.__setattr__(self, "bone", bone)
        for name, dtype, shape in (("t", np.float64, (n,)), ("s", np.float64, (n,)),
                                   ("rest_length", np.float64, (b,)), ("rest_direction", np.float64, (b, 2)),
                                   ("rigid", np.bool_, (b,)),
                                   ("offset", np.float64, (n, 2))):
            object.__setattr__(self, name, frozen_array(getattr(self, name), dtype=dtype, shape=shape,
                                                        name=f"a needle model's {name}"))


def needle_model(V: NDArray[np.float64], skeleton: Skeleton, bone: NDArray[np.integer]) -> NeedleModel:
    """Needles of vertices ``V`` (``(n, 2)``) attached to bones ``bone`` (``(n,)``) of ``skeleton``."""
    t, s, length, u, rigid, rel = needle_coordinates(V[:, None], skeleton, np.asarray(bone)[:, None])
    return NeedleModel(
        bones=skeleton.bones,
        bone=np.asarray(bone),
        t=t[:, 0],
        s=s[:, 0],
        rest_length=length,
        rest_direction=u,
        rigid=rigid,
        offset=np.where(rigid[bone][:, None], rel[:, 0], 0.0),
    )


def needle_coordinates(points: NDArray[np.float64], skeleton: Skeleton, bone: NDArray[np.integer]):
    """Points in their bones' rest frames: ``(t, s, rest_length, rest_direction, rigid, offset)``.

    ``points`` ``(..., 2)`` and ``bone`` ``(...)`` (broadcast together) give ``t`` (the fraction of
    the way along the bone) and ``s`` (the signed distance across it, along ``(-u_y, u_x)``), both
    0 on rigid bones, and ``offset``, the point less the bone's start joint; the per-bone
    ``rest_length`` ``(b,)``, unit ``rest_direction`` ``(b, 2)`` (``(1, 0)`` for rigid bones) and
    ``rigid`` ``(b,)`` come with them.
    """
    bones = skeleton.bones
    A = skeleton.positions[bones[:, 0]]
    d = skeleton.positions[bones[:, 1]] - A
    length = np.linalg.norm(d, axis=1)
    rigid = length <= MIN_BONE_LENGTH
    u = d / np.where(rigid, 1.0, length)[:, None]
    u[rigid] = (1.0, 0.0)
    rel = points - A[bone]
    along = np.sum(rel * u[bone], axis=-1)
    across = rel[..., 1] * u[bone][..., 0] - rel[..., 0] * u[bone][..., 1]
    t = np.where(rigid[bone], 0.0, along / np.where(rigid, 1.0, length)[bone])
    return t, np.where(rigid[bone], 0.0, across), length, u, rigid, rel


def posed_frames(bones: NDArray[np.int64], rest_length: NDArray[np.float64], positions: NDArray[np.float64],
                 *, preserve_area: bool = True) -> tuple[NDArray[np.float64], ...]:
    """Each posed bone's start joint, vector to its end and needle direction, ``(b, 2)`` each; the
    needle direction is the unit normal, shortened by the reciprocal of the bone's stretch
    (rest / posed length) with area preservation (fig. 3.8)."""
    A = positions[bones[:, 0]]
    d = positions[bones[:, 1]] - A
    length = np.hypot(d[:, 0], d[:, 1])
    normal = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.maximum(length, 1e-300)[:, None]
    if preserve_area:
        normal *= (rest_length / np.maximum(length, 1e-300))[:, None]
    return A, d, normal


def stage_one(model: NeedleModel, positions: NDArray[np.float64], *, preserve_area: bool = True
              ) -> NDArray[np.float64]:
    """Deformed vertices for joint positions ``positions`` (``(k, 2)``, a pose).

    Returns
    -------
    (n, 2) float
        ``U``: each vertex at the end of its bone-carried needle.
    """
    A, d, normal = posed_frames(model.bones, model.rest_length, positions, preserve_area=preserve_area)
    b = model.bone
    U = A[b] + model.t[:, None] * d[b] + model.s[:, None] * normal[b]
    if model.rigid.any():
        r = model.rigid[b]
        U[r] = A[b[r]] + model.offset[r]
    return U


def stretch_maps(model: NeedleModel, positions: NDArray[np.float64], *, preserve_area: bool = True
                 ) -> NDArray[np.complex128]:
    """How stage one stretches each bone's region, before it turns: ``(b, 2)`` complex ``(a, c)``,
    the linear map ``e -> a e + c conj(e)`` of rest-frame vectors ``e = x + iy``.

    A bone posed ``s`` times its rest length stretches its region ``s``-fold along its rest
    direction ``u`` and, with area preservation, ``1/s``-fold across (otherwise not at all):
    ``a = (s + r) / 2``, ``c = (s - r) / 2 u^2`` with ``r`` the factor across. Rigid bones and
    bones at their rest length give the identity ``(1, 0)``.
    """
    d = positions[model.bones[:, 1]] - positions[model.bones[:, 0]]
    length = np.hypot(d[:, 0], d[:, 1])
    stretch = np.where(model.rigid, 1.0, length / np.where(model.rigid, 1.0, model.rest_length))
    across = 1.0 / np.maximum(stretch, 1e-300) if preserve_area else np.ones_like(stretch)
    u = model.rest_direction[:, 0] + 1j * model.rest_direction[:, 1]
    return np.stack([(stretch + across) / 2, (stretch - across) / 2 * u**2], axis=1).astype(complex)


def triangle_shapes(maps: NDArray[np.complex128], bone: NDArray[np.integer], corners: NDArray[np.integer],
                    *, keep_area: bool = True) -> NDArray[np.complex128]:
    """The shape stage two asks of each triangle (or edge): the mean of its corners' bones'
    :func:`stretch_maps`, ``(k, 2)`` for ``corners`` ``(k, c)``; with ``keep_area`` scaled to
    determinant 1, since a mean of area-keeping maps of different directions grows area a little.
    """
    index = np.asarray(bone)[corners]
    mean = maps[index[:, 0]]  # summed corner by corner: NumPy's sum over a middle axis is slow
    for k in range(1, index.shape[1]):
        mean += maps[index[:, k]]
    mean /= index.shape[1]
    if keep_area:
        det = np.abs(mean[:, 0]) ** 2 - np.abs(mean[:, 1]) ** 2
        mean = mean / np.sqrt(np.maximum(det, 1e-300))[:, None]
    return mean
