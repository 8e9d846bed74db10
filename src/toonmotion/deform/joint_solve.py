"""Stage two: nonlinear least squares over the joint areas (thesis 3.4.3, eq. 3.2-3.10).

Only the *free* vertices move (the joint areas, :mod:`toonmotion.deform.joint_area`); every
other vertex keeps its stage-one position. The energy (eq. 3.8) is the weighted sum of

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

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from toonmotion.deform.anderson import Anderson
from toonmotion.deform.energy_terms import anchor_rows, area_form, every_row
from toonmotion.deform.joint_area import Anchors
from toonmotion.deform.solve_result import SolveResult
from toonmotion.errors import MeshError, SettingsError
from toonmotion.geometry.coordinates import (
    as_complex,
    as_points,
)
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.shape.mesh import Mesh

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
        self._area_form = area_form(np.asarray(mesh.F)[moving], len(free))
        self._still_F = np.asarray(mesh.F)[~moving]  # triangles no solve changes
        rest = as_complex(mesh.V)
        every = every_row(mesh)
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
        A4 = None if anchors is None else anchor_rows(anchors, len(mesh.V))
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
            Anderson acceleration over this many past iterations (:class:`Anderson`); 0 runs the
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
        mixer = Anderson(acceleration) if acceleration else None
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


