"""2D kinematics: rotations, and bones to joint positions and back.

Every 2D rotation in toonmotion is made here, in one convention: angles are radians in the image
frame, x right, y down, ``atan2(dy, dx)``, and a positive angle turns +x towards +y, which is
*clockwise* as seen on screen:

>>> rotate(np.array([[1.0, 0.0]]), np.pi / 2).round(12).tolist()
[[0.0, 1.0]]

Glossary; everything is batched over any leading axes ``...`` (frames, usually):

- ``angle`` ``(...)``: radians. :func:`rotation` gives ``(..., 2, 2)`` matrices acting on column
  vectors ``(x, y)``; :func:`direction` gives the unit vectors ``(..., 2) = (cos, sin)``.
- ``positions`` ``(..., k, 2)``: every joint of a skeleton, (x, y) pixels, y down, in the
  skeleton's (parents first) order.
- ``angles``, ``lengths`` ``(..., b)``: every bone, in the order of ``Skeleton.bones``, as the
  angle and length of its offset from parent to child.
- ``offsets`` ``(..., b, 2)``: each bone's child position minus its parent's.

:func:`bone_angles` takes positions to bones (inverse kinematics, exact since poses are free
positions); :func:`positions_from_bones` takes bones back to positions (forward kinematics,
parents first from the roots).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import PoseError
from toonmotion.rig.skeleton import Skeleton

FloatArray = NDArray[np.float64]


def rotation(angle: ArrayLike) -> FloatArray:
    """Rotation matrices ``[[cos, -sin], [sin, cos]]`` for ``angle`` radians, ``(..., 2, 2)``.

    A positive angle turns +x towards +y: clockwise on screen, with y down.

    Examples
    --------
    >>> rotation(np.pi / 2).round(12).tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    >>> rotation([0.0, 1.0]).shape
    (2, 2, 2)
    """
    a = np.asarray(angle, dtype=float)
    c, s = np.cos(a), np.sin(a)
    return np.stack([np.stack([c, -s], axis=-1), np.stack([s, c], axis=-1)], axis=-2)


def direction(angle: ArrayLike) -> FloatArray:
    """Unit vectors ``(cos, sin)`` at ``angle`` radians, ``(..., 2)``.

    >>> direction(np.pi / 2).round(12).tolist()
    [0.0, 1.0]
    """
    a = np.asarray(angle, dtype=float)
    return np.stack([np.cos(a), np.sin(a)], axis=-1)


def transform(points: ArrayLike, matrix: ArrayLike, *, about: ArrayLike | None = None) -> FloatArray:
    """Apply 2x2 linear maps to points, about a centre: ``about + M (p - about)``.

    Parameters
    ----------
    points : (..., n, 2) float
        (x, y) points; ``(2,)`` for a single one.
    matrix : (..., 2, 2) float
        Acting on column vectors; its leading axes broadcast against ``points.shape[:-1]``, so
        one matrix maps every point and ``(n, 2, 2)`` maps each point by its own.
    about : (..., 2) float, optional
        The fixed point, broadcast against ``points``; the origin by default.

    Returns
    -------
    (..., n, 2) float
        A new array.

    Examples
    --------
    >>> transform([[3.0, 1.0]], [[2.0, 0.0], [0.0, 1.0]], about=[1.0, 1.0]).tolist()
    [[5.0, 1.0]]
    """
    P = np.asarray(points, dtype=float)
    M = np.asarray(matrix, dtype=float)
    centre = None if about is None else np.asarray(about, dtype=float)
    rel = P if centre is None else P - centre
    x, y = rel[..., 0], rel[..., 1]
    out = np.stack([M[..., 0, 0] * x + M[..., 0, 1] * y, M[..., 1, 0] * x + M[..., 1, 1] * y], axis=-1)
    return out if centre is None else centre + out


def rotate(points: ArrayLike, angle: ArrayLike, *, about: ArrayLike | None = None) -> FloatArray:
    """Turn points by ``angle`` radians about ``about`` (the origin by default).

    Parameters
    ----------
    points, about
        As for :func:`transform` (``about`` ``(T, 1, 2)`` for one centre per frame).
    angle : float or array
        Radians, positive turning +x towards +y (clockwise on screen). Broadcast against
        ``points.shape[:-1]``: a scalar turns every point, ``(n,)`` each point by its own angle,
        and ``(T, 1)`` each frame of ``(T, n, 2)`` points by its own.

    Returns
    -------
    (..., n, 2) float
        The turned points, a new array.

    Examples
    --------
    >>> rotate([[2.0, 1.0], [1.0, 2.0]], np.pi / 2, about=[1.0, 1.0]).round(12).tolist()
    [[1.0, 2.0], [0.0, 1.0]]
    """
    return transform(points, rotation(angle), about=about)


def bone_angles(skeleton: Skeleton, positions: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Angle (radians, ``atan2(dy, dx)``) and length of every bone, ``(..., b)`` each.

    ``positions`` is ``(..., k, 2)``; leading axes are batched. Bones are in the order of
    ``skeleton.bones``; a bone of zero length has angle 0.

    Examples
    --------
    >>> s = Skeleton.from_joints([("arm", None, (0, 0)), ("hand", "arm", (0, 10))])
    >>> angles, lengths = bone_angles(s, s.positions)
    >>> np.degrees(angles).tolist(), lengths.tolist()
    ([90.0], [10.0])
    """
    P = np.asarray(positions, dtype=float)
    bones = skeleton.bones
    d = P[..., bones[:, 1], :] - P[..., bones[:, 0], :]
    return np.arctan2(d[..., 1], d[..., 0]), np.hypot(d[..., 0], d[..., 1])


def positions_from_bones(
    skeleton: Skeleton,
    roots: ArrayLike,
    angles: ArrayLike,
    lengths: ArrayLike,
    *,
    offsets: ArrayLike | None = None,
    given: ArrayLike | None = None,
) -> FloatArray:
    """Joint positions from root positions and bones (forward kinematics), ``(..., k, 2)``.

    Parents first, every child is ``parent + length * direction(angle)``; a bone that ``given``
    marks instead takes its offset from ``offsets`` (a bone of no length has no angle).

    Parameters
    ----------
    skeleton : Skeleton
    roots : (..., k, 2) or (..., r, 2) float
        The root joints' positions: either a full ``(..., k, 2)`` array, whose root rows are
        used and other rows ignored, or just the ``r`` roots in joint order (the joints with
        parent -1).
    angles, lengths : (..., b) float
        Every bone's angle (radians) and length (pixels), in the order of ``skeleton.bones``.
    offsets : (..., b, 2) float, optional
        Child minus parent, for the bones ``given`` marks.
    given : (b,) or (..., b) bool, optional
        Bones whose offset is taken from ``offsets`` (per pose, if it has leading axes); give both
        or neither.

    Returns
    -------
    (..., k, 2) float
        Leading axes are those of ``roots``, ``angles``, ``lengths`` and ``offsets``, broadcast.

    Examples
    --------
    >>> s = Skeleton.from_joints([("arm", None, (0, 0)), ("hand", "arm", (10, 0))])
    >>> positions_from_bones(s, [[1.0, 1.0]], [np.pi / 2], [5.0]).round(12).tolist()
    [[1.0, 1.0], [1.0, 6.0]]
    """
    k, bones = len(skeleton), skeleton.bones
    b = len(bones)
    root_rows = np.flatnonzero(skeleton.parents < 0)
    R = np.asarray(roots, dtype=float)
    if R.ndim < 2 or R.shape[-1] != 2 or R.shape[-2] not in (k, len(root_rows)):
        raise PoseError(
            f"root positions must have shape (..., {k}, 2) or (..., {len(root_rows)}, 2) for this "
            f"skeleton's {k} joints and {len(root_rows)} roots, got {R.shape}"
        )
    if R.shape[-2] == k:
        R = R[..., root_rows, :]
    A, L = np.asarray(angles, dtype=float), np.asarray(lengths, dtype=float)
    for what, array in (("angles", A), ("lengths", L)):
        if array.ndim < 1 or array.shape[-1] != b:
            raise PoseError(f"bone {what} must have shape (..., {b}) for this skeleton's {b} bones, "
                            f"got {array.shape}")
    step = L[..., None] * direction(A)  # (..., b, 2)
    if (offsets is None) != (given is None):
        raise PoseError("give both offsets and the mask of bones they are given for, or neither")
    if offsets is not None:
        D, mask = np.asarray(offsets, dtype=float), np.asarray(given, dtype=bool)
        if D.ndim < 2 or D.shape[-2:] != (b, 2) or mask.ndim < 1 or mask.shape[-1] != b:
            raise PoseError(f"bone offsets must have shape (..., {b}, 2) and their mask (..., {b}), "
                            f"got {D.shape} and {mask.shape}")
        step = np.where(mask[..., None], D, step)
    out = np.empty(np.broadcast_shapes(R.shape[:-2], step.shape[:-2]) + (k, 2))
    out[..., root_rows, :] = R
    for row, (parent, child) in enumerate(bones):  # child order: parents come first
        out[..., child, :] = out[..., parent, :] + step[..., row, :]
    return out
