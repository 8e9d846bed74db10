"""The pose descriptor (section 3.2, eq. 1, fig. 4) and the prior's modification to match it.

The descriptor of a 2D pose is the vector of in-plane polar angles of its limbs,
``P = [theta_1, ..., theta_K]`` (eq. 1): for every limb (a marker and its parent marker), the
angle of the child's position in a frame fixed to the parent. The frame's reference direction
is the image's x axis (*absolute*) or the parent limb's direction (*relative*: the forearm's
angle is measured from the upper arm's). Angles are radians,
``atan2(dy, dx)`` in the drawing's frame (x right, y down), wrapped into ``[-pi, pi)``; limbs
hanging from a root have no parent limb and are measured from the x axis either way. The
descriptor ignores translation, scale and limb lengths, so a squashed arm and a long one in the
same pose read alike.

Limbs come from the prior's hierarchy (:attr:`~toonmotion.proxy3d.prior.Prior.limbs`). The
modification (:func:`modify_prior`) rotates each *upper-body* limb of the projected prior in the
image plane, from the root outwards, to the drawing's angle, keeping its projected length;
lower-body limbs are left alone so the prior's ground contacts survive. Which markers are upper
body is read from the skeleton (:func:`upper_body`), never from their names.

Glossary: ``K`` limbs, ``limbs`` ``(K, 2)`` (parent, child) marker indices, parents first.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import ProxyError
from toonmotion.geometry.angles import wrap_angle
from toonmotion.proxy3d.prior import Prior

# A drawn limb shorter than this (pixels) has no direction: the prior keeps its own there.
MIN_LIMB = 1e-9


def limb_vectors(points: ArrayLike, limbs: ArrayLike) -> NDArray[np.float64]:
    """Each limb's child position minus its parent's, ``(..., K, 2)`` (or ``(..., K, 3)``).

    >>> limb_vectors(np.array([[0.0, 0], [1, 1], [1, 3]]), [[0, 1], [1, 2]]).tolist()
    [[1.0, 1.0], [0.0, 2.0]]
    """
    P = np.asarray(points, dtype=float)
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    return P[..., L[:, 1], :] - P[..., L[:, 0], :]


def pose_descriptor(points: ArrayLike, limbs: ArrayLike, *, relative: bool = False) -> NDArray[np.float64]:
    """The pose descriptor of eq. 1: each limb's in-plane polar angle.

    Parameters
    ----------
    points : (..., N, 2) float
        Marker positions, ``(x, y)`` pixels, y down; batched over leading axes (frames).
    limbs : (K, 2) int
        ``(parent, child)`` marker indices, each limb's parent limb before it
        (:attr:`Prior.limbs`).
    relative : bool
        Measure each limb from its parent limb's direction (False: from the x axis).

    Returns
    -------
    (..., K) float
        Radians in ``[-pi, pi)``; a positive angle turns clockwise on screen (y down).

    Examples
    --------
    An arm: the upper arm points right, the forearm down (y down: +pi/2):

    >>> arm = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])
    >>> limbs = [[0, 1], [1, 2]]
    >>> (pose_descriptor(arm, limbs) / np.pi).tolist()
    [0.0, 0.5]
    >>> (pose_descriptor(arm * 3 + 7, limbs, relative=True) / np.pi).tolist()
    [0.0, 0.5]
    """
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    v = limb_vectors(points, L)
    angle = np.arctan2(v[..., 1], v[..., 0])
    if relative:
        parent_limb = _parent_limbs(L)
        has = parent_limb >= 0
        angle = angle.copy()
        angle[..., has] -= np.arctan2(v[..., parent_limb[has], 1], v[..., parent_limb[has], 0])
    return np.asarray(wrap_angle(angle), dtype=float)


def descriptor_features(
    points: ArrayLike, limbs: ArrayLike, *, relative: bool = False
) -> NDArray[np.float64]:
    """Pose descriptors as unit vectors ``(cos theta, sin theta)`` per limb, ``(..., 2K)``.

    The squared distance between two such feature vectors is ``sum(2 - 2 cos(dtheta))``: the
    angles' differences, free of the wrap at ``+-pi``. Dynamic time warping compares these.

    >>> descriptor_features(np.array([[0.0, 0], [0, 2]]), [[0, 1]]).round(12).tolist()
    [0.0, 1.0]
    """
    theta = pose_descriptor(points, limbs, relative=relative)
    return np.concatenate([np.cos(theta), np.sin(theta)], axis=-1)


def upper_body(prior: Prior, *, upper: Iterable[str] | None = None) -> NDArray[np.bool_]:
    """Which markers belong to the upper body, ``(N,)`` bool, from the skeleton's structure.

    The *pelvis* is the root of the largest tree of markers. Each subtree hanging from it (the
    spine with the arms and head, each leg) is upper body when its markers are, on average over
    the clip, above the pelvis (+Y in the prior's world), and lower body when below. Markers in
    other trees (a forest) follow their root's height the same way. The pelvis itself is
    neither: it is not moved.

    Parameters
    ----------
    prior : Prior
    upper : iterable of str, optional
        The upper-body markers, named explicitly instead (for a figure upside down for most
        of the clip, say).

    Examples
    --------
    >>> P = np.array([[[0.0, 1, 0], [0, 2, 0], [1, 1.5, 0], [0, 0, 0]]])   # pelvis, neck, hand, foot
    >>> upper_body(Prior(("pelvis", "neck", "hand", "foot"), [-1, 0, 1, 0], P, fps=12)).tolist()
    [False, True, True, False]
    """
    N = len(prior.names)
    if upper is not None:
        chosen = set(upper)
        unknown = sorted(chosen - set(prior.names))
        if unknown:
            raise ProxyError(f"upper body names {unknown[0]!r}, which is not a marker; the markers are: "
                             f"{', '.join(prior.names)}")
        return np.array([n in chosen for n in prior.names])
    parents = prior.parents
    top = np.arange(N)  # each marker's top: the child of its root it hangs under (or its root)
    root = np.arange(N)
    for m in range(N):
        chain = [m]
        while parents[chain[-1]] >= 0:
            chain.append(int(parents[chain[-1]]))
        root[m] = chain[-1]
        top[m] = chain[-2] if len(chain) > 1 else chain[-1]
    sizes = np.bincount(root, minlength=N)
    pelvis = int(np.argmax(sizes))
    height = prior.positions[..., 1].mean(axis=0) - prior.positions[:, pelvis, 1].mean()
    out = np.zeros(N, dtype=bool)
    for group in np.unique(np.where(root == pelvis, top, root)):
        members = [m for m in range(N) if m != pelvis and (top[m] if root[m] == pelvis else root[m]) == group]
        if members and height[members].mean() > 0:
            out[members] = True
    return out


def modify_prior(
    projected: ArrayLike, drawn: ArrayLike, limbs: ArrayLike, upper: ArrayLike
) -> NDArray[np.float64]:
    """Rotate the projected prior's upper-body limbs in the image plane to the drawing's angles.

    From the roots outwards, each limb whose child marker is upper body is turned about its
    parent marker (at its new place) to the drawn limb's polar angle, keeping its projected
    length, and carries its subtree with it; every other limb keeps its projected vector. So the
    result's upper-body descriptor, absolute or relative, is the drawing's, its lower body is
    the projected prior's exactly, and every limb keeps its projected length (Figure 4).

    Parameters
    ----------
    projected : (T, N, 2) float
        The time-aligned prior projected by the camera approximation (pixels, y down).
    drawn : (T, N, 2) float
        The drawn markers, same frames and markers.
    limbs : (K, 2) int
        ``(parent, child)``, parents first (:attr:`Prior.limbs`).
    upper : (N,) bool
        Upper-body markers (:func:`upper_body`).

    Returns
    -------
    (T, N, 2) float
        The modified 2D prior, ``x^m`` in the paper. A drawn limb of no length (under
        :data:`MIN_LIMB`) keeps the prior's direction.

    Examples
    --------
    Pelvis, neck, hand (upper) and foot (lower); the drawn arm points up, the prior's right:

    >>> prior2d = np.array([[[0.0, 0], [0, -10], [5, -10], [0, 10]]])
    >>> drawn = np.array([[[0.0, 0], [0, -20], [0, -40], [3, 10]]])
    >>> modify_prior(prior2d, drawn, [[0, 1], [1, 2], [0, 3]], [False, True, True, False])[0].tolist()
    [[0.0, 0.0], [0.0, -10.0], [0.0, -15.0], [0.0, 10.0]]
    """
    Q = np.asarray(projected, dtype=float)
    X = np.asarray(drawn, dtype=float)
    L = np.asarray(limbs, dtype=np.int64).reshape(-1, 2)
    up = np.asarray(upper, dtype=bool)
    if Q.ndim != 3 or Q.shape[-1] != 2 or Q.shape != X.shape:
        raise ProxyError(f"the projected prior {Q.shape} and the drawing {X.shape} must both be "
                         "(frames, markers, 2) of the same shape")
    if up.shape != (Q.shape[1],):
        raise ProxyError(f"upper must say for each of the {Q.shape[1]} markers whether it is upper body")
    prior_v = limb_vectors(Q, L)
    drawn_v = limb_vectors(X, L)
    out = Q.copy()
    moved = np.zeros(len(up), dtype=bool)
    for k, (p, c) in enumerate(L):  # parents first: out[:, p] is final when limb k is placed
        if not (up[c] or moved[p]):
            continue  # neither turned nor carried: its positions stay the prior's, bit for bit
        moved[c] = True
        v = prior_v[:, k]
        if up[c]:
            length = np.linalg.norm(v, axis=-1)
            d = np.linalg.norm(drawn_v[:, k], axis=-1)
            turned = drawn_v[:, k] * (length / np.where(d < MIN_LIMB, 1.0, d))[:, None]
            v = np.where((d < MIN_LIMB)[:, None], v, turned)
        out[:, c] = out[:, p] + v
    return out


def _parent_limbs(limbs):
    """For each limb, the index of the limb ending at its parent marker, or -1."""
    ending = {int(c): k for k, (_, c) in enumerate(limbs)}
    return np.array([ending.get(int(p), -1) for p, _ in limbs], dtype=np.int64)
