"""Stage two: nonlinear least squares over the joint areas (thesis 3.4.3, eq. 3.2-3.10).

Only the *free* vertices move (the joint areas, see :func:`joint_area`); every other vertex
keeps its stage-one position. The energy (eq. 3.8) is the weighted sum of

* ``E1``, rotation- and scale-invariant curve Laplacians of the free outline vertices (3.3);
* ``E2``, mean value coordinates of the free inner vertices (3.6);
* ``E3``, squared changes of the lengths of edges that touch a free vertex (3.7).

E1 and E2 are linear in the positions. E3 is linearised the Gauss-Newton way of eq. 3.9: the
edge vector ``u_i - u_j`` should equal its rest length times its current direction.

The thesis's E3 asks joint triangles for their *rest* shape. Where a bone is stretched, the
needle model stretches its region along the bone and thins it across (fig. 3.8, area kept), but
a joint band held to its rest shape between a stretched and an unstretched region can only open
up: stretching a torso 1.5x grew whole figures by 7-14%. So a solve may be given each triangle's
*shape*: a linear map of the plane (``a e + b conj(e)`` on a complex edge ``e``) that its rest
edges take before the fit of E3. :class:`~toonmotion.deform.deformer.Deformer` passes the mean of
its corners' bones' stretch maps, scaled to keep area when the needles do (:func:`stretch_maps`).
Unstretched bones give the identity, the thesis's E3.

Even so, a region stretched along its bone and thinned across leaves its unstretched neighbours
where they were, and the band between them must widen: the needle model alone grows a figure
whose torso is stretched 1.5x by 6-16%. A solve may therefore be given the whole mesh's *area*
to keep, a hard constraint: after each iteration's solve the free vertices move by the
smallest correction, in the metric of the normal matrix, that brings the linearised total signed
area to the target. The correction is along ``N^-1 g``, with ``g`` the area's gradient (a fixed
Hermitian form times the positions, nonzero on free outline vertices only) at the last iterate,
solved with the step as a second column. The area lost or gained is spread over the joint areas'
outline as smoothly as the energy allows. The matrix
of that linear system depends on the rest mesh only, so its normal matrix is factorised once
(:class:`JointSolver`), and each iteration is a sparse product and two triangular solves.
Each iteration fixes the edge directions at their best values for the current positions and
then solves exactly for the positions, so the energy never goes up.

The thesis' energy lets a wide joint area settle as a block, away from the joint the skeleton
puts it round; a solve may therefore be given *anchors* (:class:`Anchors`): the skeleton's
joints, each held near where stage one puts it (at the joint) by a fourth term ``E4``, linear
like E1 and E2, so it only adds to the normal matrix and the right-hand side. A solve may let
some of them go (``held``): each anchor is a rank-one term of the normal matrix, so the solver
keeps its one factorisation and takes the released anchors out of each solve by the
Sherman-Morrison-Woodbury identity (:meth:`JointSolver._release`), a few dot products.

Points are complex numbers ``x + iy`` here: the RSI Laplacian's rotation-and-scale factor is
then one complex coefficient and the whole system is one ``m x m`` complex solve.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from toonmotion.errors import MeshError, SettingsError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.geometry.coordinates import (
    as_complex,
    as_points,
    barycentric,
    mean_value_weights,
    rsi_laplacian_coefficients,
)
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.rig.binding import Binding, bone_half_thickness
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton
from toonmotion.shape.mesh import Mesh, unique_edges

# A change of eq. 3.8's energy (px^2) this small is round-off: a solve whose plain step changes the
# energy by no more than the tolerance's share plus this has converged (at the rest pose the energy
# itself is round-off, 1e-23). A step that raises the energy more is not convergence: the area
# correction can raise it a little after an Anderson step.
ENERGY_FLOOR = 1e-12

# Added to the normal matrix's diagonal, relative to its mean, pulling free vertices that no
# fixed vertex anchors (a joint area that is a whole part) towards their starting positions.
_REGULARISE = 1e-9

EDGE_TERMS = ("rigid", "length")

# Sets of anchors let go whose Woodbury operands a solver keeps (each a few solves to make).
_RELEASES = 64


@dataclass(frozen=True, eq=False)
class SolveResult:
    """Outcome of one stage-two solve.

    Attributes
    ----------
    U : (n, 2) float
        All vertices: the free ones solved, the rest as given.
    iterations : int
        Gauss-Newton iterations run.
    energy_start, energy : float
        Eq. 3.8 at the starting positions and at the result (pixels squared).
    converged : bool
        The last iteration lowered the energy by less than the tolerance (a fraction).

    Construction copies ``U`` (read-only) and raises ``ValueError`` unless it is ``(n, 2)``,
    the iteration count a whole number >= 0 and the energies numbers.
    """

    U: NDArray[np.float64]
    iterations: int
    energy_start: float
    energy: float
    converged: bool

    _what = "a stage-two result"  # how errors name it

    def __post_init__(self) -> None:
        what, iterations = self._what, self.iterations
        if isinstance(iterations, bool) or not isinstance(iterations, int | np.integer) or iterations < 0:
            raise ValueError(f"{what}'s iterations must be a whole number >= 0, got {iterations!r}")
        for name in ("energy_start", "energy"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number):
                raise ValueError(f"{what}'s {name} must be a number, got {value!r}")
            object.__setattr__(self, name, float(value))
        U = frozen_array(self.U, dtype=np.float64, shape=(None, 2), name=f"{what}'s U")
        object.__setattr__(self, "U", U)
        object.__setattr__(self, "iterations", int(iterations))
        object.__setattr__(self, "converged", bool(self.converged))


@dataclass(frozen=True, eq=False)
class Anchors:
    """Points of the rest mesh that stage two holds where stage one puts them: a term ``E4``,
    ``weight`` times the squared distance of each point from there, beside eq. 3.8's.

    The thesis' stage two frees the joint areas and lets them settle as their outline, inner
    shape and edges ask (eq. 3.8); nothing keeps the joint itself where the skeleton puts it.
    Where a joint area is wide and stiff (knees in wide trousers), it settles as a block, and
    the drawn knee ended 20-24 px from the skeleton's knee on the bundled character's crouch.
    Stage one puts every point at a joint at that joint (both bones' needles turn about it), so
    anchoring the joints' own points there keeps the drawing on the skeleton the animator drew.

    Attributes
    ----------
    points : (a,) int
        Which of the points asked for (:func:`joint_anchors`) each anchor is.
    corners : (a, 3) int
        The rest triangle holding each point.
    barycentric : (a, 3) float
        Each point's weights on its triangle's corners.
    weight : float
        ``w4``, >= 0; 0 leaves the thesis' energy alone.

    Construction copies the arrays (read-only) and raises :class:`SettingsError` for a weight
    that is not a finite number >= 0.
    """

    points: NDArray[np.int64]
    corners: NDArray[np.int64]
    barycentric: NDArray[np.float64]
    weight: float

    def __post_init__(self) -> None:
        corners = frozen_array(self.corners, dtype=np.int64, shape=(None, 3), name="anchor corners")
        object.__setattr__(self, "points", frozen_array(self.points, dtype=np.int64, shape=(len(corners),),
                                                        name="anchored points"))
        object.__setattr__(self, "corners", corners)
        object.__setattr__(self, "barycentric", frozen_array(self.barycentric, dtype=np.float64,
                                                             shape=corners.shape, name="anchor weights"))
        if not (np.isfinite(self.weight) and self.weight >= 0):
            raise SettingsError(f"the joint anchor weight must be a finite number >= 0, got {self.weight}")
        object.__setattr__(self, "weight", float(self.weight))

    def subset(self, keep: NDArray[np.bool_]) -> Anchors:
        """The anchors where ``keep`` (``(a,) bool``) is True."""
        keep = np.asarray(keep, dtype=bool)
        return Anchors(self.points[keep], self.corners[keep], self.barycentric[keep], self.weight)


def joint_anchors(mesh: Mesh, points: NDArray[np.float64], weight: float) -> Anchors:
    """:class:`Anchors` for the rest ``points`` (``(p, 2)``, the skeleton's joints) that lie in
    ``mesh``; a joint drawn outside the figure is not anchored."""
    triangle, bary = barycentric(mesh.V, mesh.F, points)
    inside = np.flatnonzero(triangle >= 0)
    return Anchors(inside, np.asarray(mesh.F)[triangle[inside]].reshape(-1, 3), bary[inside], weight)


def joint_area(
    mesh: Mesh, skeleton: Skeleton, binding: Binding, mask: NDArray[np.bool_], *, width: float = 1.5,
    radius: NDArray[np.float64] | None = None,
) -> NDArray[np.bool_]:
    """Vertices that stage two moves: the joint areas, ``(n,) bool``.

    The thesis' joint area is the vertices of joint triangles (those spanning two bones), a
    band about one triangle wide. On a sharply bent elbow the two limb regions overlap on the
    inside of the bend by about the limb's half-thickness, and a one-triangle band cannot
    unfold that. So around every joint where two or more bones meet we also free the vertices
    of those bones within ``width`` times the thinner bone's half-thickness (the figure's
    distance to its outline along the bone's middle; :func:`joint_radii`, or ``radius`` when
    the caller has them already). ``width=0`` gives the thesis' band alone.
    The default, 1.5, is also :class:`~toonmotion.deform.deformer.DeformSettings`'s
    ``joint_width``, which :class:`~toonmotion.deform.deformer.Deformer` passes.
    """
    if not (np.isfinite(width) and width >= 0):
        raise SettingsError(f"the joint area width must be a finite number >= 0, got {width}")
    free = binding.joint_area.copy()
    if width == 0 or len(mesh.V) == 0:
        return free
    if radius is None:
        radius = joint_radii(skeleton, mask, width=width, floor=mesh.spacing)
    for j, meeting in enumerate(_meeting_bones(skeleton)):
        if radius[j] > 0:
            joint = skeleton.positions[j]
            near = np.hypot(mesh.V[:, 0] - joint[0], mesh.V[:, 1] - joint[1]) < radius[j]
            free |= near & np.isin(binding.bone, meeting)
    return free


def joint_radii(skeleton: Skeleton, mask: NDArray[np.bool_], *, width: float, floor: float
                ) -> NDArray[np.float64]:
    """How far round each joint :func:`joint_area` frees vertices, ``(j,)`` pixels: ``width``
    times the thinnest half-thickness of the bones meeting there (each at least ``floor``), 0
    where fewer than two bones meet."""
    thickness = bone_half_thickness(skeleton, mask, floor=floor)
    return np.array([width * thickness[meeting].min() if len(meeting) >= 2 else 0.0
                     for meeting in _meeting_bones(skeleton)])


def _meeting_bones(skeleton):
    """The bones of length that meet at each joint; joints at one place (AD's root and hip)
    count as one."""
    bones = skeleton.bones
    usable = skeleton.bone_lengths > MIN_BONE_LENGTH
    out = []
    for joint in skeleton.positions:
        here = np.flatnonzero(np.hypot(*(skeleton.positions - joint).T) <= MIN_BONE_LENGTH)
        out.append(np.flatnonzero(usable & (np.isin(bones[:, 0], here) | np.isin(bones[:, 1], here))))
    return out


class JointSolver:
    """Stage two's precomputation for one mesh and joint area; :meth:`solve` runs per frame.

    Parameters
    ----------
    mesh : Mesh
        The rest mesh.
    free : (n,) bool
        Vertices to solve for (:func:`joint_area`).
    weights : (3,) float
        ``w1, w2, w3`` for the RSI Laplacian, mean value and edge-length terms; normalised to
        sum to 1 (eq. 3.8). Equal by default.
    edge_term : {"rigid", "length"}
        The form of E3 (see :class:`~toonmotion.deform.deformer.DeformSettings`); "rigid" by
        default. :class:`~toonmotion.deform.deformer.Deformer` passes its settings' weights and
        edge term, whose defaults are these.
    anchors : Anchors, optional
        Points held where stage one puts them (``E4``, added to eq. 3.8); none by default (the
        thesis). :class:`~toonmotion.deform.deformer.Deformer` passes the skeleton's joints.
    compiled : bool
        Iterate with the compiled loop (:mod:`toonmotion.deform.kernels`, rigid edge term only):
        the same results, faster, after Numba's one-off load; the NumPy loop by default.

    Attributes
    ----------
    free : (m,) int
        Indices of the free vertices.
    weights : (3,) float
        The normalised weights.
    """

    def __init__(self, mesh: Mesh, free: NDArray[np.bool_], *, weights: Sequence[float] = (1.0, 1.0, 1.0),
                 edge_term: str = "rigid", anchors: Anchors | None = None, compiled: bool = False) -> None:
        if edge_term not in EDGE_TERMS:
            raise SettingsError(f"the edge term must be one of {', '.join(EDGE_TERMS)}, got {edge_term!r}")
        self.edge_term = edge_term
        w = np.asarray(weights, dtype=float)
        if w.shape != (3,) or not np.all(np.isfinite(w)) or (w < 0).any() or w.sum() <= 0:
            raise SettingsError(
                f"stage-two weights must be three finite numbers >= 0, not all zero; got {w.tolist()}"
            )
        self.weights = w / w.sum()
        free = np.asarray(free, dtype=bool)
        self.free = np.flatnonzero(free)
        self.fixed = np.flatnonzero(~free)
        # The area of the triangles that touch a free vertex (the only ones a solve changes) is
        # the Hermitian form area(z) = Re(z^H M z) / 2, its gradient M z.
        self._all_V = mesh.V
        moving = free[mesh.F].any(axis=1)
        self._area_form = _area_form(np.asarray(mesh.F)[moving], len(free))
        self._still_F = np.asarray(mesh.F)[~moving]  # triangles no solve changes
        rest = as_complex(mesh.V)
        every = _every_row(mesh)
        A1 = every.laplacian[free[every.laplacian_vertex]]
        A2 = every.mean_value[free[every.mean_value_vertex]]
        if edge_term == "length":
            touching = free[every.edges].any(axis=1)
            self.edges, A3 = every.edges[touching], every.edge_rows[touching]
            self._corners = None
        else:
            touching = free[mesh.F].any(axis=1)
            self._corners = np.asarray(mesh.F)[touching]
            self.edges = every.triangle_edges.reshape(-1, 3, 2)[touching].reshape(-1, 2)
            A3 = every.triangle_edge_rows[np.repeat(touching, 3)]
        self.rest_edge = rest[self.edges[:, 0]] - rest[self.edges[:, 1]]
        self.rest_length = np.abs(self.rest_edge)
        self._set_shape(None)
        w1, w2, w3 = self.weights
        self._linear = sp.vstack([np.sqrt(w1) * A1, np.sqrt(w2) * A2]).tocsr()
        self._A3 = A3
        anchors = anchors if anchors is not None and anchors.weight > 0 else None
        self.anchors = anchors
        A4 = None if anchors is None else _anchor_rows(anchors, len(mesh.V))
        self._A4, self._anchor_weight = A4, 0.0 if anchors is None else anchors.weight
        self._anchor_target = np.zeros(0, complex)
        # Each anchor's weight in this solve: w4 where held, 0 where let go (:meth:`_set_held`).
        self._anchor_weights = np.full(0 if A4 is None else A4.shape[0], self._anchor_weight)
        self._releases: dict[bytes, tuple[Any, ...]] = {}
        self._release_now: tuple[Any, ...] | None = None
        self._compiled: tuple[Any, dict[str, Any]] | None = None
        if len(self.free) == 0:
            return
        rows = [self._linear, np.sqrt(w3) * A3]
        if A4 is not None:
            rows.append(np.sqrt(self._anchor_weight) * A4)
        Af = sp.vstack(rows).tocsc()
        Ff, Fx = Af[:, self.free], Af[:, self.fixed]
        normal = (Ff.conj().T @ Ff).tocsc()
        self._epsilon = _REGULARISE * max(float(np.abs(normal.diagonal()).mean()), 1e-300)
        normal = normal + self._epsilon * sp.identity(len(self.free), format="csc")
        # The normal matrix is Hermitian positive definite: no pivoting needed.
        try:
            self._factor = splu(normal, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                                options={"SymmetricMode": True})
        except RuntimeError:  # "Factor is exactly singular": no sound mesh gives that
            raise MeshError("the mesh's joint-area system cannot be solved: the mesh is degenerate "
                            "(rig the drawing again)") from None
        # The fixed vertices' pull, E4's apart: an anchor's may be let go (its target is then 0).
        k = sum(r.shape[0] for r in rows[:2])
        self._from_fixed = (-(Ff[:k].conj().T @ Fx[:k])).tocsr()
        self._from_edges = (w3 * A3[:, self.free].conj().T).tocsr()
        if A4 is not None:
            self._from_anchors = (self._anchor_weight * A4[:, self.free].conj().T).tocsr()
            self._anchor_rows = A4[:, self.free].tocsr()
            self._anchor_fixed = A4[:, self.fixed].tocsr()
        self._compiled = self._kernel_operands() if compiled and edge_term == "rigid" else None

    def _kernel_operands(self):
        """The matrices and factors :func:`toonmotion.deform.kernels.iterate` takes (the rigid
        edge term's loop, compiled)."""
        from toonmotion.deform import kernels

        empty = (np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0, complex))
        operands = {
            "free": self.free.astype(np.int64),
            "linear": kernels.csr(self._linear),
            "anchors": empty if self._A4 is None else kernels.csr(self._A4),
            "corners": np.ascontiguousarray(self._corners, dtype=np.int64),
            "w3": float(self.weights[2]),
            "from_edges": kernels.csr(self._from_edges),
            "factor": kernels.lu_factors(self._factor),
            "area_form": kernels.csr(self._area_form),
        }
        # No iterations: loads the compiled loop (from Numba's disk cache, or compiled on a machine's
        # first use) now, with the solver, rather than in the first pose's solve.
        self._set_anchor_target(self._all_V)
        self._compiled = (kernels, operands)
        self._energy(as_complex(self._all_V))
        start = np.zeros(len(self._all_V), complex)
        self._iterate(kernels, operands, start, np.zeros(len(self.free), complex), None, 0, 1.0, 0)
        return kernels, operands

    def _iterate(self, kernels, op, z, base, area, max_iterations, tolerance, acceleration):
        """The compiled loop from ``z`` (modified in place): ``(iterations, energy, converged)``."""
        return kernels.iterate(
            z, op["free"], base, op["linear"], op["anchors"],
            np.ascontiguousarray(self._anchor_target, dtype=complex), self._anchor_weights,
            op["corners"], np.ascontiguousarray(self._rest), op["w3"], op["from_edges"], op["factor"],
            self._kernel_release(), op["area_form"], 0.0 if area is None else float(area), area is not None,
            int(max_iterations), float(tolerance), ENERGY_FLOOR, int(acceleration))

    def _kernel_release(self):
        """The released anchors' Woodbury operands as the compiled loop takes them (empty when
        every anchor is held)."""
        if self._release_now is None:
            m = len(self.free)
            return (np.zeros((0, 3), np.int64), np.zeros((0, 3), complex), np.zeros((m, 0), complex),
                    np.zeros((0, 0), complex))
        return self._release_now[3]

    @property
    def triangles(self) -> NDArray[np.int64]:
        """``(t, 3)`` corners of the triangles E3 holds (``"rigid"``), or ``(e, 2)`` ends of its
        edges (``"length"``): what a ``shape`` given to :meth:`solve` has one entry for."""
        return self._corners if self._corners is not None else self.edges

    def energy(self, U: NDArray[np.float64], *, shape: NDArray[np.complex128] | None = None,
               stage_one: NDArray[np.float64] | None = None,
               held: NDArray[np.float64] | None = None) -> float:
        """Eq. 3.8 at vertices ``U`` (``(n, 2)``), with ``shape`` as for :meth:`solve`; with
        anchors, plus their term (those ``held``, default all), measured from where ``stage_one``
        (default ``U``) puts them."""
        self._set_shape(shape)
        self._set_anchor_target(U if stage_one is None else stage_one)
        self._set_held(held)
        return self._energy(as_complex(U))

    def _set_held(self, held):
        """How firmly this solve holds each anchor (``(a,)``, a fraction of ``w4`` from 0, let go, to
        1; booleans: held or not; None: all fully): their weights, and the Woodbury operands that
        take the difference out of the factorisation."""
        if self._A4 is None:
            return
        held = np.ones(self._A4.shape[0]) if held is None else np.asarray(held, dtype=float)
        if held.shape != (self._A4.shape[0],) or not ((held >= 0) & (held <= 1)).all():
            raise ValueError(f"held must be ({self._A4.shape[0]},) fractions from 0 to 1, got {held}")
        self._anchor_weights = self._anchor_weight * held
        self._release_now = None if (held == 1).all() or len(self.free) == 0 else self._release(held)

    def _release(self, held):
        """Woodbury operands for the normal matrix with each anchor held by the fraction ``held``.

        Anchor ``k`` adds ``w4 a_k^H a_k`` to the normal matrix, ``a_k`` its E4 row over the free
        vertices. With ``C`` the rows ``sqrt(w4 (1 - held_k)) a_k`` of the anchors not fully held,
        ``Y = N^-1 C^H`` and ``S = I - C Y``, ``(N - C^H C)^-1 b = x + Y S^-1 C x`` for
        ``x = N^-1 b``. Returns ``(C, Y, S^-1, kernel operands)``, kept per ``held``; None when
        no anchor let go (even in part) touches a free vertex.
        """
        key = held.tobytes()
        if key not in self._releases:
            if len(self._releases) >= _RELEASES:
                self._releases.pop(next(iter(self._releases)))
            loose = np.flatnonzero(held < 1)
            rows = sp.diags(np.sqrt(self._anchor_weight * (1 - held[loose]))) @ self._anchor_rows[loose]
            rows = sp.csr_matrix(rows)
            rows = rows[np.flatnonzero(np.diff(rows.indptr))]  # anchors on a free vertex
            if rows.shape[0] == 0:
                self._releases[key] = None
            else:
                C = rows.toarray()
                Y = self._factor.solve(np.ascontiguousarray(C.conj().T))
                inverse = np.linalg.inv(np.eye(len(C)) - C @ Y)
                # The kernel's form: each row's (at most three) columns and values.
                cols = np.zeros((len(C), 3), np.int64)
                vals = np.zeros((len(C), 3), complex)
                for r in range(len(C)):
                    nz = np.flatnonzero(C[r])
                    cols[r, :len(nz)], vals[r, :len(nz)] = nz, C[r, nz]
                self._releases[key] = (C, Y, inverse,
                                       (cols, vals, np.ascontiguousarray(Y), np.ascontiguousarray(inverse)))
        return self._releases[key]

    def _factor_solve(self, rhs):
        """``N^-1 rhs`` (one column or several) for the normal matrix of the anchors held."""
        x = self._factor.solve(rhs)
        if self._release_now is not None:
            C, Y, inverse, _ = self._release_now
            x = x + Y @ (inverse @ (C @ x))
        return x

    def _set_anchor_target(self, U):
        """Where the anchored points are held: where stage one (``U``) puts them."""
        if self._A4 is not None:
            self._anchor_target = self._A4 @ as_complex(U)

    def _set_shape(self, shape):
        """Rest edges (and lengths) mapped by ``shape``: ``(k, 2)`` complex ``(a, b)`` per entry of
        :attr:`triangles`, edges ``e -> a e + b conj(e)``; None: the rest edges themselves."""
        if shape is None:
            self._target_rest, self._target_length = self.rest_edge, self.rest_length
        else:
            shape = np.asarray(shape, dtype=complex)
            if shape.shape != (len(self.triangles), 2):
                raise ValueError(f"a stage-two shape must be ({len(self.triangles)}, 2) complex, "
                                 f"got {shape.shape}")
            per_edge = np.repeat(shape, 3, axis=0) if self._corners is not None else shape
            edge = self.rest_edge
            self._target_rest = per_edge[:, 0] * edge + per_edge[:, 1] * np.conj(edge)
            self._target_length = np.abs(self._target_rest)
        if self._corners is not None:
            self._rest = self._target_rest.reshape(-1, 3)
            self._rest_conj = np.conj(self._rest)

    def solve(self, U: NDArray[np.float64], *, initial: NDArray[np.float64] | None = None,
              max_iterations: int = 50, tolerance: float = 1e-3,
              shape: NDArray[np.complex128] | None = None, area: float | None = None,
              acceleration: int = 0, held: NDArray[np.float64] | None = None) -> SolveResult:
        """Solve for the free vertices, the others fixed at ``U`` (the stage-one result).

        Parameters
        ----------
        U : (n, 2) float
            Stage-one positions of every vertex.
        initial : (n, 2) float, optional
            Where the free vertices start (a warm start, e.g. the previous frame's result moved
            by this frame's stage one). Used only when its energy is below ``U``'s.
        max_iterations : int
            Gauss-Newton iterations at most; 50 when not given. No caller in toonmotion relies on
            that: :meth:`Deformer.deform <toonmotion.deform.deformer.Deformer.deform>` passes
            ``DeformSettings.max_iterations`` (100 by default) and fine tuning passes 100.
        tolerance : float
            Stop when an iteration lowers the energy by less than this fraction of it; 1e-3 when
            not given. ``Deformer.deform`` passes ``DeformSettings.tolerance`` (1e-4 by default)
            and fine tuning passes 1e-6.
        shape : (k, 2) complex, optional
            The linear map ``e -> a e + b conj(e)`` each triangle's rest edges take before E3
            fits them (module docstring), one ``(a, b)`` per row of :attr:`triangles`; None: the
            rest shape (``(1, 0)`` everywhere).
        area : float, optional
            The whole mesh's signed area (px^2, :func:`~toonmotion.geometry.polygon.triangle_areas`
            summed) to keep, a constraint (module docstring); None: no constraint.
        acceleration : int
            Anderson acceleration over this many past iterations (:class:`_Anderson`); 0 runs the
            plain local-global iterations. Either way the energy never goes up, and both reach
            the same minimum.
        held : (a,) bool or float, optional
            How firmly this solve holds each anchor: a fraction of their weight, from 1 (held,
            True) to 0 (let go, False); the factorisation is kept (module docstring). None:
            all held.
        """
        self._set_shape(shape)
        self._set_anchor_target(U)
        self._set_held(held)
        z = as_complex(U).copy()
        start = self._energy(z)
        if initial is not None and len(self.free):
            warm = z.copy()
            warm[self.free] = as_complex(initial)[self.free]
            warm_energy = self._energy(warm)
            if warm_energy < start:
                z, start = warm, warm_energy
        if len(self.free) == 0:
            return SolveResult(U=np.array(U, dtype=float), iterations=0, energy_start=start,
                               energy=start, converged=True)
        base = self._from_fixed @ z[self.fixed] + self._epsilon * z[self.free]
        if self._A4 is not None:  # each held anchor pulls its free corners to its target
            pull = self._anchor_target - self._anchor_fixed @ z[self.fixed]
            base = base + self._from_anchors @ (self._anchor_weights / self._anchor_weight * pull)
        if area is not None:
            # The moving triangles' share of the target: the others keep their area in ``U``.
            area = float(area) - float(triangle_areas(np.asarray(U, dtype=float), self._still_F).sum())
        if self._compiled is not None:
            kernels, operands = self._compiled
            iterations, energy, converged = self._iterate(kernels, operands, z, base, area, max_iterations,
                                                          tolerance, acceleration)
            return SolveResult(U=as_points(z), iterations=int(iterations), energy_start=start,
                               energy=float(energy), converged=bool(converged))
        targets, energy = self._local(z)
        mixer = _Anderson(acceleration) if acceleration else None
        iterations, converged = 0, False
        while iterations < max_iterations and not converged:
            iterations += 1
            step = self._global(z, base, targets, area)
            if mixer is not None and mixer.depth:
                # Anderson: the step extrapolated from the last few; kept only where it lowers the
                # energy, so the energy still never goes up. Only a plain step may end the solve:
                # a mixed one that gains little starts the mixing again from a plain step.
                tried = z.copy()
                tried[self.free] = mixer.mix(z[self.free], step)
                tried_targets, tried_energy = self._local(tried)
                if tried_energy < energy:
                    z, targets = tried, tried_targets
                    if energy - tried_energy <= tolerance * energy:
                        mixer.restart(plain=True)
                    energy = tried_energy
                    continue
                mixer.restart(plain=True)
            elif mixer is not None:
                mixer.restart()  # the plain step asked for, taken: mixing resumes after it
            z[self.free] = step
            targets, new_energy = self._local(z)
            converged = abs(energy - new_energy) <= tolerance * energy + ENERGY_FLOOR
            energy = new_energy
        return SolveResult(U=as_points(z), iterations=iterations, energy_start=start,
                           energy=energy, converged=bool(converged))

    def _global(self, z, base, targets, area):
        """The free vertices' positions minimising eq. 3.8 with the local step's ``targets`` held,
        corrected to keep the linearised ``area`` (None: no constraint): ``(m,)`` complex."""
        rhs = base + self._from_edges @ targets
        if area is None:
            return self._factor_solve(rhs)
        # One solve for the step and for the correction's direction, N^-1 g, with the area's
        # gradient at the last iterate (it moves little in one iteration).
        both = self._factor_solve(np.stack([rhs, self._moving_area(z)[1]], axis=1))
        step, direction = both[:, 0], both[:, 1]
        moved = z.copy()
        moved[self.free] = step
        now, gradient = self._moving_area(moved)
        slope = float(np.vdot(gradient, direction).real)
        if slope > 1e-12 * max(abs(now), 1.0):
            step = step + ((area - now) / slope) * direction
        return step

    def _energy(self, z):
        if self._compiled is None:
            return self._local(z)[1]
        kernels, op = self._compiled
        target = np.ascontiguousarray(self._anchor_target, dtype=complex)
        return float(kernels.energy(z, op["linear"], op["anchors"], target, self._anchor_weights,
                                    op["corners"], np.ascontiguousarray(self._rest), op["w3"]))

    def _moving_area(self, z):
        """The moving triangles' total signed area at ``z`` and its gradient over the free
        vertices, ``(m,)`` complex: ``d area = Re(conj(g) . dz)``."""
        Mz = self._area_form @ z
        return 0.5 * float(np.vdot(z, Mz).real), Mz[self.free]

    def _local(self, z):
        """The local step at positions ``z``: every E3 row's best target edge vector, and the
        energy (eq. 3.8) at ``z``, which those targets attain.

        ``"length"``: the rest length along the edge's current direction (eq. 3.7).
        ``"rigid"``: the rest edges of a triangle turned by its best-fitting rotation.
        """
        linear = self._linear @ z
        energy = np.vdot(linear, linear).real
        if self._A4 is not None:
            off = self._A4 @ z - self._anchor_target
            energy += np.dot(self._anchor_weights, off.real ** 2 + off.imag ** 2)
        if self._corners is None:
            e = z[self.edges[:, 0]] - z[self.edges[:, 1]]
            length = np.abs(e)
            targets = np.where(length > 1e-12, self._target_length * e / np.maximum(length, 1e-300),
                               self._target_rest)
            stretch = length - self._target_length
            return targets, float(energy + self.weights[2] * np.dot(stretch, stretch))
        c = z[self._corners]  # (t, 3); the edges of a triangle run to corner 0, 1, 2 from the next
        e = np.empty_like(c)
        e[:, 0] = c[:, 0] - c[:, 1]
        e[:, 1] = c[:, 1] - c[:, 2]
        e[:, 2] = c[:, 2] - c[:, 0]
        fit = np.einsum("ij,ij->i", self._rest_conj, e)
        size = np.abs(fit)
        rotation = np.where(size > 1e-300, fit / np.where(size > 1e-300, size, 1.0), 1.0)
        targets = rotation[:, None] * self._rest
        r = e - targets
        return targets.ravel(), float(energy + self.weights[2] * np.vdot(r, r).real)


class _Anderson:
    """Anderson acceleration of a fixed-point iteration ``x -> G(x)`` (type II, as Peng et al.
    2018 apply to local-global geometry solves): the next point is the combination of the last
    few steps whose residuals ``G(x) - x`` combine to the smallest, extrapolating where plain
    iterations creep along a long valley. Complex vectors are mixed as their real and imaginary
    parts (the local step is not complex-linear).

    >>> mixer = _Anderson(3)
    >>> x = np.array([1.0 + 0j])
    >>> for _ in range(3):  # G(x) = x / 2 + 1, fixed point 2: exact after two mixed steps
    ...     x = mixer.mix(x, x / 2 + 1)
    >>> np.round(x, 12).tolist()
    [(2+0j)]
    """

    def __init__(self, depth: int) -> None:
        self.size = depth
        self.restart()

    def restart(self, *, plain: bool = False) -> None:
        """Forget the past steps (after a mixed point was refused, or gained too little to go on
        with); ``plain``: the next step is to be a plain one (:attr:`depth` is 0 until then)."""
        self.depth = 0 if plain else self.size
        self._last: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._df: list[NDArray[np.float64]] = []
        self._dg: list[NDArray[np.float64]] = []

    def mix(self, x: NDArray[np.complex128], step: NDArray[np.complex128]) -> NDArray[np.complex128]:
        """The next point after ``x``, whose plain step is ``step``."""
        g = np.ascontiguousarray(step).view(np.float64)
        f = g - np.ascontiguousarray(x).view(np.float64)
        if self._last is not None:
            self._df.append(f - self._last[0])
            self._dg.append(g - self._last[1])
            if len(self._df) > self.depth:
                del self._df[0], self._dg[0]
        self._last = (f, g)
        if not self._df:
            return np.array(step)
        DF = np.stack(self._df, axis=1)
        gram = DF.T @ DF
        gram[np.diag_indices_from(gram)] *= 1 + 1e-10
        try:
            gamma = np.linalg.solve(gram, DF.T @ f)
        except np.linalg.LinAlgError:
            self.restart()
            return np.array(step)
        return (g - np.stack(self._dg, axis=1) @ gamma).view(np.complex128)


@dataclass(frozen=True, eq=False)
class _EveryRow:
    """Eq. 3.8's rows with every vertex free: a solver for any joint area takes its rows from
    these (the rows of a free vertex, or of a triangle or edge touching one, do not depend on
    which others are free), so a widened joint area costs a factorisation, not a rebuild."""

    laplacian: sp.csr_matrix  # E1, a row per outline vertex, loop by loop
    laplacian_vertex: NDArray[np.int64]
    mean_value: sp.csr_matrix  # E2, a row per inner vertex
    mean_value_vertex: NDArray[np.int64]
    triangle_edges: NDArray[np.int64]  # (3t, 2): E3 rigid, three rows per triangle
    triangle_edge_rows: sp.csr_matrix
    edges: NDArray[np.int64]  # (e, 2): E3 length, a row per edge
    edge_rows: sp.csr_matrix


_EVERY_ROW: weakref.WeakKeyDictionary[Mesh, _EveryRow] = weakref.WeakKeyDictionary()


def _every_row(mesh):
    """The mesh's :class:`_EveryRow`, built on first use and kept while the mesh lives."""
    if mesh not in _EVERY_ROW:
        every = np.ones(len(mesh.V), bool)
        inner = np.arange(mesh.n_outline, len(mesh.V))
        triangle_edges, triangle_rows, _ = _triangle_edge_rows(mesh, every)
        edges, edge_rows = _edge_rows(mesh, every)
        _EVERY_ROW[mesh] = _EveryRow(
            _laplacian_rows(mesh, as_complex(mesh.V), every).tocsr(),
            np.concatenate(mesh.boundary) if mesh.boundary else np.zeros(0, np.int64),
            _mean_value_rows(mesh, every).tocsr(), inner,
            triangle_edges, triangle_rows.tocsr(), edges, edge_rows.tocsr())
    return _EVERY_ROW[mesh]


def _anchor_rows(anchors, n):
    """E4 rows: one per anchored point, its barycentric combination of its triangle's corners."""
    a = len(anchors.corners)
    rows = np.repeat(np.arange(a), 3)
    return sp.csr_matrix((anchors.barycentric.ravel().astype(complex), (rows, anchors.corners.ravel())),
                         shape=(a, n))


def _area_form(F, n):
    """``M``, ``(n, n)`` Hermitian, with ``Re(z^H M z) / 2`` the total signed area of triangles
    ``F`` (as :func:`~toonmotion.geometry.polygon.triangle_areas`, positive counter-clockwise
    on screen): each corner's gradient is ``i/2 (next corner - previous corner)``."""
    F = np.asarray(F)
    rows = np.concatenate([F.ravel(), F.ravel()])
    cols = np.concatenate([np.roll(F, -1, axis=1).ravel(), np.roll(F, 1, axis=1).ravel()])
    vals = np.concatenate([np.full(F.size, 0.5j), np.full(F.size, -0.5j)])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def _laplacian_rows(mesh, rest, free):
    """E1 rows: one per free outline vertex, ``u - (u_prev + u_next)/2 - c (u_next - u_prev)``."""
    rows, cols, vals = [], [], []
    count = 0
    for loop in mesh.boundary:
        prev, after = np.roll(loop, 1), np.roll(loop, -1)
        keep = free[loop]
        c = rsi_laplacian_coefficients(mesh.V[prev[keep]], mesh.V[loop[keep]], mesh.V[after[keep]])
        k = int(keep.sum())
        r = np.arange(count, count + k)
        rows += [r, r, r]
        cols += [loop[keep], prev[keep], after[keep]]
        vals += [np.ones(k, complex), -0.5 + c, -0.5 - c]
        count += k
    return _matrix(rows, cols, vals, count, len(mesh.V))


def _mean_value_rows(mesh, free):
    """E2 rows: one per free inner vertex, ``u_i - sum_j w_ij u_j``."""
    inner = free.copy()
    inner[: mesh.n_outline] = False
    r, c, w = mean_value_weights(mesh.V, mesh.F)
    keep = inner[r]
    index = np.cumsum(inner) - 1
    ids = np.flatnonzero(inner)
    rows = [index[ids], index[r[keep]]]
    cols = [ids, c[keep]]
    vals = [np.ones(len(ids), complex), -w[keep].astype(complex)]
    return _matrix(rows, cols, vals, len(ids), len(mesh.V))


def _edge_rows(mesh, free):
    """E3 rows: one per edge touching a free vertex, ``u_i - u_j``."""
    edges = unique_edges(mesh.F)
    edges = edges[free[edges[:, 0]] | free[edges[:, 1]]]
    k = np.arange(len(edges))
    A = _matrix([k, k], [edges[:, 0], edges[:, 1]], [np.ones(len(k), complex), -np.ones(len(k), complex)],
                len(edges), len(mesh.V))
    return edges, A


def _triangle_edge_rows(mesh, free):
    """E3 rows, rigid form: three per triangle touching a free vertex, one for each edge."""
    triangles = np.flatnonzero(free[mesh.F].any(axis=1))
    F = mesh.F[triangles]
    edges = np.stack([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1).reshape(-1, 2)
    k = np.arange(len(edges))
    A = _matrix([k, k], [edges[:, 0], edges[:, 1]], [np.ones(len(k), complex), -np.ones(len(k), complex)],
                len(edges), len(mesh.V))
    return edges, A, F


def _matrix(rows, cols, vals, shape0, shape1):
    if not rows:
        return sp.csr_matrix((shape0, shape1), dtype=complex)
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(shape0, shape1)
    )

