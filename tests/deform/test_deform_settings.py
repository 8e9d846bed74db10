"""The unfolding loop's tuning is DeformSettings, not module constants (issue 47): each setting
changes what docs/tuning.md says it changes, measured over the bundled character's extreme poses
(:func:`toonmotion.testing.poses.extreme_poses`, deformed in order by one Deformer)."""

import functools

import numpy as np
import pytest

from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.errors import SettingsError
from toonmotion.geometry.polygon import triangle_areas
from toonmotion.samples import sample_rig
from toonmotion.testing.poses import extreme_poses


@functools.cache
def _over_the_poses(**settings):
    """``(vertices the joint areas widened by, summed; triangles left inverted)`` over the poses."""
    hero = sample_rig()
    deformer = Deformer(hero, DeformSettings(**settings))
    widened = inverted = 0
    for _, pose in extreme_poses(hero.skeleton):
        result = deformer.deform(pose)
        widened += int(result.free.sum() - deformer.free.sum())
        inverted += int((triangle_areas(result.U, hero.mesh.F) <= 0).sum())
    return widened, inverted


def test_the_defaults_widen_some_joint_areas_and_leave_nothing_inverted():
    widened, inverted = _over_the_poses()
    assert widened > 0 and inverted == 0


def test_a_larger_crushed_fraction_widens_round_more_triangles():
    """0 widens round inverted triangles only; 0.6 round every triangle squeezed to 60 %."""
    assert _over_the_poses(crushed=0.0)[0] < _over_the_poses()[0] < _over_the_poses(crushed=0.6)[0]


def test_larger_cells_widen_more_at_once():
    assert _over_the_poses(unfold_cell=2.0)[0] < _over_the_poses()[0] < _over_the_poses(unfold_cell=8.0)[0]


def test_fewer_rings_round_a_crushed_triangle_widen_less():
    assert _over_the_poses(unfold_rings=0)[0] < _over_the_poses()[0]


def test_without_untangling_folds_are_left():
    """Untangling mends what unfolding leaves: with no pass and no patch, triangles stay inverted."""
    assert _over_the_poses(untangle_passes=0, untangle_rings=0)[1] > 0 == _over_the_poses()[1]


@pytest.mark.parametrize("settings, message", [
    (dict(crushed=1.5), "crushed must be a finite number from 0 to 1, got 1.5"),
    (dict(crushed=float("nan")), "crushed must be a finite number from 0 to 1"),
    (dict(anchor_give=-0.1), "anchor_give must be a finite number from 0 to 1"),
    (dict(unfold_cell=0.0), "unfold_cell must be a finite number > 0, got 0.0"),
    (dict(unfold_rings=-1), "unfold_rings must be a whole number >= 0, got -1"),
    (dict(anchor_give_steps=1.5), "anchor_give_steps must be a whole number >= 0"),
    (dict(untangle_passes=True), "untangle_passes must be a whole number >= 0, got True"),
])
def test_a_tuning_value_out_of_range_is_refused_in_one_line(settings, message):
    with pytest.raises(SettingsError, match=message.replace("(", r"\(").replace(")", r"\)")):
        DeformSettings(**settings)


def test_the_untangler_takes_its_passes_and_rings():
    """A square of two triangles with a corner pushed across the diagonal: mended by default, left
    as it is with no pass and no patch (:func:`toonmotion.deform.unfold.untangle`)."""
    from toonmotion.deform.unfold import untangle

    U = np.array([[0.0, 0.0], [0.0, 2.0], [2.0, 2.0], [0.5, 1.5]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    movable = np.array([False, False, False, True])
    assert (triangle_areas(untangle(U, F, movable), F) > 0).all()
    np.testing.assert_array_equal(untangle(U, F, movable, passes=0, patch_rings=0), U)
