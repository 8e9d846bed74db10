"""Fine tuning a deformed character: sketch curves and point dragging (thesis 3.5, fig. 3.11-3.12).

Both edits work on a deformed mesh ``U`` (the result of :meth:`Deformer.deform`, drawing pixels)
and return a new one. Some vertices are *moved* to exact targets; a neighbourhood around them
*follows* through the stage-two energy (eq. 3.8, :class:`JointSolver`); every other vertex keeps
its position bit for bit. The thesis describes the edits in a paragraph each and leaves these
choices open:

* **The rest shape of the follow solve is ``U`` itself**, not the drawing. An edit then bends
  the neighbourhood as rigidly as possible from its *current* shape: a region the edit does not
  push is at zero energy and stays exactly where it is (a no-op edit is a no-op), and a bent
  elbow does not spring back towards the drawing. The edge term is always the ``"rigid"`` form,
  whatever the deformer's setting: its triangles turn as a whole and so do not flip. One caveat:
  where ``U`` already has folded triangles, the mean value term (eq. 3.6, built from unsigned
  angles) is not zero at ``U``, so a solve whose free vertices reach them moves them a little
  even when no target moves.
* **The neighbourhood** is every vertex within ``radius`` px of a moved vertex, measured along
  mesh edges in ``U`` (geodesic, so a drag on one leg does not pull the other leg lying next to
  it); by default ``max(4 h, 2 * largest move)`` with ``h`` the mesh spacing: a few triangles
  round a small touch-up, and a region twice as wide as a large move, to spread its bend over.
* **Point dragging** picks the vertex nearest each start point, inside or on the outline (a
  facial feature is inside), within ``max(2 h, 3)`` px. A dragged vertex in a joint area frees
  its connected joint area as well, so the joint bends with it as in stage two, but only within
  :data:`JOINT_REACH` times the smaller of a joint width (the joint area's reach round the
  joints of the vertex's bone, :attr:`Deformer.joint_width_px
  <toonmotion.deform.deformer.Deformer>`) and the default follow radius along mesh edges. So a
  figure whose joint areas join up into most of its body (the bundled character's cover 1,118
  of its 1,517 vertices, its neck joint's reach is 141 px) does not move as a whole under a
  small drag, a larger drag takes more of the joint along, and nothing farther moves at all.
* **Sketch curves** (fig. 3.11): ``S0`` and ``Sn`` are the outline vertices nearest the curve's
  first and last points; they must lie on one outline loop and differ. Of the loop's two arcs
  between them, the one lying closer to the curve on average is re-shaped. Each arc vertex keeps
  its needle's *current* direction, from its foot on its posed bone to the vertex, and slides
  along it onto the curve ("keep the angle, change the length"). The current direction, rather
  than the needle's rest angle, is used because stage two moves vertices off their needles: a
  curve drawn exactly along the outline then changes nothing. The foot is the nearest point of
  the bone to the rest vertex (``t`` clipped to ``[0, 1]``), so past a bone's end (a hand, a
  head) needles fan out from the end joint; vertices of zero-length bones use the bone's start.
  Where the needle line crosses the curve several times, the crossing nearest the vertex's
  current distance along the needle wins (needle parameter nearest 1). Where it misses the
  curve, which happens near the curve's ends and in hollows whose needles run parallel to it,
  the vertex goes to the point at its own arc-length fraction of the arc along the curve, so
  the arc's vertices keep their order along the curve.
"""

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

from toonmotion.deform.joint_solve import JointSolver
from toonmotion.errors import EditError
from toonmotion.geometry.segments import arc_lengths, closest_points_on_segments, resample_by_arc_length
from toonmotion.rig.pose import check_pose
from toonmotion.shape.mesh import Mesh, unique_edges

# A drag frees the joint area it is in up to this many joint widths away along mesh edges.
JOINT_REACH = 2.0
# A sketch curve reshapes the outline stretch between its ends; one that stretch would have to be
# folded onto, more than this many times the curve's length, is refused: its ends were drawn either
# side of a limb (a short stroke by a cat's tail crushed the whole tail onto it).
MAX_SHORTENING = 3.0
# The follow solve runs once per edit, not per frame, so it iterates further than a pose does.
_MAX_ITERATIONS = 100
_TOLERANCE = 1e-6
# Curve points closer than this (px) to the previous one are dropped as repeats.
_REPEAT = 1e-9
# A needle shorter than this (px) has no direction; the bone's normal is used instead.
_TINY_NEEDLE = 1e-9
# Needle-curve crossings this far (as a fraction of a segment) past a segment's ends still count,
# so a vertex lying exactly on a curve point is found despite rounding.
_SLACK = 1e-9


def follow(mesh, U, index, targets, *, radius=None, also_free=None, weights=(1.0, 1.0, 1.0)):
    """Move some vertices of a deformed mesh to targets; their neighbourhood follows.

    Parameters
    ----------
    mesh : Mesh
        The character's mesh (its triangles, outline and spacing are used, not its rest ``V``).
    U : (n, 2) float
        Deformed vertices, (x, y) drawing pixels, y down.
    index : (s,) int
        Vertices to move; distinct.
    targets : (s, 2) float
        Where they go, same frame as ``U``.
    radius : float, optional
        Vertices within this geodesic distance (px along mesh edges in ``U``) of a moved vertex
        follow. Default ``max(4 * mesh.spacing, 2 * largest move)``.
    also_free : (n,) bool, optional
        Further vertices that follow, wherever they are.
    weights : (3,) float
        Stage two's ``w1, w2, w3`` (:class:`JointSolver`).

    Returns
    -------
    (n, 2) float
        New vertices: ``index`` at ``targets``, the followers solved with ``U`` as the rest
        shape, every other vertex exactly as in ``U``.

    Examples
    --------
    A strip of four squares; pulling its right end up bends the strip near it only.

    >>> V = np.array([[x, y] for y in (0.0, 1.0) for x in range(5)])
    >>> F = np.array([[i, i + 5, i + 1] for i in range(4)] + [[i + 1, i + 5, i + 6] for i in range(4)])
    >>> mesh = Mesh(V=V, F=F, boundary=(np.r_[0, 5:10, 4:0:-1],), spacing=1.0)
    >>> U = follow(mesh, V, [4], [[4.0, -0.5]], radius=2.5)
    >>> U[4].tolist(), bool(np.all(U[[0, 5]] == V[[0, 5]])), bool(np.all(U[[3, 9]] != V[[3, 9]]))
    ([4.0, -0.5], True, True)
    """
    U = _check_vertices(mesh, U)
    index, targets = _check_moves(U, index, targets)
    n = len(U)
    if also_free is not None:
        also_free = np.asarray(also_free)
        if also_free.shape != (n,) or also_free.dtype != bool:
            raise EditError(f"also_free must be ({n},) bool, one flag per vertex; "
                            f"got shape {also_free.shape} of {also_free.dtype}")
    if len(index) == 0:
        return U.copy()
    move = float(np.hypot(*(targets - U[index]).T).max())
    if radius is None:
        radius = _default_radius(mesh, move)
    elif not (np.isscalar(radius) and np.isfinite(radius) and radius >= 0):
        raise EditError(f"the follow radius must be a finite number of pixels >= 0, got {radius!r}")
    free = _geodesic_near(mesh.F, U, index, float(radius))
    if also_free is not None:
        free |= also_free
    free[index] = False
    start = U.copy()
    start[index] = targets
    if not free.any():
        return start
    rest = Mesh(V=U, F=mesh.F, boundary=mesh.boundary, spacing=mesh.spacing)
    solved = JointSolver(rest, free, weights=weights).solve(start, max_iterations=_MAX_ITERATIONS,
                                                             tolerance=_TOLERANCE).U
    start[free] = solved[free]
    return start


def sketch_targets(mesh, needles, positions, U, curve):
    """Where a sketch curve puts the outline stretch it is drawn along (fig. 3.11).

    Parameters
    ----------
    mesh : Mesh
    needles : NeedleModel
        The character's needles (:attr:`Deformer.needles`).
    positions : (j, 2) float
        The pose's joint positions, which place the bones the needles hang from.
    U : (n, 2) float
        Deformed vertices, (x, y) drawing pixels, y down.
    curve : (k, 2) float
        The drawn polyline, ``k >= 2``, same frame as ``U``; drawn from ``S0``'s end to ``Sn``'s.

    Returns
    -------
    index : (s,) int
        The outline arc from ``S0`` to ``Sn``, in order along the curve.
    targets : (s, 2) float
        Each arc vertex's point on the curve, along its needle.
    """
    U = _check_vertices(mesh, U)
    C = _check_curve(curve)
    positions = np.asarray(positions, dtype=float)
    joints = int(needles.bones.max()) + 1
    if positions.ndim != 2 or positions.shape[1] != 2 or len(positions) < joints \
            or not np.all(np.isfinite(positions)):
        raise EditError(f"joint positions must be a finite ({joints}, 2) array, got shape {positions.shape}; "
                        "pass the pose's positions")
    arc = _arc_along(mesh, U, C)
    targets = _onto_curve(U[arc], _feet(needles, positions, arc), C)
    return arc, targets


def tune_with_curve(deformer, pose, U, curve, *, radius=None):
    """Re-shape the outline along a sketch curve; its neighbourhood follows.

    :func:`sketch_targets`, then :func:`follow` with the deformer's stage-two weights.

    Parameters
    ----------
    deformer : Deformer
    pose : Pose
        The pose ``U`` was deformed into.
    U : (n, 2) float
        Deformed vertices, (x, y) drawing pixels, y down.
    curve : (k, 2) float
        The drawn polyline, same frame as ``U``.
    radius : float, optional
        See :func:`follow`.

    Returns
    -------
    (n, 2) float
        New vertices.
    """
    check_pose(deformer.character.skeleton, pose)
    mesh = deformer.character.mesh
    index, targets = sketch_targets(mesh, deformer.needles, pose.positions, U, curve)
    return follow(mesh, U, index, targets, radius=radius, weights=deformer.settings.weights)


def drag_points(deformer, U, start, end, *, radius=None):
    """Drag vertices of a deformed mesh; their neighbourhood and joint areas follow.

    Parameters
    ----------
    deformer : Deformer
    U : (n, 2) float
        Deformed vertices, (x, y) drawing pixels, y down.
    start, end : (k, 2) float
        Where each drag starts and ends. A start picks the vertex of ``U`` nearest it, within
        ``max(2 * spacing, 3)`` px; each vertex may be dragged once.
    radius : float, optional
        See :func:`follow`.

    Returns
    -------
    (n, 2) float
        New vertices: each dragged vertex exactly at its end point; nothing farther than
        ``radius`` and :data:`JOINT_REACH` joint widths from the dragged vertices (along mesh
        edges) moves.
    """
    mesh = deformer.character.mesh
    U = _check_vertices(mesh, U)
    start, end = _check_points(start, "drag start"), _check_points(end, "drag end")
    if start.shape != end.shape:
        raise EditError(f"got {len(start)} drag starts but {len(end)} ends; give one end per start")
    distance, index = cKDTree(U).query(start)
    reach = mesh.pick_reach
    far = np.flatnonzero(distance > reach)
    if len(far):
        x, y = start[far[0]]
        raise EditError(f"no vertex within {reach:.1f} px of ({x:.1f}, {y:.1f}); start a drag on the figure")
    vertex, first, count = np.unique(index, return_index=True, return_counts=True)
    if (count > 1).any():
        v = vertex[count > 1][0]
        a, b = np.flatnonzero(index == v)[:2]
        raise EditError(f"drags {a} and {b} both start at vertex {v}; drag each vertex once")
    joint = _joint_areas_touched(mesh.F, deformer.free, index)
    if joint.any():
        width = float(deformer.joint_width_px[deformer.needles.bone[index]].max())
        reach = JOINT_REACH * min(width, _default_radius(mesh, float(np.hypot(*(end - U[index]).T).max())))
        joint &= _geodesic_near(mesh.F, U, index, reach)
    return follow(mesh, U, index, end, radius=radius, also_free=joint, weights=deformer.settings.weights)


# --- checks -------------------------------------------------------------------------------


def _check_vertices(mesh, U):
    U = np.asarray(U, dtype=float)
    if U.shape != mesh.V.shape:
        raise EditError(f"deformed vertices must be {mesh.V.shape} for this mesh, got {U.shape}; "
                        "pass the character's deformed U")
    if not np.all(np.isfinite(U)):
        raise EditError("the deformed vertices contain NaN or infinity; deform the pose again")
    return U


def _check_moves(U, index, targets):
    index = np.asarray(index)
    targets = np.asarray(targets, dtype=float)
    if index.ndim != 1 or (len(index) and not np.issubdtype(index.dtype, np.integer)):
        raise EditError(f"vertex indices must be a 1-D array of whole numbers, got {index.dtype} "
                        f"of shape {index.shape}")
    index = index.astype(np.int64)
    if targets.shape != (len(index), 2):
        raise EditError(f"targets must be ({len(index)}, 2), one point per moved vertex; got {targets.shape}")
    if not np.all(np.isfinite(targets)):
        raise EditError("the targets contain NaN or infinity; give finite points")
    if ((index < 0) | (index >= len(U))).any():
        raise EditError(f"vertex indices must be between 0 and {len(U) - 1}, "
                        f"got {index.min()}..{index.max()}")
    if len(np.unique(index)) != len(index):
        raise EditError("a vertex is moved twice; give each vertex one target")
    return index, targets


def _check_points(points, what):
    try:
        points = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise EditError(f"a {what} must be (x, y) numbers; got {points!r}") from None
    if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
        raise EditError(f"{what} points must be a (k, 2) array with k >= 1, got shape {points.shape}")
    if not np.all(np.isfinite(points)):
        raise EditError(f"a {what} point is NaN or infinite; give finite (x, y) pixels")
    return points


def _check_curve(curve):
    """The curve as ``(k, 2)`` float without consecutive repeats, ``k >= 2``."""
    try:
        C = np.asarray(curve, dtype=float)
    except (TypeError, ValueError):
        raise EditError("a sketch curve must be (x, y) points; draw it again") from None
    if C.ndim != 2 or C.shape[1] != 2:
        raise EditError(f"a sketch curve must be a (k, 2) array of points, got shape {C.shape}")
    if len(C) < 2:
        raise EditError(f"a sketch curve needs at least two points, got {len(C)}; draw a longer stroke")
    if not np.all(np.isfinite(C)):
        raise EditError("the sketch curve has NaN or infinite points; draw it again")
    step = np.hypot(*np.diff(C, axis=0).T)
    C = C[np.r_[True, step > _REPEAT]]
    if len(C) < 2:
        raise EditError("the sketch curve's points are all at one place; draw a stroke along the outline")
    return C


# --- sketch curves ------------------------------------------------------------------------------


def _arc_along(mesh, U, C):
    """The outline arc ``S0 .. Sn`` the curve ``C`` is drawn along, ``(s,)`` int, in curve order."""
    loops = mesh.boundary
    outline = np.concatenate(loops)
    loop_of = np.repeat(np.arange(len(loops)), [len(loop) for loop in loops])
    place = np.concatenate([np.arange(len(loop)) for loop in loops])
    distance, nearest = cKDTree(U[outline]).query(C[[0, -1]])
    limit = max(4.0 * mesh.spacing, 0.5 * float(np.hypot(*np.diff(C, axis=0).T).sum()))
    for d, end in zip(distance, ("starts", "ends"), strict=True):
        if d > limit:
            raise EditError(f"the sketch curve {end} {d:.1f} px from the outline (at most {limit:.1f} px); "
                            "draw it near the outline")
    if loop_of[nearest[0]] != loop_of[nearest[1]]:
        raise EditError("the sketch curve's ends are near different outline loops; draw it along one "
                        "stretch of outline")
    if nearest[0] == nearest[1]:
        raise EditError("the curve's ends meet the outline at one vertex; draw it along the part to change")
    loop = loops[loop_of[nearest[0]]]
    a, b = place[nearest]
    size = len(loop)
    forward = loop[(a + np.arange((b - a) % size + 1)) % size]
    backward = loop[(a - np.arange((a - b) % size + 1)) % size]
    A, B = C[:-1], C[1:]
    mean = [closest_points_on_segments(U[arc], A, B)[1].min(axis=1).mean() for arc in (forward, backward)]
    arc = forward if mean[0] <= mean[1] else backward
    arc_length, curve_length = float(arc_lengths(U[arc])[-1]), float(arc_lengths(C)[-1])
    if arc_length > MAX_SHORTENING * curve_length:
        raise EditError(f"the outline between the curve's ends runs {arc_length:.0f} px, "
                        f"{arc_length / curve_length:.1f} times the curve's {curve_length:.0f} px, and "
                        "would be crushed onto it; draw the curve along the whole stretch to change")
    return arc


def _feet(needles, positions, arc):
    """Needle feet on the posed bones and a fallback direction for needles of no length.

    Returns
    -------
    foot : (s, 2) float
    normal : (s, 2) float
        The posed bone's unit normal on the side of the vertex's rest needle; zero for a bone of
        no length.
    """
    bone = needles.bone[arc]
    A = positions[needles.bones[bone, 0]]
    d = positions[needles.bones[bone, 1]] - A
    rigid = needles.rigid[bone]
    t = np.where(rigid, 0.0, np.clip(needles.t[arc], 0.0, 1.0))
    length = np.hypot(d[:, 0], d[:, 1])
    side = np.where(needles.s[arc] < 0, -1.0, 1.0) / np.where(length > 0, length, np.inf)
    normal = np.stack([-d[:, 1], d[:, 0]], axis=1) * side[:, None]
    return A + t[:, None] * d, normal


def _onto_curve(P, feet, C):
    """Slide points ``P`` (``(s, 2)``) along their needles onto the polyline ``C`` (``(k, 2)``).

    Each needle line is ``foot + lam * (P - foot)``, ``lam > 0``; the crossing with ``lam``
    nearest 1 wins. Points whose line misses the curve go to their arc-length fraction of it.
    """
    foot, normal = feet
    d = P - foot
    tiny = np.hypot(d[:, 0], d[:, 1]) < _TINY_NEEDLE
    d[tiny] = normal[tiny]
    A, E = C[:-1], np.diff(C, axis=0)  # (k-1, 2)
    W = A[None] - foot[:, None]  # (s, k-1, 2)
    denominator = _cross(d[:, None], E[None])  # (s, k-1)
    parallel = np.abs(denominator) <= 1e-12 * np.hypot(*d.T)[:, None] * np.hypot(*E.T)[None]
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = _cross(W, E[None]) / denominator
        mu = _cross(W, d[:, None]) / denominator
    hit = ~parallel & (lam > 0) & (mu >= -_SLACK) & (mu <= 1 + _SLACK)
    badness = np.where(hit, np.abs(lam - 1), np.inf)
    j = np.argmin(badness, axis=1)
    found = np.isfinite(badness[np.arange(len(P)), j])
    mu_j = np.clip(mu[np.arange(len(P)), j], 0.0, 1.0)
    out = A[j] + mu_j[:, None] * E[j]
    if not found.all():
        out[~found] = resample_by_arc_length(C, _fractions(P), fraction=True)[~found]
    return out


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _fractions(P):
    """Arc-length fraction of each point of the polyline ``P`` (``(s, 2)``), 0 to 1."""
    s = arc_lengths(P)
    return s / s[-1] if s[-1] > 0 else np.linspace(0.0, 1.0, len(P))


# --- neighbourhoods ------------------------------------------------------------------------------


def _edge_graph(F, n, *, U=None, keep=None):
    """Sparse symmetric graph of mesh edges: lengths in ``U``, or ones; only edges within ``keep``."""
    E = unique_edges(F)
    if keep is not None:
        E = E[keep[E[:, 0]] & keep[E[:, 1]]]
    w = np.ones(len(E)) if U is None else np.maximum(np.hypot(*(U[E[:, 0]] - U[E[:, 1]]).T), 1e-12)
    return sp.csr_matrix((w, (E[:, 0], E[:, 1])), shape=(n, n))


def _default_radius(mesh, move):
    """The follow radius when none is given: a few triangles, or twice the largest move."""
    return max(4.0 * mesh.spacing, 2.0 * move)


def _geodesic_near(F, U, index, radius):
    """Vertices within ``radius`` px of ``index`` along mesh edges in ``U``, ``(n,) bool``."""
    graph = _edge_graph(F, len(U), U=U)
    distance = dijkstra(graph, directed=False, indices=index, limit=radius, min_only=True)
    return distance <= radius


def _joint_areas_touched(F, free, index):
    """The connected joint areas (components of ``free`` along mesh edges) holding any of ``index``."""
    free = np.asarray(free, dtype=bool)
    _, label = connected_components(_edge_graph(F, len(free), keep=free), directed=False)
    touched = np.unique(label[index[free[index]]])
    return free & np.isin(label, touched)
