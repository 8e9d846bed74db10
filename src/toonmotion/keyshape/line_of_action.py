"""The line of action (Bregler et al. 2002, section 4): one open line, drawn over every frame of a
cartoon, captured with key lines and retargeted onto a chain of a character's skeleton.

*Lines* are N points in correspondence, ``(N, 2)`` float, drawing pixels (x right, y down),
open: from one end to the other, evenly spaced by arc length (:func:`resample_line`). A line
drawn straight is a normal key, so the checks here allow straight lines (not points); the
affine of a straight line is not unique across it, and capture takes the least-norm one (the
Gauss-Newton step's QP is regularised by ``1e-12 * trace``, :mod:`~toonmotion.keyshape.contour`).

:func:`capture_lines` is contour capture (eq. 4-7) with straight lines allowed; a straight
blend is a saddle of the model, so each frame is solved from several starts
(:func:`~toonmotion.keyshape.contour.capture_contours`, ``straight``). A bend can trade against a stretch
across the line; only the spacing of the points along it tells them apart (a two-segment bend
cannot be told from a stretch at all), but the model's line, which retargeting uses, is the
same either way. :func:`captured_lines` is the model's line per frame; :func:`retarget_line`
poses a skeleton from a line per frame:

- ``C``, a scale and a translation, takes the first frame's line onto the chain's rest span:
  its arc length onto the chain's rest length, its start onto the chain's first joint.
- The chain's joints sit along the line at their rest arc-length fractions; every chain bone
  takes the angle of the chord between its two joints' places on the line and keeps its rest
  length (no stretch: a line drawn longer than the first frame's is followed in shape, not length).
- Every joint off the chain keeps its rest offset from its parent, turned by its parent's
  change of bone angle, so limbs hang rigidly from the chain bone they are attached to. Roots
  (and what hangs from them but not from the chain) turn with the line's chord: its direction
  from end to end against the chain's from first joint to tip.
- The direction the line was drawn in: ``"root-first"`` (from the chain's first joint to its
  tip), ``"tip-first"``, or ``"auto"``, which turns the lines round when the first line's chord
  points away from the chain's rest chord (more than 90 degrees).

These choices are ours (docs/keyshapes.md).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.contour import ContourCapture, capture_contours
from toonmotion.keyshape.model import check_shapes
from toonmotion.rig.kinematics import bone_angles, positions_from_bones
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

FloatArray = NDArray[np.float64]
DIRECTIONS = ("auto", "root-first", "tip-first")


def resample_line(polyline: ArrayLike, count: int) -> FloatArray:
    """An open polyline resampled to ``count`` points evenly spaced by arc length, from its first
    point to its last (both kept).

    Examples
    --------
    >>> resample_line([(0, 0), (4, 0), (4, 2)], 4).tolist()
    [[0.0, 0.0], [2.0, 0.0], [4.0, 0.0], [4.0, 2.0]]
    """
    try:
        P = np.array(polyline, dtype=float)
    except (TypeError, ValueError):
        raise KeyShapeError("a line must be a list of [x, y] points") from None
    if P.ndim != 2 or P.shape[1] != 2:
        raise KeyShapeError("a line must be a list of [x, y] points")
    if not np.isfinite(P).all():
        raise KeyShapeError("a line has a point that is not a finite number")
    if not (isinstance(count, int) and 2 <= count <= 100_000):
        raise KeyShapeError(f"a line is resampled to 2 to 100,000 points, not {count!r}")
    steps = np.hypot(*np.diff(P, axis=0).T)
    keep = np.concatenate([[True], steps > 0])  # repeated points add no length
    P, run = P[keep], np.concatenate([[0.0], np.cumsum(steps[steps > 0])])
    if len(P) < 2 or not run[-1] > 0:
        raise KeyShapeError("a line needs at least 2 distinct points (it has no length)")
    at = run[-1] * np.arange(count) / (count - 1)
    out = np.stack([np.interp(at, run, P[:, 0]), np.interp(at, run, P[:, 1])], axis=1)
    out[-1] = P[-1]
    return out


def capture_lines(lines: ArrayLike, keys: ArrayLike, *, lower: ArrayLike = -0.5, upper: ArrayLike = 1.5,
                  support: int | None = None) -> ContourCapture:
    """Capture ``lines`` (T, N, 2) with key lines ``keys`` (K, N, 2): contour capture
    (:func:`~toonmotion.keyshape.contour.capture_contours`, the same solve and bounds) with
    straight lines allowed, each frame solved from several starts.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> straight = resample_line([(0, 0), (0, -100)], 20)
    >>> u = np.linspace(0, 1, 50)
    >>> bent = resample_line(np.stack([20 * np.sin(np.pi * u), -100 * u], axis=1), 20)  # a C
    >>> found = capture_lines([warp([[1, 0, 5], [0, 1, 0]], [0.4, 0.6], [straight, bent])], [straight, bent])
    >>> found.weights.round(6).tolist(), found.affine[0, :, 2].round(6).tolist()
    ([[0.4, 0.6]], [5.0, 0.0])
    """
    return capture_contours(lines, keys, lower=lower, upper=upper, support=support, straight=True)


def captured_lines(capture: ContourCapture, keys: ArrayLike) -> FloatArray:
    """The model's line of every frame (T, N, 2): ``warp(affine[t], weights[t], keys)``."""
    S = check_shapes(keys, what="the key lines", allow_straight=True)
    if capture.weights.shape[1] != len(S):
        raise KeyShapeError(f"the motion has weights for {capture.weights.shape[1]} keys, not the "
                            f"{len(S)} key lines")
    blend = np.tensordot(capture.weights, S, axes=1)  # (T, N, 2)
    return np.asarray(np.einsum("tij,tnj->tni", capture.affine[:, :, :2], blend)
                      + capture.affine[:, None, :, 2], dtype=float)


def default_chain(skeleton: Skeleton) -> tuple[str, ...]:
    """The chain from the skeleton's first root to the leaf farthest from it at rest (for a
    figure rigged at the hips and standing, the spine up to the head).

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> default_chain(sample_rig().skeleton)
    ('root', 'hip', 'torso', 'neck', 'head')
    """
    parents, P = skeleton.parents, skeleton.positions
    below = np.zeros(len(skeleton), dtype=bool)  # the first root's tree
    below[0] = True
    for j in range(1, len(skeleton)):
        below[j] = parents[j] >= 0 and below[parents[j]]
    leaves = [j for j in np.flatnonzero(below) if j > 0 and not (parents == j).any()]
    if not leaves:
        raise KeyShapeError(f"the skeleton's root {skeleton.names[0]!r} has no bones: name a chain of joints")
    tip = max(leaves, key=lambda j: float(np.hypot(*(P[j] - P[0]))))
    path = [int(tip)]
    while parents[path[-1]] >= 0:
        path.append(int(parents[path[-1]]))
    return tuple(skeleton.names[j] for j in reversed(path))


def chain_joints(skeleton: Skeleton, chain: Sequence[str] | str | None) -> NDArray[np.int64]:
    """The joint indices of ``chain`` (names, each the parent of the next, or one comma-separated
    string); the default chain when None. :class:`KeyShapeError` or :class:`SkeletonError` in one
    line otherwise.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> chain_joints(sample_rig().skeleton, "hip, torso, neck").tolist()
    [1, 2, 3]
    """
    given = default_chain(skeleton) if chain is None else chain
    names = [n.strip() for n in (given.split(",") if isinstance(given, str) else map(str, given))]
    if len(names) < 2:
        raise KeyShapeError(f"a chain needs at least 2 joints, each the parent of the next; got {names}")
    index = np.array([skeleton.index(n) for n in names], dtype=np.int64)
    if len(set(names)) != len(names):
        twice = next(n for n in names if names.count(n) > 1)
        raise KeyShapeError(f"the chain names joint {twice!r} twice")
    for a, b, ia, ib in zip(names, names[1:], index, index[1:], strict=False):
        if skeleton.parents[ib] != ia:
            parent = skeleton.names[skeleton.parents[ib]] if skeleton.parents[ib] >= 0 else None
            raise KeyShapeError(f"the chain must run from parent to child: {a!r} is not the parent of {b!r} "
                                f"(the parent of {b!r} is {parent!r})")
    return index


def retarget_line(lines: ArrayLike, skeleton: Skeleton, chain: Sequence[str] | str | None = None, *,
                  direction: str = "auto", rest: ArrayLike | None = None) -> FloatArray:
    """Joint positions (T, k, 2) posing ``skeleton`` along a line of action per frame.

    Parameters
    ----------
    lines : (T, N, 2) float
        The line of every frame, points in correspondence, drawing pixels (the captured model's
        lines, :func:`captured_lines`, or lines as drawn).
    skeleton : Skeleton
    chain : sequence of str, optional
        Joint names from a root-side joint to a tip, each the parent of the next; by default
        :func:`default_chain`.
    direction : {"auto", "root-first", "tip-first"}
        Which end of the lines is the chain's first joint; ``"auto"`` decides from the first line.
    rest : (k, 2) float, optional
        The pose to bend (its bone lengths and offsets are kept); the skeleton's rest by default.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> skeleton = sample_rig().skeleton
    >>> spine = skeleton.positions[[skeleton.index(n) for n in default_chain(skeleton)]]
    >>> line = resample_line(spine, 30)
    >>> for drawn in (line, line[::-1]):  # drawn either way: the rest pose
    ...     print(float(np.abs(retarget_line([drawn], skeleton) - skeleton.positions).max()) < 1e-9)
    True
    True
    """
    if direction not in DIRECTIONS:
        raise KeyShapeError(f"direction must be one of {DIRECTIONS}, got {direction!r}")
    L = check_shapes(lines, what="the lines of action", allow_straight=True)
    index = chain_joints(skeleton, chain)
    R = skeleton.positions if rest is None else np.asarray(rest, dtype=float)
    if R.shape != (len(skeleton), 2) or not np.isfinite(R).all():
        raise KeyShapeError(f"the rest pose must be finite positions of all {len(skeleton)} joints")
    rest_angles, rest_lengths = bone_angles(skeleton, R)
    bone_of = {int(child): row for row, child in enumerate(skeleton.bones[:, 1])}
    chain_lengths = np.array([rest_lengths[bone_of[int(j)]] for j in index[1:]])
    total = float(chain_lengths.sum())
    rest_chord = R[index[-1]] - R[index[0]]
    if not total > MIN_BONE_LENGTH or not np.hypot(*rest_chord) > MIN_BONE_LENGTH:
        raise KeyShapeError("the chain's ends meet at rest: choose a chain that spans the character")
    if direction == "tip-first" or (direction == "auto" and (L[0, -1] - L[0, 0]) @ rest_chord < 0):
        L = L[:, ::-1]
    scale = total / _arc(L[0])[-1]
    P = scale * (L - L[0, 0]) + R[index[0]]  # the lines in the character's frame (C)
    chord = P[:, -1] - P[:, 0]
    if (np.hypot(chord[:, 0], chord[:, 1]) <= MIN_BONE_LENGTH).any():
        frame = int(np.flatnonzero(np.hypot(chord[:, 0], chord[:, 1]) <= MIN_BONE_LENGTH)[0])
        raise KeyShapeError(f"the line of frame {frame} ends where it starts: a line of action is open")
    fractions = np.concatenate([[0.0], np.cumsum(chain_lengths)]) / total
    places = np.stack([_along(p, fractions) for p in P])  # (T, c, 2): the chain's joints on the line
    turn = np.arctan2(chord[:, 1], chord[:, 0]) - np.arctan2(rest_chord[1], rest_chord[0])  # (T,)
    change = np.zeros((len(P), len(skeleton)))  # each joint's change of bone angle
    on_chain = {int(j): i for i, j in enumerate(index)}
    for j in range(len(skeleton)):
        parent = int(skeleton.parents[j])
        change[:, j] = turn if parent < 0 else change[:, parent]
        i = on_chain.get(j, 0)
        if i > 0 and chain_lengths[i - 1] > MIN_BONE_LENGTH:
            d = places[:, i] - places[:, i - 1]
            seen = np.hypot(d[:, 0], d[:, 1]) > MIN_BONE_LENGTH * scale
            angle = np.arctan2(d[:, 1], d[:, 0]) - rest_angles[bone_of[j]]
            change[:, j] = np.where(seen, angle, change[:, j])
    turned = rest_angles + change[:, skeleton.bones[:, 1]]  # (T, b): each bone by its joint's change
    posed = positions_from_bones(skeleton, np.broadcast_to(R, (len(P), *R.shape)), turned,
                                 np.broadcast_to(rest_lengths, turned.shape))
    return np.asarray(posed + (places[:, 0] - posed[:, index[0]])[:, None, :], dtype=float)


def _arc(points: FloatArray) -> FloatArray:
    """Arc length from the first point to each point, (N,)."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(points, axis=0).T))])


def _along(points: FloatArray, fractions: FloatArray) -> FloatArray:
    """The points at ``fractions`` of the polyline's arc length, (c, 2)."""
    run = _arc(points)
    at = fractions * run[-1]
    return np.stack([np.interp(at, run, points[:, 0]), np.interp(at, run, points[:, 1])], axis=1)
