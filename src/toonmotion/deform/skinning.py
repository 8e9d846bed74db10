"""Multi-weight skinning: each vertex follows a few bones' needles, blended by smooth weights
(the thesis' future work, 7.2 item 3).

The thesis binds every vertex to one bone, so a joint bends only where stage two's band lets
it, and a bent limb shows a crease where two bones' regions meet. Here each vertex follows the
needles of up to :data:`KEEP` bones, each written in that bone's frame as in stage one, and its
stage-one position is the weighted mean of where those needles put it.

**The weights** are Pinocchio's heat-diffusion weights (Baran and Popović, "Automatic rigging and
animation of 3D characters", SIGGRAPH 2007, section 4): for every bone ``b``,
``(K + M H) w_b = M H p_b``, with ``K`` the mesh's cotangent stiffness matrix, ``M`` its lumped
vertex areas, ``p_b`` 1 on the vertices the decomposition gives to ``b`` and 0 elsewhere, and
``H`` the diagonal ``c / d^2`` with ``d`` each vertex's distance to its own bone (``c = 1``). One
factorisation serves every bone. They are smooth, sum to 1 and are 1 on the bones themselves.
Chosen over bounded biharmonic weights (Jacobson et al. 2011), which need a quadratic program
per bone and no maintained solver for it sits in our dependencies, and over plain distance
falloffs, which ignore the shape. Each vertex keeps its :data:`KEEP` largest weights (those below
:data:`SMALLEST` are dropped), renormalised to sum to 1, so the rest pose and any similarity of
the whole skeleton are reproduced exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from toonmotion.deform.needles import needle_coordinates, posed_frames
from toonmotion.errors import MeshError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.geometry.segments import closest_points_on_segments
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton
from toonmotion.shape.mesh import Mesh

# Bones a vertex follows at most, and the smallest weight kept.
KEEP = 4
SMALLEST = 1e-3


@dataclass(frozen=True, eq=False)
class SkinnedNeedles:
    """Each vertex's needles in its few bones' rest frames, and their weights.

    Attributes
    ----------
    bones : (b, 2) int
        ``(parent, child)`` joints of each bone (``skeleton.bones``).
    bone : (n, k) int
        The bones each vertex follows (unused slots repeat a bone with weight 0).
    weight : (n, k) float
        Their weights, >= 0, each row summing to 1.
    t, s : (n, k) float
        The vertex's position along and across each of those bones (as in the needle model).
    rest_length : (b,) float
    rigid : (b,) bool
        Bones of zero rest length; they carry no weight.

    Construction copies the arrays (read-only) and raises ``ValueError`` unless their shapes agree.
    """

    bones: NDArray[np.int64]
    bone: NDArray[np.int64]
    weight: NDArray[np.float64]
    t: NDArray[np.float64]
    s: NDArray[np.float64]
    rest_length: NDArray[np.float64]
    rigid: NDArray[np.bool_]

    def __post_init__(self) -> None:
        bones = frozen_array(self.bones, dtype=np.int64, shape=(None, 2), name="skinned needles' bones")
        bone = frozen_array(self.bone, dtype=np.int64, shape=(None, None), name="skinned needles' bone")
        object.__setattr__(self, "bones", bones)
        object.__setattr__(self, "bone", bone)
        for name in ("weight", "t", "s"):
            object.__setattr__(self, name, frozen_array(getattr(self, name), dtype=np.float64,
                                                        shape=bone.shape, name=f"skinned needles' {name}"))
        for name, dtype in (("rest_length", np.float64), ("rigid", np.bool_)):
            object.__setattr__(self, name, frozen_array(getattr(self, name), dtype=dtype, shape=(len(bones),),
                                                        name=f"skinned needles' {name}"))


def heat_weights(mesh: Mesh, skeleton: Skeleton, bone: NDArray[np.integer]) -> NDArray[np.float64]:
    """Pinocchio's heat-diffusion weights (module docstring), ``(n, b)``: one column per bone of
    ``skeleton``, rows summing to 1, zero for bones of zero length.

    Parameters
    ----------
    mesh : Mesh
    skeleton : Skeleton
    bone : (n,) int
        Each vertex's bone from the decomposition (``Binding.bone``).

    Raises
    ------
    MeshError
        The system cannot be factorised (a degenerate mesh).
    """
    V, F = mesh.V, np.asarray(mesh.F)
    n, b = len(V), len(skeleton.bones)
    K, area = _cotangent_stiffness(V, F), _lumped_areas(V, F)
    A = skeleton.positions[skeleton.bones[:, 0]]
    B = skeleton.positions[skeleton.bones[:, 1]]
    closest, _ = closest_points_on_segments(V, A, B)
    d = np.linalg.norm(V - closest[np.arange(n), bone], axis=1)
    heat = area / np.maximum(d, 0.5 * mesh.spacing) ** 2
    try:
        factor = splu((K + sp.diags(heat)).tocsc())
    except RuntimeError:
        raise MeshError("the mesh's skinning weights cannot be solved: the mesh is degenerate "
                        "(rig the drawing again)") from None
    P = np.zeros((n, b))
    P[np.arange(n), bone] = heat
    W = np.clip(factor.solve(P), 0.0, None)
    W[:, skeleton.bone_lengths <= MIN_BONE_LENGTH] = 0.0
    total = W.sum(axis=1, keepdims=True)
    lost = total[:, 0] <= 0
    W[lost] = 0.0
    W[lost, bone[lost]] = 1.0
    return W / np.where(lost[:, None], 1.0, total)


def skinned_needles(V: NDArray[np.float64], skeleton: Skeleton, weights: NDArray[np.float64]
                    ) -> SkinnedNeedles:
    """Each vertex's :data:`KEEP` heaviest bones (weights below :data:`SMALLEST` dropped, the rest
    renormalised) and its needle in each, from ``weights`` ``(n, b)`` (:func:`heat_weights`)."""
    k = min(KEEP, weights.shape[1])
    order = np.argsort(-weights, axis=1, kind="stable")[:, :k]
    w = np.take_along_axis(weights, order, axis=1)
    w = np.where(w >= SMALLEST, w, 0.0)
    w /= w.sum(axis=1, keepdims=True)
    t, across, length, _, rigid, _ = needle_coordinates(V[:, None, :], skeleton, order)
    return SkinnedNeedles(bones=skeleton.bones, bone=order, weight=w, t=t, s=across, rest_length=length,
                          rigid=rigid)


def skinned_stage_one(model: SkinnedNeedles, positions: NDArray[np.float64], *, preserve_area: bool = True
                      ) -> NDArray[np.float64]:
    """Stage one with blended needles: each vertex at the weighted mean of where its bones'
    needles put it, ``(n, 2)`` (needles shortened by the reciprocal stretch with area
    preservation, as in :func:`~toonmotion.deform.needles.stage_one`)."""
    A, d, normal = posed_frames(model.bones, model.rest_length, positions, preserve_area=preserve_area)
    b = model.bone
    placed = A[b] + model.t[..., None] * d[b] + model.s[..., None] * normal[b]
    return np.einsum("nk,nkj->nj", model.weight, placed)


def _cotangent_stiffness(V, F):
    """The cotangent stiffness matrix ``K`` (positive semi-definite), ``(n, n)``."""
    n = len(V)
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = F[:, (k + 1) % 3], F[:, (k + 2) % 3], F[:, k]
        a, c = V[i] - V[o], V[j] - V[o]
        cross = np.abs(a[:, 0] * c[:, 1] - a[:, 1] * c[:, 0])
        cot = np.einsum("ij,ij->i", a, c) / np.maximum(cross, 1e-12)
        w = 0.5 * cot
        rows += [i, j, i, j]
        cols += [j, i, i, j]
        vals += [-w, -w, w, w]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def _lumped_areas(V, F):
    """A third of the area of the triangles round each vertex, ``(n,)``."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    return np.bincount(F.ravel(), np.repeat(area / 3, 3), minlength=len(V))
