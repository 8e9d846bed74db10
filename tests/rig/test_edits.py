"""Tests for toonmotion.rig.edits: the correction and depth history, undo, redo, replay."""

import numpy as np
import pytest

from toonmotion.errors import EditError, SettingsError
from toonmotion.rig.binding import Correction
from toonmotion.rig.character import RigSettings
from toonmotion.rig.edits import DepthEdit, apply_edit, describe, redo, replay, undo, without_edits
from toonmotion.rig.pipeline import remesh, rig_drawing
from toonmotion.samples import sample_character

# A box round the sample's right hand and the end of its forearm, given to the hand.
HAND_BOX = np.array([[40.0, 200.0], [120.0, 200.0], [120.0, 300.0], [40.0, 300.0]])


@pytest.fixture(scope="module")
def character():
    rgba, skeleton = sample_character()
    return rig_drawing(rgba, skeleton=skeleton)


def _inside(V, box):
    (x0, y0), (x1, y1) = box.min(axis=0), box.max(axis=0)
    return (V[:, 0] > x0) & (V[:, 0] < x1) & (V[:, 1] > y0) & (V[:, 1] < y1)


@pytest.fixture(scope="module")
def edited(character):
    ch = apply_edit(character, Correction(curve=HAND_BOX, bone="right_hand"))
    ch = apply_edit(ch, DepthEdit(value=2, bone="right_elbow"))
    return apply_edit(ch, DepthEdit(value=-1, at=tuple(character.skeleton.positions[-1])))


def test_a_correction_attaches_the_enclosed_vertices(character, edited):
    hand = character.skeleton.bone_names.index("right_hand")
    inside = _inside(edited.mesh.V, HAND_BOX)
    assert inside.sum() > 5
    assert (edited.binding.bone[inside] == hand).all()
    assert (character.binding.bone[inside] != hand).any(), "the box should change something"
    assert len(edited.edits) == 3 and edited.undone == ()


def test_depth_edits_set_a_region_by_name_or_point(character, edited):
    names = character.skeleton.bone_names
    assert edited.depth[names.index("right_elbow")] == 2
    # The region of the rest vertex nearest the left foot's joint.
    foot = character.skeleton.positions[-1]
    foot_region = int(edited.binding.bone[np.argmin(np.hypot(*(edited.mesh.V - foot).T))])
    assert edited.depth[foot_region] == -1
    assert np.count_nonzero(edited.depth) == 2


def test_undo_rebuilds_exactly_the_earlier_state(character, edited):
    one, taken = undo(edited)
    assert [describe(e) for e in taken] == [describe(edited.edits[-1])]
    assert one.edits == edited.edits[:2]
    assert np.count_nonzero(one.depth) == 1
    np.testing.assert_array_equal(one.binding.bone, edited.binding.bone)
    none, _ = undo(edited, 3)
    np.testing.assert_array_equal(none.binding.bone, character.binding.bone)
    np.testing.assert_array_equal(none.binding.joint_area, character.binding.joint_area)
    assert not none.depth.any() and none.edits == () and none.binding.corrections == ()


def test_redo_brings_back_undone_edits_in_order(edited):
    none, _ = undo(edited, 3)
    assert len(none.undone) == 3
    again, redone = redo(none, 2)
    assert redone == edited.edits[:2]
    np.testing.assert_array_equal(again.binding.bone, undo(edited)[0].binding.bone)
    full, _ = redo(again)
    np.testing.assert_array_equal(full.depth, edited.depth)
    np.testing.assert_array_equal(full.binding.bone, edited.binding.bone)
    assert full.undone == ()


def test_a_new_edit_clears_redo(edited):
    one, _ = undo(edited)
    assert len(one.undone) == 1
    assert apply_edit(one, DepthEdit(value=5, bone="head")).undone == ()


def test_nothing_to_undo_or_redo(character, edited):
    with pytest.raises(EditError, match="no edits to undo"):
        undo(character)
    with pytest.raises(EditError, match="only 3 edits to undo"):
        undo(edited, 4)
    with pytest.raises(EditError, match="nothing to redo"):
        redo(edited)
    with pytest.raises(SettingsError, match="steps >= 1"):
        undo(edited, 0)


def test_edits_replay_on_a_new_mesh(edited):
    """Edits are kept in drawing pixels and bone names, so they survive re-meshing."""
    coarse, skipped = remesh(edited, RigSettings(vertices=600))
    assert skipped == []
    assert abs(len(coarse.mesh.V) - len(edited.mesh.V)) > 300
    hand = coarse.skeleton.bone_names.index("right_hand")
    assert (coarse.binding.bone[_inside(coarse.mesh.V, HAND_BOX)] == hand).all()
    np.testing.assert_array_equal(coarse.depth, edited.depth)
    assert len(coarse.edits) == 3


def test_replay_skips_edits_that_no_longer_apply(character):
    edits = (DepthEdit(value=1, bone="tail"), DepthEdit(value=3, bone="head"))
    replayed, skipped = replay(character, edits)
    assert [e for e, _ in skipped] == [edits[0]]
    assert "no bone is called 'tail'" in skipped[0][1]
    assert replayed.edits == edits[1:]


def test_without_edits_is_the_automatic_rig(character, edited):
    bare = without_edits(edited)
    np.testing.assert_array_equal(bare.binding.bone, character.binding.bone)
    assert bare.edits == () and not bare.depth.any()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"value": 1}, "exactly one of them"),
        ({"value": 1, "bone": "head", "at": (1, 2)}, "exactly one of them"),
        ({"value": 1.5, "bone": "head"}, "whole number"),
        ({"value": True, "bone": "head"}, "whole number"),
        ({"value": 1, "at": (np.nan, 2)}, "point has a non-finite position"),
        ({"value": 1, "at": (1, 2, 3)}, "give two numbers"),
        ({"value": 1, "at": (2e7, 2)}, "over 10,000,000 px from the origin"),
    ],
)
def test_malformed_depth_edits(kwargs, message):
    with pytest.raises(EditError, match=message):
        DepthEdit(**kwargs)


def test_an_edit_that_would_change_nothing_or_lies_off_the_drawing_is_refused(character, edited):
    """A lasso round no vertex, a lasso giving vertices to the bone they are on already, and a
    depth picked far off the drawing: each an EditError, and no edit recorded."""
    far = character.mesh.V.max(axis=0) + 500
    with pytest.raises(EditError, match="holds no vertex"):
        apply_edit(edited, Correction(curve=np.array([far, far + (5, 0), far + (0, 5)]), bone="head"))
    with pytest.raises(EditError, match="attached to right_hand already"):
        apply_edit(edited, Correction(curve=HAND_BOX, bone="right_hand"))
    with pytest.raises(EditError, match="no part of the drawing"):
        apply_edit(edited, DepthEdit(value=1, at=tuple(far)))
    assert len(edited.edits) == 3
