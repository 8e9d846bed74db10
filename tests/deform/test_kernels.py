"""Tests for toonmotion.deform.kernels: stage two's compiled loop is the NumPy loop of
``JointSolver.solve``, and Anderson acceleration reaches the same minimum in fewer iterations.

Every case runs on the bundled sample character and each shared drawing, on the key poses the
benchmark animates (bends and raised chains), with the area constraint and the joint anchors.
"""

import numpy as np
import pytest

from toonmotion.deform.needles import stretch_maps
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.testing.poses import key_poses

CHARACTERS = ("sample", "char1", "char2", "char3", "char4")


def _problems(deformer):
    """``(U1, shape, area)`` for each of the skeleton's key poses but rest, for the deformer's solver."""
    character = deformer.character
    area = float(triangle_areas(character.mesh.V, character.mesh.F).sum())
    for pose in key_poses(character.skeleton)[1:-1]:
        maps = stretch_maps(deformer.needles, pose.positions, preserve_area=True)
        yield deformer.stage_one(pose), deformer._shape_for(deformer.solver, maps), area


def _numpy(solver, *args, **kwargs):
    """``solver.solve`` through the NumPy loop."""
    compiled, solver._compiled = solver._compiled, None
    try:
        return solver.solve(*args, **kwargs)
    finally:
        solver._compiled = compiled


@pytest.mark.parametrize("name", CHARACTERS)
@pytest.mark.parametrize("acceleration", [0, 5])
def test_the_compiled_loop_is_the_numpy_loop(rigs, name, acceleration):
    deformer = rigs.deformer(name, compiled=True)
    solver = deformer.solver
    assert solver._compiled is not None  # the rigid edge term runs compiled
    for U1, shape, area in _problems(deformer):
        options = dict(shape=shape, area=area, max_iterations=60, tolerance=1e-4, acceleration=acceleration)
        compiled, reference = solver.solve(U1, **options), _numpy(solver, U1, **options)
        assert compiled.iterations == reference.iterations
        assert compiled.energy == pytest.approx(reference.energy, rel=1e-9)
        assert np.abs(compiled.U - reference.U).max() < 1e-6


@pytest.mark.parametrize("name", CHARACTERS)
def test_acceleration_reaches_the_same_minimum_in_fewer_iterations(rigs, name):
    """Iterated to convergence, the plain and the accelerated loops end at one energy (the same
    minimum), the accelerated one in at most two thirds of the iterations summed over the poses
    (measured: 0.32-0.61 of them)."""
    deformer = rigs.deformer(name, compiled=True)
    plain_iterations = mixed_iterations = 0
    for U1, shape, area in _problems(deformer):
        options = dict(shape=shape, area=area, max_iterations=20000, tolerance=1e-11)
        plain = deformer.solver.solve(U1, acceleration=0, **options)
        mixed = deformer.solver.solve(U1, acceleration=5, **options)
        assert plain.converged and mixed.converged
        assert mixed.energy == pytest.approx(plain.energy, rel=1e-6)
        assert mixed.energy <= mixed.energy_start
        plain_iterations += plain.iterations
        mixed_iterations += mixed.iterations
    print(f"\n{name}: {plain_iterations} plain iterations, {mixed_iterations} accelerated")
    assert mixed_iterations <= 2 * plain_iterations / 3


@pytest.mark.parametrize("name", CHARACTERS)
@pytest.mark.parametrize("compiled", [False, True])
def test_anchors_let_go_in_a_solve_are_a_solver_built_without_them(rigs, name, compiled):
    """A solve holding some anchors (the factorisation keeps them all; the others are taken out by
    the Woodbury identity) ends where a solver factorised without those anchors ends, with the
    same energy and iterations: every other anchor held, none held, and every anchor held by a
    sixteenth (a solver factorised with a sixteenth of the weight)."""
    from toonmotion.deform.joint_area import Anchors
    from toonmotion.deform.joint_solve import JointSolver

    deformer = rigs.deformer(name, compiled=compiled)
    solver, anchors = deformer.solver, deformer.anchors
    every = np.ones(len(anchors.points), bool)
    weaker = Anchors(anchors.points, anchors.corners, anchors.barycentric, anchors.weight / 16)
    for held, kept in ((np.arange(len(every)) % 2 == 0, None), (~every, None), (every / 16, weaker)):
        kept = kept if kept is not None else anchors.subset(held)
        alone = JointSolver(deformer.character.mesh, deformer.free, anchors=kept, compiled=compiled)
        for U1, shape, area in _problems(deformer):
            options = dict(shape=shape, area=area, max_iterations=60, tolerance=1e-4, acceleration=5)
            released, reference = solver.solve(U1, held=held, **options), alone.solve(U1, **options)
            assert released.iterations == reference.iterations
            assert released.energy == pytest.approx(reference.energy, rel=1e-9)
            assert np.abs(released.U - reference.U).max() < 1e-6
            assert solver.energy(released.U, shape=shape, stage_one=U1, held=held) == \
                pytest.approx(released.energy, rel=1e-9)
