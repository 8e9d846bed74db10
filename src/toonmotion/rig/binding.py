"""Decomposition: which bone each mesh vertex follows (thesis 3.3, eq. 3.1, fig. 3.6; 6.3a).

Two rules (``decompose(rule=...)``). The default, ``"geodesic"``, attaches each vertex to the
bone nearest *through the drawing* (:func:`geodesic_bones`). The thesis' rule, ``"straight"``,
attaches it to the nearest bone whose connecting segment (from the vertex to its closest point
on the bone) stays inside the silhouette, so an arm never grabs the body across the gap between
them; when no bone can be reached that way (annotated bones often run just outside a thin limb)
the vertex takes the bone that minimises its distance plus ``OUTSIDE_PENALTY`` times the length
of the segment outside the figure, and :attr:`Binding.fallback` records it.

Triangles whose three vertices share a bone are *interior* triangles, the rest *joint*
triangles. Vertices are *silhouette* (on the outline), *interior* (every triangle around them
is interior) or *joint* vertices.

Corrections (6.3a) attach every vertex inside a closed curve to a chosen bone. A binding keeps
its corrections, not only their result, so they can be replayed on a new mesh.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import EditError, SkeletonError, ToonmotionError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.geometry.polygon import points_in_polygon
from toonmotion.geometry.segments import closest_points_on_segments
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton
from toonmotion.shape.mesh import Mesh

SILHOUETTE, INTERIOR, JOINT = 0, 1, 2
VERTEX_KINDS = ("silhouette", "interior", "joint")

# Segment samples this close (pixels) to the vertex are not tested: outline vertices may sit a
# fraction of a pixel outside the mask's pixel centres.
_VERTEX_SLACK = 1.5

# Pixels of segment outside the figure count this many times their length in a fallback choice.
OUTSIDE_PENALTY = 4.0
# The geodesic rule links each vertex straight to this many nearest bones (the rest it reaches
# through the mesh), and drops links more than LINK_OUTSIDE mesh spacings outside the figure.
NEAREST_BONES = 6
LINK_OUTSIDE = 2.0
# Each pixel a vertex lies past a bone's end adds this much to the geodesic rule's link cost.
BEYOND_END = 0.5
# The geodesic rule measures from this fraction of each limb's half-thickness out from its bone.
SURFACE = 0.5
_SCAN = 3

RULES = ("straight", "geodesic")


class CorrectionError(ToonmotionError):
    """A decomposition correction is malformed."""


@dataclass(frozen=True, eq=False)
class Correction:
    """Attach every vertex inside ``curve`` (a closed ``(k, 2)`` polyline) to bone ``bone``.

    Construction copies the curve (read-only) and raises :class:`CorrectionError` unless it is
    at least 3 finite points and ``bone`` is a string.
    """

    curve: NDArray[np.float64]
    bone: str

    def __post_init__(self) -> None:
        curve = _correction_curve(self.curve)
        if not isinstance(self.bone, str):
            raise CorrectionError(f"a correction names its bone by a string, got {self.bone!r}")
        object.__setattr__(self, "curve", curve)


def _correction_curve(curve: ArrayLike) -> NDArray[np.float64]:
    try:
        P = np.asarray(curve, dtype=float)
    except (TypeError, ValueError):
        raise CorrectionError("a correction curve needs at least 3 (x, y) points") from None
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 3:
        raise CorrectionError("a correction curve needs at least 3 (x, y) points")
    if not np.all(np.isfinite(P)):
        raise CorrectionError("a correction curve has non-finite coordinates")
    return frozen_array(P, dtype=np.float64, name="a correction curve", error=CorrectionError)


@dataclass(frozen=True, eq=False)
class Binding:
    """Vertex-to-bone attachment and the classification that follows from it.

    Attributes
    ----------
    bone : (n,) int
        Bone of each vertex, an index into ``skeleton.bones``.
    fallback : (n,) bool
        Vertices that could reach no bone without crossing the outline and took the nearest.
    corrections : tuple of Correction
        Corrections applied after the automatic decomposition, in order.
    joint_triangle : (m,) bool
        True for joint triangles (vertices on more than one bone).
    vertex_kind : (n,) int
        :data:`SILHOUETTE`, :data:`INTERIOR` or :data:`JOINT`.
    joint_area : (n,) bool
        Vertices of joint triangles (joint vertices and the silhouette vertices among them):
        the joint areas that stage two of the deformation works on.

    Construction copies the arrays (read-only) and raises ``ValueError`` unless every
    per-vertex array has ``n`` entries, bones are >= 0 and kinds are one of the three.
    :func:`binding_from_bones` is how the library builds one.
    """

    bone: NDArray[np.int64]
    fallback: NDArray[np.bool_]
    corrections: tuple[Correction, ...]
    joint_triangle: NDArray[np.bool_]
    vertex_kind: NDArray[np.int8]
    joint_area: NDArray[np.bool_]

    def __post_init__(self) -> None:
        bone = frozen_array(self.bone, dtype=np.int64, shape=(None,), name="a binding's bone")
        n = len(bone)
        if n and bone.min() < 0:
            raise ValueError("a binding's bone indices must be >= 0")
        kind = frozen_array(self.vertex_kind, dtype=np.int8, shape=(n,), name="a binding's vertex_kind")
        if n and (kind.min() < SILHOUETTE or kind.max() > JOINT):
            raise ValueError(f"a binding's vertex kinds must be {SILHOUETTE}, {INTERIOR} or {JOINT}")
        corrections = tuple(self.corrections)
        if not all(isinstance(c, Correction) for c in corrections):
            raise TypeError("a binding's corrections must be Correction objects")
        object.__setattr__(self, "bone", bone)
        object.__setattr__(self, "vertex_kind", kind)
        object.__setattr__(self, "corrections", corrections)
        for name, shape in (("fallback", (n,)), ("joint_triangle", (None,)), ("joint_area", (n,))):
            flags = frozen_array(getattr(self, name), dtype=np.bool_, shape=shape, name=f"a binding's {name}")
            object.__setattr__(self, name, flags)


def decompose(
    mesh: Mesh, skeleton: Skeleton, mask: NDArray[np.bool_], *, corrections: Iterable[Correction] = (),
    rule: str = "geodesic",
) -> Binding:
    """Attach every vertex of ``mesh`` to a bone of ``skeleton`` (eq. 3.1).

    Parameters
    ----------
    mesh : Mesh
    skeleton : Skeleton
    mask : (h, w) bool
        The silhouette's mask, used to test that a connecting segment stays inside.
    corrections : sequence of Correction
        Applied in order after the automatic decomposition.
    rule : {"straight", "geodesic"}
        ``"straight"``: the thesis's rule (module docstring). ``"geodesic"``: the nearest bone
        *through the drawing* (:func:`geodesic_bones`, the default); no vertex needs the
        fallback.

    Returns
    -------
    Binding

    Raises
    ------
    SkeletonError
        No bone of non-zero length; with ``"geodesic"``, a part of the mesh no bone reaches.
    """
    if rule not in RULES:
        raise SkeletonError(f"the decomposition rule must be one of {', '.join(RULES)}, got {rule!r}")
    if rule == "geodesic":
        bone, fallback = geodesic_bones(mesh, skeleton, mask), np.zeros(len(mesh.V), dtype=bool)
    else:
        bone, fallback = _straight_bones(mesh, skeleton, mask)
    binding = binding_from_bones(mesh, bone, fallback, ())
    for correction in corrections:
        binding = attach_inside(binding, mesh, skeleton, correction.curve, correction.bone)
    return binding


def _straight_bones(mesh, skeleton, mask):
    """The thesis's rule: ``(bone per vertex, fallback per vertex)``."""
    A, B, usable = _bone_segments(skeleton)
    closest, distance = closest_points_on_segments(mesh.V, A[usable], B[usable])
    order = np.argsort(distance, axis=1, kind="stable")
    n = len(mesh.V)
    chosen = np.full(n, -1)
    for rank in range(order.shape[1]):
        todo = np.flatnonzero(chosen < 0)
        if len(todo) == 0:
            break
        candidate = order[todo, rank]
        reach = _outside_length(mesh.V[todo], closest[todo, candidate], mask) == 0
        chosen[todo[reach]] = candidate[reach]
    fallback = np.flatnonzero(chosen < 0)
    if len(fallback):
        k = closest.shape[1]
        outside = _outside_length(
            np.repeat(mesh.V[fallback], k, axis=0), closest[fallback].reshape(-1, 2), mask
        ).reshape(-1, k)
        chosen[fallback] = np.argmin(distance[fallback] + OUTSIDE_PENALTY * outside, axis=1)
    return np.flatnonzero(usable)[chosen], np.isin(np.arange(n), fallback)


def attach_inside(binding: Binding, mesh: Mesh, skeleton: Skeleton, curve: ArrayLike, bone: str) -> Binding:
    """Attach every vertex inside a closed curve to one bone (decomposition correction, 6.3a).

    Parameters
    ----------
    binding : Binding
    mesh : Mesh
    skeleton : Skeleton
    curve : (k, 2) float
        Closed polyline (the last point joins the first), k >= 3.
    bone : str
        Name of the bone, i.e. of its child joint.

    Returns
    -------
    Binding
        A new binding with the correction appended to ``corrections``.
    """
    curve = _correction_curve(curve)
    names = skeleton.bone_names
    if bone not in names:
        raise SkeletonError(f"no bone is called {bone!r}; the bones are: {', '.join(names)}")
    inside = points_in_polygon(mesh.V, [curve])
    if not inside.any():
        raise EditError("the curve holds no vertex of the mesh: draw it round the part to attach")
    new_bone = binding.bone.copy()
    new_bone[inside] = names.index(bone)
    corrections = (*binding.corrections, Correction(curve=curve, bone=bone))
    return binding_from_bones(mesh, new_bone, binding.fallback, corrections)


def classify(mesh: Mesh, bone: NDArray[np.integer]) -> tuple[NDArray[np.bool_], NDArray[np.int8]]:
    """Joint triangles and vertex kinds for a vertex-to-bone map (fig. 3.6).

    Returns
    -------
    joint_triangle : (m,) bool
    vertex_kind : (n,) int
    """
    b = bone[mesh.F]
    joint_triangle = (b[:, 0] != b[:, 1]) | (b[:, 1] != b[:, 2])
    kind = np.full(len(mesh.V), INTERIOR, dtype=np.int8)
    kind[np.unique(mesh.F[joint_triangle])] = JOINT
    kind[: mesh.n_outline] = SILHOUETTE
    return joint_triangle, kind


def binding_from_bones(
    mesh: Mesh, bone: ArrayLike, fallback: ArrayLike, corrections: Iterable[Correction] = ()
) -> Binding:
    """A :class:`Binding` from a vertex-to-bone map, classified (used when loading)."""
    bones = np.asarray(bone)
    joint_triangle, kind = classify(mesh, bones)
    joint_area = np.zeros(len(bones), dtype=bool)
    joint_area[mesh.F[joint_triangle].ravel()] = True
    return Binding(
        bone=bones,
        fallback=np.asarray(fallback, dtype=bool),
        corrections=tuple(corrections),
        joint_triangle=joint_triangle,
        vertex_kind=kind,
        joint_area=joint_area,
    )


def geodesic_bones(mesh: Mesh, skeleton: Skeleton, mask: NDArray[np.bool_]) -> NDArray[np.int64]:
    """Each vertex's bone by the shortest way to it through the drawing (eq. 3.1 with distance
    inside the shape), ``(n,)`` indices into ``skeleton.bones``.

    Each vertex is linked straight to its :data:`NEAREST_BONES` nearest bones (at the nearest
    point of each), a link costing its length plus :data:`OUTSIDE_PENALTY` times its pixels
    outside the mask; links more than :data:`LINK_OUTSIDE` mesh spacings outside are dropped. One
    multi-source Dijkstra (``scipy.sparse.csgraph``) over those links and the mesh's edges then
    gives every vertex the bone its cheapest way starts from. Where a bone can be seen from a
    vertex the way is the straight segment (the thesis's rule, exactly); where it cannot (a curled
    pigtail, a thin curved arm whose annotated bone runs just outside it) the way goes round
    through the mesh, so a limb is claimed along its own length, never across a gap. Every way
    is a shortest path, so each bone's region is connected to the vertices that see the bone.

    Raises
    ------
    SkeletonError
        A bone lies wholly outside the drawing, or some vertices are reached by no bone (a part
        of the drawing apart from every bone).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    A, B, usable = _bone_segments(skeleton)
    _check_bones_touch_the_drawing(skeleton, A, B, usable, mask, mesh.spacing)
    V, F = mesh.V, np.asarray(mesh.F)
    n, bones = len(V), np.flatnonzero(usable)
    closest, distance = closest_points_on_segments(V, A[bones], B[bones])
    k = min(NEAREST_BONES, len(bones))
    nearest = np.argpartition(distance, k - 1, axis=1)[:, :k] if k < len(bones) else \
        np.broadcast_to(np.arange(k), (n, k))
    vertex = np.repeat(np.arange(n), k)
    bone = nearest.ravel()
    foot = closest[vertex, bone]
    outside = _outside_length(V[vertex], foot, mask)
    # A link may leave the figure only where its bone does (a bone drawn just off its limb),
    # never to cross a gap between limbs.
    h, w = mask.shape
    fx = np.clip(np.rint(foot[:, 0]), 0, w - 1).astype(np.int64)
    fy = np.clip(np.rint(foot[:, 1]), 0, h - 1).astype(np.int64)
    keep = (outside == 0) | (~mask[fy, fx] & (outside <= LINK_OUTSIDE * mesh.spacing))
    vertex, bone = vertex[keep], bone[keep]
    # How far past the bone's ends the vertex lies, along the bone: near a joint a vertex beside
    # one bone is nearly as near the next one's end, and the bone it lies beside should win.
    d = B[bones] - A[bones]
    along = np.einsum("ij,ij->i", V[vertex] - A[bones][bone], d[bone]) / np.einsum("ij,ij->i", d, d)[bone]
    beyond = np.maximum(np.maximum(-along, along - 1), 0) * np.linalg.norm(d, axis=1)[bone]
    # Measured from the limb's surface rather than its bone (less the half-thickness; every cost
    # is shifted by the thickest so all stay >= 0): a vertex of a wide head or belly stays with
    # its own bone though a thin limb's joint is a little nearer.
    radius = _limb_half_thickness(skeleton, mask, mesh.spacing)[bones]
    cost = distance[vertex, bone] + OUTSIDE_PENALTY * outside[keep] + BEYOND_END * beyond \
        + SURFACE * (radius.max() - radius[bone])
    edges = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1), axis=0)
    length = np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1)
    rows = np.concatenate([edges[:, 0], edges[:, 1], n + bone])
    cols = np.concatenate([edges[:, 1], edges[:, 0], vertex])
    weight = np.concatenate([length, length, cost]) + 1e-12  # csgraph drops zero weights
    size = n + len(bones)
    graph = coo_matrix((weight, (rows, cols)), shape=(size, size)).tocsr()
    reached, _, source = dijkstra(graph, indices=n + np.arange(len(bones)), min_only=True,
                                  return_predecessors=True)
    lost = np.flatnonzero(~np.isfinite(reached[:n]))
    if len(lost):
        raise SkeletonError(f"{len(lost)} mesh vertices (a part of the drawing around "
                            f"{tuple(np.round(V[lost[0]]).astype(int))}) are reached by no bone; give that "
                            "part a bone or leave it out of the mask")
    return bones[source[:n] - n].astype(np.int64)


def _check_bones_touch_the_drawing(skeleton, A, B, usable, mask, spacing):
    """SkeletonError naming a usable bone none of whose points is within ``LINK_OUTSIDE``
    spacings of the mask: it would claim vertices it is nowhere near."""
    from scipy.ndimage import distance_transform_edt

    h, w = mask.shape
    far = distance_transform_edt(~np.pad(mask, 1))[1:-1, 1:-1]
    for b in np.flatnonzero(usable):
        k = int(np.ceil(np.linalg.norm(B[b] - A[b]))) + 1
        P = A[b] + np.linspace(0, 1, k)[:, None] * (B[b] - A[b])
        x, y = np.rint(P[:, 0]).astype(np.int64), np.rint(P[:, 1]).astype(np.int64)
        on = (x >= 0) & (x < w) & (y >= 0) & (y < h)
        if not on.any() or far[y[on], x[on]].min() > LINK_OUTSIDE * spacing:
            raise SkeletonError(f"bone {skeleton.bone_names[b]!r} lies wholly outside the drawing; move its "
                                "joints onto the figure")


def _bone_segments(skeleton):
    bones = skeleton.bones
    A = skeleton.positions[bones[:, 0]]
    B = skeleton.positions[bones[:, 1]]
    usable = np.linalg.norm(B - A, axis=1) > MIN_BONE_LENGTH
    if not usable.any():
        raise SkeletonError(
            "the skeleton has no bone of non-zero length; give at least two joints at "
            "different places, one the parent of the other"
        )
    return A, B, usable


def _outside_length(start, end, mask):
    """For each segment start -> end, about how many pixels of it lie outside the mask."""
    h, w = mask.shape
    length = np.linalg.norm(end - start, axis=1)
    count = np.ceil(length).astype(np.int64) + 1
    seg = np.repeat(np.arange(len(start)), count)
    offset = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    t = offset / np.maximum(np.repeat(count - 1, count), 1)
    p = start[seg] + t[:, None] * (end[seg] - start[seg])
    tested = t * np.repeat(length, count) > _VERTEX_SLACK
    x = np.rint(p[:, 0]).astype(np.int64)
    y = np.rint(p[:, 1]).astype(np.int64)
    on_image = (x >= 0) & (x < w) & (y >= 0) & (y < h)
    inside = np.zeros(len(p), dtype=bool)
    inside[on_image] = mask[y[on_image], x[on_image]]
    return np.bincount(seg[tested & ~inside], minlength=len(start))


def bone_half_thickness(skeleton: Skeleton, mask: NDArray[np.bool_], *, floor: float) -> NDArray[np.float64]:
    """Each bone's limb half-thickness: the median distance to the outline along the middle half
    of the bone, at least ``floor`` (a bone outside its limb), ``(b,)`` pixels."""
    from scipy.ndimage import distance_transform_edt

    distance = distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    h, w = mask.shape
    bones = skeleton.bones
    A, B = skeleton.positions[bones[:, 0]], skeleton.positions[bones[:, 1]]
    t = np.linspace(0.25, 0.75, 9)
    P = A[:, None] + t[None, :, None] * (B - A)[:, None]
    x = np.clip(np.rint(P[..., 0]), 0, w - 1).astype(np.int64)
    y = np.clip(np.rint(P[..., 1]), 0, h - 1).astype(np.int64)
    return np.maximum(np.median(distance[y, x], axis=1), floor)


def _limb_half_thickness(skeleton, mask, spacing):
    """Each bone's limb half-thickness wherever the bone runs in it: the largest distance to the
    outline found across the bone (within ``SCAN`` spacings each side) along its middle half, the
    median over the bone, at least ``spacing``. A bone drawn along one side of its limb still
    measures the whole limb."""
    from scipy.ndimage import distance_transform_edt

    distance = distance_transform_edt(np.pad(mask, 1))[1:-1, 1:-1]
    h, w = mask.shape
    bones = skeleton.bones
    A, B = skeleton.positions[bones[:, 0]], skeleton.positions[bones[:, 1]]
    d = B - A
    normal = np.stack([-d[:, 1], d[:, 0]], axis=1) / np.maximum(np.linalg.norm(d, axis=1), 1e-12)[:, None]
    t = np.linspace(0.25, 0.75, 9)
    across = np.linspace(-_SCAN * spacing, _SCAN * spacing, 4 * _SCAN + 1)
    P = (A[:, None, None] + t[None, :, None, None] * d[:, None, None]
         + across[None, None, :, None] * normal[:, None, None])
    x = np.clip(np.rint(P[..., 0]), 0, w - 1).astype(np.int64)
    y = np.clip(np.rint(P[..., 1]), 0, h - 1).astype(np.int64)
    return np.maximum(np.median(distance[y, x].max(axis=2), axis=1), spacing)
