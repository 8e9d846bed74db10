"""Deform a rigged character into a pose: stage one, then stage two (thesis 3.4).

A :class:`Deformer` is built once per character and settings (it holds the needle model and
stage two's factorisation); :meth:`Deformer.deform` then runs per pose or frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.deform.joint_area import joint_anchors, joint_area, joint_radii
from toonmotion.deform.joint_solve import EDGE_TERMS, JointSolver
from toonmotion.deform.needles import needle_model, stage_one, stretch_maps, triangle_shapes
from toonmotion.deform.skinning import heat_weights, skinned_needles, skinned_stage_one
from toonmotion.deform.solve_result import SolveResult
from toonmotion.deform.unfold import PASSES, PATCH_RINGS, rings_round, topology, untangle
from toonmotion.errors import SettingsError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.rig.character import Character
from toonmotion.rig.pose import Pose, check_pose

SKINNINGS = ("one-bone", "weights")

# Widened joint-area solvers a Deformer keeps (each a factorisation of a few hundred vertices, 2.4 MB
# for 666 free of char2's 1,504): the benchmark's sequence widens through 10-20 of them, and a cache
# of 8 refactorised them on every pass.
_UNFOLD_SOLVERS = 32


@dataclass(frozen=True)
class DeformSettings:
    """How a pose deforms the drawing.

    Attributes
    ----------
    preserve_area : bool
        Needles shorten as their bone stretches (fig. 3.8), keeping the figure's area.
    weights : tuple of 3 floats
        Stage two's ``w1, w2, w3`` (RSI Laplacian, mean value, edge length), normalised.
    joint_width : float
        How far around each joint stage two works, in multiples of the figure's half-thickness
        there; 0 keeps to the thesis' band of joint triangles (see ``joint_area``).
    max_iterations : int
        Gauss-Newton iterations at most; the thesis reports about 35 on average.
    tolerance : float
        Stop iterating when an iteration lowers the energy by less than this fraction.
    stage_two : bool
        Run stage two at all (off shows the needle model alone, as in fig. 3.9e).
    skinning : str
        ``"one-bone"``: every vertex follows its own bone's needle (the thesis); ``"weights"``:
        it follows a few bones' needles blended by heat-diffusion weights
        (:mod:`toonmotion.deform.skinning`, the thesis' future work 7.2 item 3).
    unfold : int
        Times stage two may widen its joint area where a triangle is left inverted or crushed
        below a fifth of its rest area (two rings of triangles round each, then solved again from
        the result; a frame deformed after another starts from the other's widened area); what is
        still inverted after that is untangled locally (:mod:`toonmotion.deform.unfold`), and a
        joint anchor gives way where a triangle stays inverted (``joint_anchor``). 0 keeps to one
        solve, untangles nothing and holds every anchor.
    acceleration : int
        Stage two's Anderson acceleration: each local-global step mixed with this many before it
        (:meth:`~toonmotion.deform.joint_solve.JointSolver.solve`); the same minimum in fewer
        iterations (docs/posing.md). 0: the plain iterations.
    compiled : bool
        Run stage two's iterations compiled with Numba (:mod:`toonmotion.deform.kernels`): the
        same results, 1.3-1.8x faster frames, but a process pays about 1.6 s once to load Numba
        and the compiled code, more than a short command saves. The editor turns it on; commands
        leave it off.
    edge_term : str
        ``"rigid"``: each joint triangle's edges keep their lengths *and* their orientation
        (the edges of a triangle turn together), so triangles do not flip; ``"length"``: the
        thesis' edge-length term (eq. 3.7), which cannot tell a triangle from its mirror image.
    joint_anchor : float
        How firmly stage two holds the point of the drawing at each joint where the skeleton
        puts it (``w4`` of :class:`~toonmotion.deform.joint_area.Anchors`, against eq. 3.8's
        weights summing to 1); 0 is the thesis, which let the drawn knees of the bundled
        character's crouch settle 20-24 px from the skeleton's. Where holding the joints leaves a
        triangle inverted that a solve holding none does not, the anchors give way a step at a
        time (``anchor_give`` and ``anchor_give_steps``), nearest the fold first (with ``unfold``
        > 0).

    The unfolding loop's tuning (docs/tuning.md gives each its measurement):

    crushed : float
        A fraction of a triangle's rest area, 0 to 1: stage two widens its joint area round a
        triangle left with no more than this (folded, or crushed into a spike on the way to
        folding; an armpit's). 0 widens round inverted triangles only.
    unfold_cell : float
        Mesh spacings, > 0: the joint area widens by whole square cells this wide (those holding a
        crushed triangle or the rings round it), so an animation widens it in a few coarse steps
        and reuses one factorisation. Larger cells widen more at once.
    unfold_rings : int
        Rings of triangles round a crushed one whose cells are taken too, >= 0.
    anchor_give : float
        0 to 1: an anchor that folds the drawing has its hold multiplied by this, a step at a time
        (0: let go at once, as the thesis lets every joint settle).
    anchor_give_steps : int
        Steps of ``anchor_give`` before an anchor is let go, >= 0.
    untangle_passes : int
        Passes of local untangling over the triangles still inverted after unfolding, >= 0
        (:func:`~toonmotion.deform.unfold.untangle`).
    untangle_rings : int
        The largest patch untangling's last resort lays out again (Tutte's method), in rings round
        an inverted triangle, >= 0.

    Construction raises :class:`SettingsError` for a value out of range.
    """

    preserve_area: bool = True
    weights: tuple[float, ...] = (1.0, 1.0, 1.0)
    joint_width: float = 1.5
    max_iterations: int = 100
    tolerance: float = 1e-4
    stage_two: bool = True
    edge_term: str = "rigid"
    unfold: int = 3
    skinning: str = "one-bone"
    joint_anchor: float = 10.0
    acceleration: int = 5
    compiled: bool = False
    crushed: float = 0.2
    unfold_cell: float = 4.0
    unfold_rings: int = 2
    anchor_give: float = 0.25
    anchor_give_steps: int = 3
    untangle_passes: int = PASSES
    untangle_rings: int = PATCH_RINGS

    def __post_init__(self) -> None:
        for name in ("preserve_area", "stage_two", "compiled"):
            if not isinstance(getattr(self, name), bool | np.bool_):
                raise SettingsError(f"{name} must be true or false, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        # The same checks and messages as JointSolver and joint_area, which the settings feed.
        w = np.asarray(self.weights, dtype=float)
        if w.shape != (3,) or not np.all(np.isfinite(w)) or (w < 0).any() or w.sum() <= 0:
            raise SettingsError(
                f"stage-two weights must be three finite numbers >= 0, not all zero; got {w.tolist()}"
            )
        object.__setattr__(self, "weights", (float(w[0]), float(w[1]), float(w[2])))
        width = self.joint_width
        if not (np.isfinite(width) and width >= 0):
            raise SettingsError(f"the joint area width must be a finite number >= 0, got {width}")
        object.__setattr__(self, "joint_width", float(width))
        if self.edge_term not in EDGE_TERMS:
            raise SettingsError(
                f"the edge term must be one of {', '.join(EDGE_TERMS)}, got {self.edge_term!r}"
            )
        if isinstance(self.max_iterations, bool) or not (
            isinstance(self.max_iterations, int) and self.max_iterations >= 1
        ):
            raise SettingsError(f"max_iterations must be a whole number >= 1, got {self.max_iterations!r}")
        if self.skinning not in SKINNINGS:
            raise SettingsError(f"skinning must be one of {', '.join(SKINNINGS)}, got {self.skinning!r}")
        anchor = self.joint_anchor
        if isinstance(anchor, bool) or not (isinstance(anchor, int | float) and np.isfinite(anchor)
                                            and anchor >= 0):
            raise SettingsError(f"the joint anchor weight must be a finite number >= 0, got {anchor!r}")
        object.__setattr__(self, "joint_anchor", float(anchor))
        if isinstance(self.unfold, bool) or not (isinstance(self.unfold, int) and self.unfold >= 0):
            raise SettingsError(f"unfold must be a whole number >= 0, got {self.unfold!r}")
        if isinstance(self.acceleration, bool) or not (isinstance(self.acceleration, int)
                                                       and self.acceleration >= 0):
            raise SettingsError(f"acceleration must be a whole number >= 0, got {self.acceleration!r}")
        if not (isinstance(self.tolerance, (int, float)) and np.isfinite(self.tolerance)
                and self.tolerance > 0):
            raise SettingsError(f"the stage-two tolerance must be a number > 0, got {self.tolerance!r}")
        for name in ("unfold_rings", "anchor_give_steps", "untangle_passes", "untangle_rings"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, int) and value >= 0):
                raise SettingsError(f"{name} must be a whole number >= 0, got {value!r}")
        for name, low, high in (("crushed", 0.0, 1.0), ("anchor_give", 0.0, 1.0)):
            _number_in(self, name, low, high)
        _number_in(self, "unfold_cell", 0.0, np.inf, low_open=True)


def _number_in(settings: DeformSettings, name: str, low: float, high: float, *,
               low_open: bool = False) -> None:
    """Refuse ``settings.name`` unless a finite number from ``low`` to ``high`` (above ``low`` when
    ``low_open``); keep it as a float."""
    value = getattr(settings, name)
    ok = (not isinstance(value, bool) and isinstance(value, int | float) and np.isfinite(value)
          and (value > low if low_open else value >= low) and value <= high)
    if not ok:
        bound = f"> {low:g}" if low_open and high == np.inf else f"from {low:g} to {high:g}"
        raise SettingsError(f"{name} must be a finite number {bound}, got {value!r}")
    object.__setattr__(settings, name, float(value))


@dataclass(frozen=True, eq=False)
class Deformation(SolveResult):
    """A deformed mesh and how it was reached: stage two's :class:`SolveResult` plus stage one.

    Attributes
    ----------
    U, iterations, energy_start, energy, converged
        As for :class:`SolveResult`; ``iterations`` is 0 when stage two is off.
    stage_one : (n, 2) float
        The needle model's result, before stage two.
    free : (n,) bool or None
        The vertices stage two moved: the deformer's joint area, widened where it unfolded
        triangles (None when not given).

    Construction copies ``U`` and ``stage_one`` (read-only) and raises ``ValueError`` unless
    they are ``(n, 2)`` alike and the figures are numbers (an iteration count >= 0).
    """

    stage_one: NDArray[np.float64]
    free: NDArray[np.bool_] | None = None
    _what = "a deformation"

    def __post_init__(self) -> None:
        super().__post_init__()
        stage = frozen_array(self.stage_one, dtype=np.float64, shape=self.U.shape,
                             name=f"{self._what}'s stage_one")
        object.__setattr__(self, "stage_one", stage)
        if self.free is not None:
            object.__setattr__(self, "free", frozen_array(self.free, dtype=np.bool_, shape=(len(self.U),),
                                                          name=f"{self._what}'s free"))


class Deformer:
    """Everything precomputed to deform one character; build once, call :meth:`deform` per frame.

    Attributes
    ----------
    character : Character
    settings : DeformSettings
    needles : NeedleModel
    skin : SkinnedNeedles or None
        The blended needles with ``skinning="weights"``, else None.
    free : (n,) bool
        The joint-area vertices stage two moves.
    anchors : Anchors
        The skeleton's joints drawn inside the figure, which stage two holds at the joints.
    joint_width_px : (b,) float
        Each bone's joint width: how far round the joints at its ends stage two frees vertices
        (:func:`~toonmotion.deform.joint_area.joint_radii`, the larger end), at least the mesh
        spacing.
    solver : JointSolver
    """

    def __init__(self, character: Character, settings: DeformSettings | None = None) -> None:
        self.character = character
        self.settings = settings = settings or DeformSettings()
        mesh = character.mesh
        self.needles = needle_model(mesh.V, character.skeleton, character.binding.bone)
        self.skin = None if settings.skinning == "one-bone" else skinned_needles(
            mesh.V, character.skeleton, heat_weights(mesh, character.skeleton, character.binding.bone))
        radius = joint_radii(character.skeleton, character.mask, width=settings.joint_width,
                             floor=mesh.spacing)
        self.free = joint_area(mesh, character.skeleton, character.binding, character.mask,
                               width=settings.joint_width, radius=radius)
        ends = radius[character.skeleton.bones]
        self.joint_width_px = np.maximum(ends.max(axis=1), mesh.spacing)
        self.anchors = joint_anchors(mesh, character.skeleton.positions, settings.joint_anchor)
        self.solver = JointSolver(mesh, self.free, weights=settings.weights, edge_term=settings.edge_term,
                                  anchors=self.anchors, compiled=settings.compiled)
        self._rest_triangle_areas = triangle_areas(mesh.V, mesh.F)
        self._rest_area = float(self._rest_triangle_areas.sum())
        self._F = np.asarray(mesh.F)
        self._unfold_solvers: dict[bytes, JointSolver] = {}
        self._topology: tuple | None = None  # for untangling, built when first needed
        cell = np.floor((mesh.V - mesh.V.min(axis=0)) / (settings.unfold_cell * mesh.spacing))
        cell = cell.astype(np.int64)
        self._cell = cell[:, 0] * (cell[:, 1].max() + 1) + cell[:, 1]

    def drawn_joints(self, U: NDArray[np.float64]) -> NDArray[np.float64]:
        """Where the drawing deformed to ``U`` (``(n, 2)``) carries each of the skeleton's joints:
        ``(k, 2)``, the point of the drawing at the joint in the rest pose, NaN for a joint drawn
        outside the figure. Compare with the pose's joints to see how closely the drawing follows
        its skeleton."""
        out = np.full((len(self.character.skeleton.names), 2), np.nan)
        a = self.anchors
        out[a.points] = np.einsum("ij,ijk->ik", a.barycentric, np.asarray(U, dtype=float)[a.corners])
        return out

    def stage_one(self, pose: Pose) -> NDArray[np.float64]:
        """The needle model alone for ``pose``: ``(n, 2)``."""
        check_pose(self.character.skeleton, pose)
        if self.skin is not None:
            return skinned_stage_one(self.skin, pose.positions, preserve_area=self.settings.preserve_area)
        return stage_one(self.needles, pose.positions, preserve_area=self.settings.preserve_area)

    def shape(self, pose: Pose) -> NDArray[np.complex128]:
        """The shape stage two asks of each joint triangle in ``pose``: its bones' stretch
        (:func:`~toonmotion.deform.needles.triangle_shapes`), for :meth:`JointSolver.solve`."""
        check_pose(self.character.skeleton, pose)
        maps = stretch_maps(self.needles, pose.positions, preserve_area=self.settings.preserve_area)
        return self._shape_for(self.solver, maps)

    def deform(self, pose: Pose, *, previous: Deformation | None = None) -> Deformation:
        """Deform the character into ``pose``.

        Parameters
        ----------
        pose : Pose
        previous : Deformation, optional
            The previous frame's result; stage two then starts from its displacement carried
            onto this frame (used only when that start is better than stage one's).
        """
        U1 = self.stage_one(pose)
        s = self.settings
        maps = stretch_maps(self.needles, pose.positions, preserve_area=s.preserve_area)
        shape = self._shape_for(self.solver, maps)
        if not s.stage_two:
            energy = self.solver.energy(U1, shape=shape)
            return Deformation(U=U1, stage_one=U1, iterations=0, energy_start=energy,
                               energy=energy, converged=True)
        initial = None if previous is None else U1 + (previous.U - previous.stage_one)
        area = self._rest_area if s.preserve_area else None
        # An animation keeps the joint area the previous frame widened: it folds in the same
        # places frame after frame, and one widened solve costs less than a plain one and another.
        free = previous.free if previous is not None and previous.free is not None and s.unfold \
            else self.free
        held = np.ones(len(self.anchors.points))  # how firmly each anchor is held
        iterations, start = 0, None
        while True:
            U, free, result, solver, folded, spent = self._solve(U1, maps, shape, area, free, initial, held)
            iterations += spent
            if start is None:  # eq. 3.8 at the start; the anchors' term is 0 there
                start = result.energy_start if solver is self.solver else self.solver.energy(U1, shape=shape)
            if not (s.unfold and folded.any() and self.solver.anchors is not None and (held > 0).any()):
                break
            if (held == 1).all():  # whether the anchors fold it: the solve holding none tells
                loose = self._solve(U1, maps, shape, area, free, initial, np.zeros_like(held))
                iterations += loose[-1]
                if loose[4].any():
                    break  # it folds without them too: they are kept
            # Holding a joint there folds the drawing: the anchor nearest the fold gives way a
            # step, and the next solve starts from this one's result (it moves the joint little).
            k = self._nearest_anchor(folded, held)
            held[k] = held[k] * s.anchor_give if held[k] > s.anchor_give ** s.anchor_give_steps else 0.0
            initial = U
        # Energies are eq. 3.8 (plus the anchors held) over the deformer's own joint area, whichever
        # solve ran (the start: the plain solve's, warm or not, or stage one's when the first solve
        # was a widened one).
        plain = solver is self.solver and U is result.U
        energy = result.energy if plain else self.solver.energy(U, shape=shape, stage_one=U1, held=held)
        return Deformation(U=U, stage_one=U1, iterations=iterations, energy_start=start,
                           energy=energy, converged=result.converged, free=free)

    def _solve(self, U1, maps, shape, area, free, initial, held):
        """Stage two from stage one ``U1`` over joint area ``free``, with the anchors ``held``:
        widened where it folds, up to ``unfold`` times, then untangled. Returns the vertices, the
        joint area, the last solve's result and solver, which triangles are still folded, and the
        iterations."""
        s, iterations = self.settings, 0
        for round_ in range(s.unfold + 1):
            solver = self._solver_for(free)
            result = solver.solve(U1, initial=initial, max_iterations=s.max_iterations, tolerance=s.tolerance,
                                  shape=shape if solver is self.solver else self._shape_for(solver, maps),
                                  area=area, acceleration=s.acceleration, held=held)
            U, iterations = result.U, iterations + result.iterations
            areas = triangle_areas(U, self._F)
            crushed = areas <= s.crushed * self._rest_triangle_areas
            if round_ == s.unfold or not crushed.any():
                break
            wider = free | self._cells_round(crushed)
            if not (wider != free).any():
                break
            free, initial = wider, U
        folded = areas <= 0
        if s.unfold and folded.any():
            if self._topology is None:
                self._topology = topology(self._F, len(U))
            U = untangle(U, self._F, free, self._topology, passes=s.untangle_passes,
                         patch_rings=s.untangle_rings)
            folded = triangle_areas(U, self._F) <= 0
        return U, free, result, solver, folded, iterations

    def _nearest_anchor(self, folded, held):
        """The held anchor whose joint lies nearest a ``folded`` triangle, at rest."""
        a = self.anchors
        centres = self.character.mesh.V[self._F[folded]].mean(axis=1)
        joints = self.character.skeleton.positions[a.points]
        gap = np.hypot(*(centres[:, None] - joints[None]).transpose(2, 0, 1)).min(axis=0)
        return int(np.argmin(np.where(held > 0, gap, np.inf)))

    def _cells_round(self, crushed):
        """Every vertex in a cell of ``unfold_cell`` mesh spacings that holds a vertex of a
        ``crushed`` triangle (or of the ``unfold_rings`` rings of triangles round it): widening by
        whole cells changes the joint area in a few coarse steps, so an animation soon stops
        widening it and reuses one factorisation."""
        near = rings_round(self._F, crushed, len(self.free), self.settings.unfold_rings)
        return np.isin(self._cell, np.unique(self._cell[near]))

    def _solver_for(self, free):
        """A JointSolver for the joint area ``free``, widened or not (anchors let go are taken
        out of its solves, not of its factorisation); the last few others than the deformer's own
        are kept."""
        if not (free != self.free).any():
            return self.solver
        key = np.packbits(free).tobytes()
        if key not in self._unfold_solvers:
            if len(self._unfold_solvers) >= _UNFOLD_SOLVERS:
                self._unfold_solvers.pop(next(iter(self._unfold_solvers)))
            self._unfold_solvers[key] = JointSolver(self.character.mesh, free, weights=self.settings.weights,
                                                    edge_term=self.settings.edge_term, anchors=self.anchors,
                                                    compiled=self.settings.compiled)
        return self._unfold_solvers[key]

    def _shape_for(self, solver, maps):
        """Each of ``solver``'s triangles' shape from the bones' stretch ``maps``."""
        return triangle_shapes(maps, self.needles.bone, solver.triangles,
                               keep_area=self.settings.preserve_area)
