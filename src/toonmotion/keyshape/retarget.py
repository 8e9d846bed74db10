"""Retargeting captured key-shape motion (Bregler et al. 3.4): the captured weights replayed on
output key-shapes drawn for another character, and the captured affine motion added.

Each input key is paired with an output key: a shape (any number of points, the same in every
output key) or a pose of a rigged character's skeleton.

The output lives in its own frame. ``C``, a scale and a translation, takes the input's first key
onto the output's first key (centre onto centre, size onto size), and the input's motion is
carried over as ``C A(t) C^-1``; so outputs equal to the inputs give the input back exactly.

*Shapes*: each output key's affine relative to the first output key is factored out (eq. 5) and
the input keys' own affine relation put in its place, the keys are blended with the captured
weights, and the motion applied.

*Poses* (the paper's joint-angle interpolation for articulated figures): every bone's angle
(unwrapped from the first key) and length, and the root's place, are blended with the weights;
the pose then follows the same motion.

*Pins*: a point (an output point or a joint) held at a position at chosen frames by the least
global translation, the translations blended between pinned frames (PCHIP: no overshoot) and
held beyond them. These choices are ours (docs/keyshapes.md).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PchipInterpolator

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.model import check_shapes, fit_affine
from toonmotion.rig.kinematics import bone_angles, positions_from_bones
from toonmotion.rig.skeleton import Skeleton

FloatArray = NDArray[np.float64]


def retarget_shapes(capture: ContourCapture, input_keys: ArrayLike, output_keys: ArrayLike, *,
                    placing: ArrayLike | None = None) -> FloatArray:
    """The output shapes (T, M, 2): ``output_keys`` (K, M, 2) blended with the captured weights
    and moved as the input moved; ``input_keys`` (K, N, 2) are the keys the motion was captured with.
    ``placing`` (3, 3) replaces ``C``, the map of the input's first key onto the output's (sub-parts
    share their whole shapes' one).

    Examples
    --------
    >>> from toonmotion.keyshape.contour import capture_contours
    >>> from toonmotion.keyshape.model import warp
    >>> keys = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)],
    ...                  [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])
    >>> clip = [warp([[1, 0, 3 * t], [0, 1, 0]], [1 - t / 2, t / 2], keys) for t in range(3)]
    >>> found = capture_contours(clip, keys)
    >>> bool(np.allclose(retarget_shapes(found, keys, keys), clip))  # the same keys: the input back
    True
    """
    S = check_shapes(input_keys, what="input key-shapes")
    out = check_shapes(output_keys, what="output key-shapes")
    W = _weights(capture, len(S))
    if len(out) != len(S):
        raise KeyShapeError(f"pair every input key with an output key: {len(S)} inputs, {len(out)} outputs")
    C = place_onto(S[0], out[0]) if placing is None else np.asarray(placing, dtype=float)
    C_inv = np.linalg.inv(C)
    aligned = []
    for s_k, o_k in zip(S, out, strict=True):
        A_in = _square(fit_affine(s_k, S[0]))  # input key 1 -> input key k
        A_out = _square(fit_affine(o_k, out[0]))  # output key 1 -> output key k
        aligned.append(_apply(C @ A_in @ C_inv @ np.linalg.inv(A_out), o_k))
    blend = np.tensordot(W, np.stack(aligned), axes=1)  # (T, M, 2)
    return _moved(capture, C, blend)


def retarget_poses(capture: ContourCapture, input_keys: ArrayLike, skeleton: Skeleton,
                   key_poses: ArrayLike, *, reference: ArrayLike | None = None) -> FloatArray:
    """Joint positions (T, k, 2): the skeleton's ``key_poses`` (K, k, 2), one per input key,
    blended bone by bone (angles and lengths) with the captured weights and moved as the input
    moved. ``reference`` (points: the character's outline in the first key pose) gives its
    size and place for ``C``; by default the first pose's joints do."""
    S = check_shapes(input_keys, what="input key-shapes")
    W = _weights(capture, len(S))
    poses = np.asarray(key_poses, dtype=float)
    if poses.ndim != 3 or poses.shape[1:] != (len(skeleton), 2) or len(poses) != len(S):
        raise KeyShapeError(f"give one pose of the skeleton's {len(skeleton)} joints per key ({len(S)} keys)")
    if not np.isfinite(poses).all():
        raise KeyShapeError("a key pose has a joint that is not a finite number")
    angles, lengths = bone_angles(skeleton, poses)  # (K, b)
    angles = angles[0] + np.angle(np.exp(1j * (angles - angles[0])))  # the short way from key 1
    roots = poses[:, skeleton.parents < 0]
    blended = positions_from_bones(skeleton, np.tensordot(W, roots, axes=1), W @ angles, W @ lengths)
    placed = poses[0] if reference is None else check_shapes(reference, what="the reference outline")[0]
    return _moved(capture, place_onto(S[0], placed), blended)


def pin(points: ArrayLike, index: int, targets: Mapping[int, ArrayLike]) -> FloatArray:
    """``points`` (T, n, 2) moved so that point ``index`` is at ``targets[t]`` on each pinned
    frame ``t``: one translation per frame, blended between pinned frames, held beyond them.

    Examples
    --------
    >>> walk = np.zeros((5, 2, 2)) + np.arange(5)[:, None, None]
    >>> pinned = pin(walk, 0, {0: (0, 0), 4: (0, 0)})
    >>> pinned[:, 0].tolist()
    [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
    """
    P = np.asarray(points, dtype=float)
    if not targets:
        return P.copy()
    if not 0 <= index < P.shape[1]:
        raise KeyShapeError(f"the pinned point must be one of the {P.shape[1]} points, got {index}")
    frames = np.array(sorted(targets))
    if frames.min() < 0 or frames.max() >= len(P):
        raise KeyShapeError(f"pinned frames must lie within the motion's {len(P)} frames")
    offsets = np.array([np.asarray(targets[f], dtype=float) - P[f, index] for f in frames])
    if len(frames) == 1:
        shift = np.repeat(offsets, len(P), axis=0)
    else:
        t = np.clip(np.arange(len(P)), frames[0], frames[-1])
        shift = PchipInterpolator(frames, offsets, axis=0)(t)
    return P + shift[:, None, :]


def _weights(capture: ContourCapture, keys: int) -> FloatArray:
    if capture.weights.shape[1] != keys:
        raise KeyShapeError(f"the motion has weights for {capture.weights.shape[1]} keys, not the {keys} "
                            "input keys: retarget a motion captured with the hand-picked keys (--keys)")
    return capture.weights


def place_onto(source: FloatArray, target: FloatArray) -> FloatArray:
    """The scale and translation (3, 3) taking ``source``'s centre and size onto ``target``'s."""
    scale = _size(target) / max(_size(source), 1e-9)
    C = np.eye(3)
    C[:2, :2] *= scale
    C[:2, 2] = _centre(target) - scale * _centre(source)
    return C


def _moved(capture: ContourCapture, C: FloatArray, points: FloatArray) -> FloatArray:
    """``points`` (T, n, 2), in the output's key frame, moved by ``C A(t) C^-1`` each frame."""
    A = np.concatenate([capture.affine, np.tile([[[0.0, 0.0, 1.0]]], (len(capture.affine), 1, 1))], axis=1)
    M = C @ A @ np.linalg.inv(C)
    return np.einsum("tij,tnj->tni", M[:, :2, :2], points) + M[:, None, :2, 2]


def _square(A: FloatArray) -> FloatArray:
    return np.vstack([A, [0.0, 0.0, 1.0]])


def _apply(M: NDArray[np.floating], points: FloatArray) -> FloatArray:
    return np.asarray(points @ M[:2, :2].T + M[:2, 2], dtype=float)


def _centre(points: FloatArray) -> FloatArray:
    return np.asarray((points.max(axis=0) + points.min(axis=0)) / 2, dtype=float)


def _size(points: FloatArray) -> float:
    return float(np.hypot(*np.ptp(points, axis=0)))
