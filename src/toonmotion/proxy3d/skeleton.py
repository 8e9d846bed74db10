"""The skeleton proxy (section 3.4.3, eq. 11-22): a joint hierarchy with the prior's limb lengths.

Per frame, the markers' 3D positions ``X`` (``3N`` numbers) minimise

- eq. 11, the input match: ``w_a |R X_j - x^m_j|`` with ``R`` the orthographic camera and ``x^m``
  the *modified* prior (:func:`~toonmotion.proxy3d.descriptor.modify_prior`: the prior's
  upper-body limbs turned to the drawn angles, its lower body left alone for its ground
  contacts) -- not the drawn markers, so the drawing's squash and stretch is filtered out;
- eq. 12, the prior: ``w_m |X_j - X~_j|``;
- eq. 13-15, limb lengths, linearised about the prior pose: for limb ``(p, c)`` with prior
  vector ``v~`` and length ``L``, ``|X_c - X_p|^2 = L^2`` becomes
  ``2 v~ . (X_c - X_p) = L^2 + |v~|^2``; we divide the row by ``2 L`` so its residual is in
  metres, weighted ``w_l``.

Eq. 18-22: ``X = mu + V b`` in the span of the first ``P`` principal components (default 20) of
the prior's poses and of any other clips given, so each frame is a ``P``-unknown linear
least-squares problem, solved in closed form (all frames at once, by their normal equations).
Default weights: ``w_a = 1``, ``w_l = 1``, ``w_m = 0.1`` (the paper gives none; the input match
must win over the prior in the image plane, while depth has only the prior to go by).

**Joint angles.** Positions do not yet have the prior's limb lengths exactly. From the roots
outwards each limb keeps its solved direction (roll and pitch, in the paper's words) and takes
the prior's length, so the lengths are constant to rounding error. Each limb's rotation from its
rest vector (the prior's first-frame limb) is the prior's own turn of that limb -- which carries
the twist about the limb (yaw) that positions cannot show -- followed by the smallest rotation
taking the prior's limb onto the solved one.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.descriptor import modify_prior, upper_body
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.prior import Prior


@dataclass(frozen=True, eq=False)
class SkeletonProxy:
    """The skeleton proxy.

    Attributes
    ----------
    positions : (T, N, 3) float
        Joint positions, metres; limb lengths constant.
    rest : (K, 3) float
        Each limb's rest vector: the prior's limb on its first frame, at the prior's length.
    rotations : (T, K, 4) float
        Each limb's rotation from rest, unit quaternions ``(x, y, z, w)``.
    solved : (T, N, 3) float
        The least-squares positions (eq. 22) before the lengths are made exact.
    modified : (T, N, 2) float
        ``x^m``, the modified prior seen through ``R`` (metres, image axes).
    """

    positions: NDArray[np.float64]
    rest: NDArray[np.float64]
    rotations: NDArray[np.float64]
    solved: NDArray[np.float64]
    modified: NDArray[np.float64]


@dataclass(frozen=True)
class SkeletonWeights:
    """Weights of eq. 16 (module docstring) and the subspace's size ``P``."""

    input: float = 1.0
    limb: float = 1.0
    prior: float = 0.1
    components: int = 20

    def __post_init__(self) -> None:
        for name in ("input", "limb", "prior"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ProxyError(f"the skeleton's {name} weight must be a number >= 0, got {value!r}")
        if self.prior <= 0:
            raise ProxyError("the skeleton's prior weight must be positive (depth comes from it alone)")
        if isinstance(self.components, bool) or not isinstance(self.components, int) or self.components < 1:
            raise ProxyError("the number of principal components must be at least 1, got "
                             f"{self.components!r}")


def skeleton_proxy(
    markers: Markers,
    prior: Prior,
    R: ArrayLike,
    *,
    upper: ArrayLike | None = None,
    extra: Sequence[Prior] = (),
    weights: SkeletonWeights | None = None,
) -> SkeletonProxy:
    """The skeleton proxy of eq. 11-22.

    Parameters
    ----------
    markers : Markers
        The drawn markers, pixels.
    prior : Prior
        Time-aligned to the markers, metres, +Y up.
    R : (2, 3) float
        The orthographic camera (:func:`~toonmotion.proxy3d.orthographic.camera`).
    upper : (N,) bool, optional
        Upper-body markers; :func:`~toonmotion.proxy3d.descriptor.upper_body` by default.
    extra : sequence of Prior
        Other clips (the same marker names, metres) whose poses join the prior's in the PCA.
    weights : SkeletonWeights, optional

    Returns
    -------
    SkeletonProxy

    Examples
    --------
    The prior drawn exactly comes back, lengths exact:

    >>> from toonmotion.proxy3d.orthographic import camera
    >>> t = np.linspace(0, 1, 6)[:, None]
    >>> P = np.stack([np.hstack([0 * t, 1 + 0 * t, 0 * t]), np.hstack([0 * t, 1.5 + 0 * t, 0 * t]),
    ...               np.hstack([0.3 * np.cos(t), 1.5 + 0.3 * np.sin(t), 0 * t])], axis=1)
    >>> prior = Prior(("hips", "neck", "hand"), [-1, 0, 1], P, fps=12)
    >>> drawn = Markers(prior.names, 100 * P @ camera(0, 0).T + 300, fps=12)
    >>> s = skeleton_proxy(drawn, prior, camera(0, 0))
    >>> float(np.abs(s.positions - P).max()) < 1e-9
    True
    """
    w = weights or SkeletonWeights()
    if tuple(prior.names) != tuple(markers.names) or prior.frame_count != markers.frame_count:
        raise ProxyError("the prior must be aligned to the markers (the same names and frames) first")
    limbs = prior.limbs
    if len(limbs) == 0:
        raise ProxyError("the markers form no limb (no marker has a parent); there is no skeleton to build")
    Rm = np.asarray(R, dtype=float)
    if Rm.shape != (2, 3) or not np.isfinite(Rm).all():
        raise ProxyError(f"the orthographic camera must be a finite 2x3 matrix, got shape {Rm.shape}")
    up = upper_body(prior) if upper is None else np.asarray(upper, dtype=bool)
    X = prior.positions
    modified = modify_prior(X @ Rm.T, markers.positions, limbs, up)
    vectors = X[:, limbs[:, 1]] - X[:, limbs[:, 0]]
    lengths = np.linalg.norm(vectors, axis=-1).mean(axis=0)
    if np.any(lengths <= 0):
        raise ProxyError("a limb of the prior has no length (two markers on one joint); map them to "
                         "different joints")
    mean, V = _subspace(prior, extra, w.components)
    solved = _solve(modified, X, vectors, lengths, limbs, Rm, mean, V, w)
    positions, rotations, rest = _exact_lengths(solved, prior, limbs, lengths)
    return SkeletonProxy(positions=positions, rest=rest, rotations=rotations, solved=solved,
                         modified=modified)


def _subspace(prior, extra, components):
    """Mean ``(3N,)`` and the first principal directions ``(3N, P)`` of the clips' poses."""
    poses = [prior.positions.reshape(prior.frame_count, -1)]
    for other in extra:
        if tuple(other.names) != tuple(prior.names):
            raise ProxyError("every extra clip for the skeleton's subspace needs the prior's markers, in its "
                             "order")
        poses.append(other.positions.reshape(other.frame_count, -1))
    data = np.concatenate(poses)
    mean = data.mean(axis=0)
    _, sing, Vt = np.linalg.svd(data - mean, full_matrices=False)
    keep = min(components, int(np.sum(sing > sing[0] * 1e-12)) if len(sing) and sing[0] > 0 else 0)
    return mean, Vt[:keep].T


def _solve(modified, X, vectors, lengths, limbs, R, mean, V, w):
    """Eq. 16-22 for every frame: ``(T, N, 3)``."""
    T, N = X.shape[:2]
    P = V.shape[1]
    if P == 0:
        return X.copy()
    Vn = V.reshape(N, 3, P)
    # Input match, the same every frame: rows (N, 2) of R X_j.
    A_in = w.input * np.einsum("id,ndp->nip", R, Vn).reshape(2 * N, P)
    b_in = w.input * (modified - (mean.reshape(N, 3) @ R.T)).reshape(T, 2 * N)
    # Limb lengths: (v~ / L) . (X_c - X_p) = (L^2 + |v~|^2) / (2 L), per frame.
    u = vectors / lengths[:, None]                                        # (T, K, 3)
    dV = Vn[limbs[:, 1]] - Vn[limbs[:, 0]]                                # (K, 3, P)
    A_limb = w.limb * np.einsum("tkd,kdp->tkp", u, dV)                    # (T, K, P)
    dmean = mean.reshape(N, 3)[limbs[:, 1]] - mean.reshape(N, 3)[limbs[:, 0]]
    target = (lengths ** 2 + (vectors ** 2).sum(-1)) / (2 * lengths)
    b_limb = w.limb * (target - np.einsum("tkd,kd->tk", u, dmean))
    # Prior: V b = X~ - mean (V has orthonormal columns).
    b_prior = w.prior * (X.reshape(T, -1) - mean) @ V                     # (T, P)
    G = A_in.T @ A_in + np.einsum("tkp,tkq->tpq", A_limb, A_limb) + w.prior ** 2 * np.eye(P)
    rhs = b_in @ A_in + np.einsum("tkp,tk->tp", A_limb, b_limb) + w.prior * b_prior
    coefficients = np.linalg.solve(G, rhs[..., None])[..., 0]
    return (mean + coefficients @ V.T).reshape(T, N, 3)


def _exact_lengths(solved, prior, limbs, lengths):
    """Positions with the prior's lengths, limb rotations from rest and the rest vectors."""
    T = len(solved)
    X = prior.positions
    out = solved.copy()
    prior_vec = X[:, limbs[:, 1]] - X[:, limbs[:, 0]]
    rest = prior_vec[0] / np.linalg.norm(prior_vec[0], axis=-1, keepdims=True) * lengths[:, None]
    quats = np.empty((T, len(limbs), 4))
    for k, (p, c) in enumerate(limbs):  # parents first: out[:, p] is final
        direction = solved[:, c] - solved[:, p]
        norm = np.linalg.norm(direction, axis=-1, keepdims=True)
        fallback = prior_vec[:, k] / np.linalg.norm(prior_vec[:, k], axis=-1, keepdims=True)
        unit = np.where(norm > 1e-12, direction / np.where(norm > 0, norm, 1.0), fallback)
        out[:, c] = out[:, p] + lengths[k] * unit
        turn = _prior_turn(prior, c)
        turned = turn.apply(np.tile(rest[k], (T, 1)))
        quats[:, k] = (_swing(turned, lengths[k] * unit) * turn).as_quat()
    return out, quats, rest


def _prior_turn(prior, child):
    """The prior's turn of the limb ending at ``child`` from its first frame, per frame."""
    T = prior.frame_count
    if prior.turns is None:
        return Rotation.identity(T)
    q = Rotation.from_quat(prior.turns[:, child])
    return q * q[0].inv()


def _swing(a, b):
    """The smallest rotations taking vectors ``a`` onto the directions of ``b``, ``(T, 3)`` each."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1)
    cos = np.clip((a * b).sum(-1), -1, 1)
    angle = np.arctan2(s, cos)
    # Opposite vectors: any axis perpendicular to a.
    other = np.where(np.abs(a[:, :1]) < 0.9, [[1.0, 0, 0]], [[0.0, 1, 0]])
    perpendicular = np.cross(a, other)
    axis = np.where((s > 1e-12)[:, None], axis, perpendicular)
    axis /= np.linalg.norm(axis, axis=-1, keepdims=True)
    return Rotation.from_rotvec(axis * angle[:, None])


def limb_lengths(positions: ArrayLike, limbs: Iterable[Sequence[int]]) -> NDArray[np.float64]:
    """Each limb's length per frame, ``(T, K)``.

    >>> limb_lengths([[[0.0, 0, 0], [3, 4, 0]]], [[0, 1]]).tolist()
    [[5.0]]
    """
    P = np.asarray(positions, dtype=float)
    L = np.asarray(list(limbs), dtype=np.int64).reshape(-1, 2)
    return np.linalg.norm(P[:, L[:, 1]] - P[:, L[:, 0]], axis=-1)
