"""Deformation on the extreme pose set, the stretches and the single-frame filter (issue 16).

Poses come from the skeleton's structure (:mod:`toonmotion.testing.poses`): each bend joint bent
150 degrees above the root and 120 below, both ways; chains raised overhead; the upper body
turned 40 degrees against the lower; every bone stretched 1.5x; the filter's jump. On the bundled
character and every shared drawing: no triangle inverted after stage two, and the figure's area
within 2% of the drawing's.
"""

import numpy as np
import pytest

from tests.conftest import drawing_names
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.testing.poses import extreme_poses, filter_jump, stretch_poses

CHARACTERS = ["sample", *drawing_names()]
AREA_TOLERANCE = 0.02


@pytest.fixture(scope="module", params=CHARACTERS)
def named(request, rigs):
    """``(name, Deformer)`` of each character."""
    return request.param, rigs.deformer(request.param)


def _area_change(deformer, pose):
    mesh = deformer.character.mesh
    U = deformer.deform(pose).U
    return float(triangle_areas(U, mesh.F).sum() / triangle_areas(mesh.V, mesh.F).sum() - 1)


def _inverted(deformer, pose):
    return int((triangle_areas(deformer.deform(pose).U, deformer.character.mesh.F) <= 0).sum())


def test_no_triangle_is_inverted_in_any_extreme_pose(named):
    _, deformer = named
    inverted = {label: count for label, pose in extreme_poses(deformer.character.skeleton)
                if (count := _inverted(deformer, pose))}
    assert not inverted, f"inverted triangles after stage two: {inverted}"


def test_extreme_poses_keep_the_figures_area(named):
    _, deformer = named
    poses = extreme_poses(deformer.character.skeleton)
    changes = {label: _area_change(deformer, pose) for label, pose in poses}
    worst = max(changes, key=lambda k: abs(changes[k]))
    print(f"\nworst: {worst} {changes[worst]:+.3%}")
    assert abs(changes[worst]) <= AREA_TOLERANCE


def test_every_stretched_bone_and_the_filters_jump_keep_the_figures_area(named):
    _, deformer = named
    cases = [*stretch_poses(deformer.character.skeleton), ("filter jump", filter_jump(deformer.character))]
    changes = {label: _area_change(deformer, pose) for label, pose in cases}
    worst = max(changes, key=lambda k: abs(changes[k]))
    print(f"\nworst: {worst} {changes[worst]:+.3%}")
    assert abs(changes[worst]) <= AREA_TOLERANCE


def test_without_area_preservation_nothing_holds_the_area(rigs):
    """The constraint is part of area preservation: switched off, a stretched torso grows the
    figure as the needles do."""
    deformer = rigs.deformer("sample", preserve_area=False)
    torso = dict(stretch_poses(deformer.character.skeleton))["torso x1.5"]
    assert _area_change(deformer, torso) > 0.05


def test_unfolding_off_leaves_the_single_solve(rigs):
    """``unfold=0`` is the plain stage two: its joint area, no untangling."""
    deformer = rigs.deformer("sample", unfold=0)
    for _, pose in extreme_poses(deformer.character.skeleton)[:6]:
        result = deformer.deform(pose)
        np.testing.assert_array_equal(result.free, deformer.free)
