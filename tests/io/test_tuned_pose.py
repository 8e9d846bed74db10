"""Tests for toonmotion.io.tuned_pose: a pose, or one key, with its fine-tuning edits."""

import numpy as np
import pytest

from toonmotion.deform.tuning import CurveEdit, DragEdit
from toonmotion.errors import EditError, SettingsError
from toonmotion.io.pose_json import load_keyframes, load_pose_edits, save_keyframes, save_pose
from toonmotion.io.tuned_pose import load_tuned_pose, save_tuned_pose, with_edits, without_last_edit
from toonmotion.rig.pose import rest_pose
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character

DRAG = DragEdit(start=np.array([[10.0, 20.0]]), end=np.array([[12.0, 18.0]]))
CURVE = CurveEdit(points=np.array([[0.0, 0.0], [5.0, 1.0], [9.0, 0.0]]))


@pytest.fixture(scope="module")
def skeleton():
    return sample_character()[1]


def test_a_pose_file_round_trips_its_edits(skeleton, tmp_path):
    path = tmp_path / "pose.json"
    save_pose(path, skeleton, rest_pose(skeleton))
    tuned = with_edits(load_tuned_pose(path, skeleton), (DRAG, CURVE))
    save_tuned_pose(tuned, skeleton)
    again = load_tuned_pose(path, skeleton)
    assert again.key is None and again.timeline is None
    np.testing.assert_array_equal(again.pose.positions, skeleton.positions)
    assert len(load_pose_edits(path)) == 2
    np.testing.assert_array_equal(again.edits[0].end, DRAG.end)
    np.testing.assert_array_equal(again.edits[1].points, CURVE.points)


def test_a_key_s_edits_are_written_on_that_key_only(skeleton, tmp_path):
    path = tmp_path / "keys.json"
    timeline = sample_keyframes(skeleton)
    save_keyframes(path, skeleton, timeline)
    frame = timeline.keys[2].frame
    tuned = load_tuned_pose(path, skeleton, key=frame)
    np.testing.assert_array_equal(tuned.pose.positions, timeline.keys[2].pose.positions)
    save_tuned_pose(with_edits(tuned, (DRAG,)), skeleton)
    keys = load_keyframes(path, skeleton).keys
    assert [len(k.edits) for k in keys] == [1 if k.frame == frame else 0 for k in keys]
    for before, after in zip(timeline.keys, keys, strict=True):
        np.testing.assert_array_equal(before.pose.positions, after.pose.positions)


def test_a_missing_key_names_the_keys_there_are(skeleton, tmp_path):
    path = tmp_path / "keys.json"
    save_keyframes(path, skeleton, sample_keyframes(skeleton))
    with pytest.raises(SettingsError, match=r"has no key at frame 5; its keys are at \[0, "):
        load_tuned_pose(path, skeleton, key=5)


def test_taking_back_the_last_edit_returns_it_and_nothing_left_is_an_error(skeleton, tmp_path):
    path = tmp_path / "pose.json"
    save_pose(path, skeleton, rest_pose(skeleton), (DRAG, CURVE))
    tuned, taken = without_last_edit(load_tuned_pose(path, skeleton))
    assert isinstance(taken, CurveEdit) and len(tuned.edits) == 1
    tuned, taken = without_last_edit(tuned)
    assert isinstance(taken, DragEdit) and tuned.edits == ()
    with pytest.raises(EditError, match="has no edits to undo"):
        without_last_edit(tuned)
