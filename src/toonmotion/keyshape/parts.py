"""Sub-parts (Bregler et al. 3.1.4): a character split into parts — legs, arms, head — each
captured with its own affine and key weights, and retargeted part by part.

A part is a list of point indices into the shapes (at least 3, not all on one line); parts may
share points (a shoulder in the arm and the torso). Retargeting places every part with the
whole shapes' one map ``C`` (input key 1 onto output key 1), so the parts stay together, and
a point in several parts goes where they put it on average (our choice: docs/keyshapes.md).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.contour import ContourCapture, capture_contours
from toonmotion.keyshape.model import check_shapes
from toonmotion.keyshape.retarget import place_onto, retarget_shapes

FloatArray = NDArray[np.float64]
Parts = Mapping[str, Sequence[int]]


def check_parts(parts: Parts, count: int, *, what: str = "parts") -> dict[str, NDArray[np.int64]]:
    """``parts`` as index arrays; :class:`KeyShapeError` in one line unless every part has at
    least 3 distinct points of the ``count`` and every point is in a part.

    Examples
    --------
    >>> {k: v.tolist() for k, v in check_parts({"top": [0, 1, 2], "bottom": [2, 3, 0]}, 4).items()}
    {'top': [0, 1, 2], 'bottom': [2, 3, 0]}
    """
    if not parts:
        raise KeyShapeError(f"{what}: name at least one part")
    out = {}
    for name, points in parts.items():
        try:
            index = np.asarray(points, dtype=np.int64).ravel()
        except (TypeError, ValueError):
            raise KeyShapeError(f"{what}: part {name!r} must list point numbers") from None
        if len(np.unique(index)) < 3:
            raise KeyShapeError(f"{what}: part {name!r} needs at least 3 distinct points")
        if index.min() < 0 or index.max() >= count:
            raise KeyShapeError(f"{what}: part {name!r} names a point outside 0 to {count - 1}")
        out[str(name)] = index
    missing = np.setdiff1d(np.arange(count), np.concatenate(list(out.values())))
    if len(missing):
        raise KeyShapeError(f"{what}: point {int(missing[0])} is in no part (every point needs one)")
    return out


def capture_parts(contours: ArrayLike, shapes: ArrayLike, parts: Parts, *, lower: ArrayLike = -0.5,
                  upper: ArrayLike = 1.5, support: int | None = None) -> dict[str, ContourCapture]:
    """Each part of ``contours`` (T, N, 2) captured with the same part of ``shapes`` (K, N, 2):
    its own affine and weights (bounds and support as for :func:`capture_contours`).

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (0, 4), (2, 8), (3, 6)],      # a house
    ...               [(0.0, 0), (6, 0), (4, 4), (0, 4), (2, 12), (4, 7)]])    # splayed, a tall roof
    >>> body, head = [0, 1, 2, 3], [2, 3, 4, 5]
    >>> frame = np.vstack([warp(np.eye(2, 3), [1, 0], S)[:4], warp(np.eye(2, 3), [0, 1], S)[4:]])
    >>> found = capture_parts([frame], S, {"body": body, "head": head})
    >>> [found[k].weights.round(6).tolist() for k in ("body", "head")]
    [[[1.0, 0.0]], [[0.0, 1.0]]]
    """
    S = check_shapes(shapes)
    V = check_shapes(contours, what="contours")
    index = check_parts(parts, S.shape[1])
    return {name: capture_contours(V[:, i], S[:, i], lower=lower, upper=upper, support=support)
            for name, i in index.items()}


def retarget_parts(captures: Mapping[str, ContourCapture], input_keys: ArrayLike, output_keys: ArrayLike,
                   input_parts: Parts, output_parts: Parts) -> FloatArray:
    """The output shapes (T, M, 2): each output part retargeted from its input part's capture,
    all placed by the whole keys' ``C``; a point in several parts takes their mean.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (0, 4), (2, 8), (3, 6)],
    ...               [(0.0, 0), (6, 0), (4, 4), (0, 4), (2, 12), (4, 7)]])
    >>> parts = {"body": [0, 1, 2, 3], "head": [2, 3, 4, 5]}
    >>> frame = np.vstack([warp(np.eye(2, 3), [1, 0], S)[:4], warp(np.eye(2, 3), [0, 1], S)[4:]])
    >>> found = capture_parts([frame], S, parts)
    >>> bool(np.allclose(retarget_parts(found, S, S, parts, parts)[0], frame))  # the same keys: itself
    True
    """
    S = check_shapes(input_keys, what="input key-shapes")
    out = check_shapes(output_keys, what="output key-shapes")
    ins = check_parts(input_parts, S.shape[1], what="input parts")
    outs = check_parts(output_parts, out.shape[1], what="output parts")
    if set(ins) != set(outs) or set(ins) != set(captures):
        raise KeyShapeError(f"pair every part: input {sorted(ins)}, output {sorted(outs)}, captured "
                            f"{sorted(captures)}")
    C = place_onto(S[0], out[0])
    T = len(next(iter(captures.values())).affine)
    total, count = np.zeros((T, out.shape[1], 2)), np.zeros(out.shape[1])
    for name, i in ins.items():
        o = outs[name]
        total[:, o] += retarget_shapes(captures[name], S[:, i], out[:, o], placing=C)
        count[o] += 1
    return total / count[None, :, None]
